#include "hapticut/proxy.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>

#include "hapticut/geometry.h"
#include "hapticut/scene_io.h"
#include "test_support.h"

namespace hapticut {
namespace {

using testing::make_space;

constexpr double kDt = 0.001;

std::uint64_t count(const Proxy& proxy, ProxyState from, ProxyState to, bool neighbour) {
  return proxy.counters().transitions[int(from)][int(to)][neighbour ? 1 : 0];
}

Vec3 centroid(const TetMesh& mesh, std::int32_t t) {
  Vec3 c;
  for (std::int32_t v : mesh.tet(t)) c += mesh.vertex(v) * 0.25;
  return c;
}

bool has_boundary_face(const TetMesh& mesh, std::int32_t t) {
  for (int f = 0; f < 4; ++f) {
    if (mesh.neighbour(t, f) == kNoTet) return true;
  }
  return false;
}

// Checked here without check_invariants, so the tests also fail against an
// engine whose check has a blind spot for them.
bool inside_rigid(const Space& space, const Vec3& q) {
  const TetMesh& mesh = space.mesh();
  for (std::int32_t t = 0; t < mesh.tet_count(); ++t) {
    if (space.tet_is_rigid(t) && mesh.outside_distance(t, q) < -100 * space.tolerance())
      return true;
  }
  return false;
}

TEST(Proxy, WalksIntoTheNeighbourThroughTheSharedFace) {
  const auto space_owner = make_space(two_tets_mesh(), 0);
  const Space& space = *space_owner;
  Proxy proxy(space);
  EXPECT_EQ(proxy.reset({2, 2, -1}), StartKind::InsideTet);
  const std::int32_t start_tet = proxy.place().tet;
  const TickResult r = proxy.step({2, 2, 1}, kDt);
  EXPECT_FALSE(r.capped);
  EXPECT_EQ(proxy.place().state, ProxyState::Tet);
  EXPECT_NE(proxy.place().tet, start_tet);
  EXPECT_EQ(proxy.q(), Vec3(2, 2, 1));
  EXPECT_EQ(count(proxy, ProxyState::Tet, ProxyState::Face, false), 1u);
  EXPECT_EQ(count(proxy, ProxyState::Face, ProxyState::Tet, true), 1u);
  EXPECT_EQ(proxy.force_N(), Vec3(0, 0, 0));
}

TEST(Proxy, RigidNeighbourHoldsTheProxyOnTheFaceAndLetsItSlide) {
  const MeshData mesh = two_tets_mesh();
  // Tet 1 (above z = 0) is bone.
  const auto space_owner = make_space(mesh, {0, 2});
  const Space& space = *space_owner;
  Proxy proxy(space);
  proxy.reset({2, 2, -1});
  proxy.step({2, 2, 3}, kDt);
  EXPECT_EQ(proxy.place().state, ProxyState::Face);
  EXPECT_NEAR(proxy.q().z, 0.0, 1e-9);
  EXPECT_NEAR(proxy.q().x, 2.0, 1e-9);
  EXPECT_NEAR(proxy.force_N().z, -0.3, 1e-9);  // k (q - p) with k = 0.1 N/mm.
  proxy.step({3, 2.5, 3}, kDt);                // Slide while pressing.
  EXPECT_EQ(proxy.place().state, ProxyState::Face);
  EXPECT_NEAR(proxy.q().x, 3.0, 1e-9);
  EXPECT_NEAR(proxy.q().y, 2.5, 1e-9);
  EXPECT_NEAR(proxy.q().z, 0.0, 1e-9);
  EXPECT_EQ(proxy.check_invariants(), "");
  proxy.step({3, 2.5, -2}, kDt);  // Pull back into the air.
  EXPECT_EQ(proxy.place().state, ProxyState::Tet);
  EXPECT_EQ(proxy.q(), Vec3(3, 2.5, -2));
}

// A valley: bone fills the bottom layer (z < 10) and, in the middle layer,
// the cells beyond x = 20 and beyond y = 20. Pressed into it, the proxy stops
// on the valley's edge, then in its corner.
TEST(Proxy, SlidesIntoAValleyEdgeThenItsCorner) {
  const MeshData mesh = grid_mesh({0, 10, 20, 30}, {0, 10, 20, 30}, {0, 10, 20, 30});
  std::vector<std::int32_t> m(mesh.tets.size(), 0);
  for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
    Vec3 c;
    for (std::int32_t v : mesh.tets[t]) c += mesh.vertices_mm[v] * 0.25;
    if (c.z < 10 || (c.z < 20 && (c.x > 20 || c.y > 20))) m[t] = 2;
  }
  const auto space_owner = make_space(mesh, m);
  const Space& space = *space_owner;
  Proxy proxy(space);
  proxy.reset({15, 15, 15});
  proxy.step({25, 15, 5}, kDt);
  EXPECT_EQ(proxy.place().state, ProxyState::Edge);
  EXPECT_NEAR(norm(proxy.q() - Vec3(20, 15, 10)), 0.0, 1e-9);
  EXPECT_EQ(proxy.check_invariants(), "");
  proxy.step({25, 25, 5}, kDt);
  EXPECT_EQ(proxy.place().state, ProxyState::Vertex);
  EXPECT_NEAR(norm(proxy.q() - Vec3(20, 20, 10)), 0.0, 1e-9);
  EXPECT_NEAR(norm(proxy.force_N() - Vec3(-0.5, -0.5, 0.5)), 0.0, 1e-9);
  proxy.step({12, 14, 5}, kDt);  // Back up the valley floor: a face again.
  EXPECT_EQ(proxy.place().state, ProxyState::Face);
  EXPECT_NEAR(norm(proxy.q() - Vec3(12, 14, 10)), 0.0, 1e-9);
  EXPECT_EQ(proxy.check_invariants(), "");
}

TEST(Proxy, DragLagsByExactlyD) {
  const auto space_owner =
      make_space(grid_mesh({0, 10, 20, 30}, {0, 10, 20}, {0, 10, 20}, 0.2, 9), 1);
  const Space& space = *space_owner;
  Proxy proxy(space);
  proxy.reset({2, 5, 5});
  for (int i = 1; i <= 250; ++i) {
    proxy.step({2 + 0.1 * i, 5 + 0.02 * i, 5 + 0.01 * i}, kDt);
    if (i > 20) {
      EXPECT_NEAR(norm(proxy.q() - proxy.last_p()), 1.0, 1e-9) << "tick " << i;
    }
    ASSERT_EQ(proxy.check_invariants(), "") << "tick " << i;
  }
  EXPECT_NEAR(norm(proxy.force_N()), 0.1, 1e-10);  // k D.
}

TEST(Proxy, EntersTheCubeFromOutside) {
  const auto space_owner = make_space(cube_mesh(10.0), 0);
  const Space& space = *space_owner;
  Proxy proxy(space);
  EXPECT_EQ(proxy.reset({-5, 3, 4}), StartKind::Outside);
  proxy.step({5, 3, 4}, kDt);
  EXPECT_EQ(proxy.place().state, ProxyState::Tet);
  EXPECT_EQ(proxy.q(), Vec3(5, 3, 4));
  EXPECT_EQ(count(proxy, ProxyState::Outside, ProxyState::Face, false), 1u);
  proxy.step({15, 3, 4}, kDt);  // And out through the far side.
  EXPECT_EQ(proxy.place().state, ProxyState::Outside);
  EXPECT_EQ(proxy.q(), Vec3(15, 3, 4));
}

// OUTSIDE tests every plane q->p enters through, in any order, and keeps the
// nearest clean hit: on random moves into small meshes (the linear scan's,
// up to 32 boundary faces) no boundary triangle is crossed clearly inside it
// before the entry point the proxy lands on, and a move through a triangle's
// inside always enters.
TEST(Proxy, OutsideEntersThroughTheNearestBoundaryTriangle) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  // Two cubes side by side (24 faces): a move can cross several triangles on its way in.
  MeshData two_cubes = cube_mesh(10.0);
  const MeshData second = cube_mesh(10.0);
  const auto offset = static_cast<std::int32_t>(two_cubes.vertices_mm.size());
  for (const Vec3& v : second.vertices_mm) two_cubes.vertices_mm.push_back(v + Vec3{14, 3, -2});
  for (auto tet : second.tets) {
    for (auto& v : tet) v += offset;
    two_cubes.tets.push_back(tet);
  }
  for (const MeshData& data :
       {two_cubes, cube_mesh(10.0), icosahedron_mesh(10.0), edge_fan_mesh(12)}) {
    const auto space = make_space(data, 0);
    const TetMesh& mesh = space->mesh();
    ASSERT_LE(mesh.boundary_faces().size(), 32U);
    Aabb box;
    for (const Vec3& v : data.vertices_mm) box.grow(v);
    const Vec3 centre = (box.lo + box.hi) * 0.5;
    const double size = norm(box.hi - box.lo);
    int entered = 0;
    for (int trial = 0; trial < 3000; ++trial) {
      Vec3 from{unit(rng), unit(rng), unit(rng)};
      from = centre + from * (1.5 * size / norm(from));
      const Vec3 to = centre + Vec3{unit(rng), unit(rng), unit(rng)} * (0.3 * size);
      Proxy proxy(space);
      ASSERT_EQ(proxy.reset(from), StartKind::Outside);
      MoveContext context;
      context.tolerance_mm = space->tolerance();
      proxy.transition(to, context);
      const double found = proxy.place().state == ProxyState::Outside
                               ? 2.0
                               : norm(proxy.q() - from) / norm(to - from);
      // Brute force: the nearest parameter at which from->to crosses a triangle clearly inside.
      double nearest = 2.0;
      for (std::size_t k = 0; k < mesh.boundary_faces().size(); ++k) {
        const Plane& plane = mesh.boundary_plane(k);
        const double d0 = plane.signed_distance(from);
        const double d1 = plane.signed_distance(to);
        if (!(d0 > 0.0 && d1 < 0.0)) continue;
        const double t = d0 / (d0 - d1);
        const Vec3 c = from + (to - from) * t;
        bool inside = true;
        for (int j = 0; j < 3; ++j)
          inside = inside && mesh.boundary_side_planes(k)[j].signed_distance(c) < -1e-6;
        if (inside) nearest = std::min(nearest, t);
      }
      EXPECT_LE(found, nearest + 1e-9) << "trial " << trial << ": entered at " << found
                                       << ", a triangle is crossed at " << nearest;
      entered += found <= 1.0 ? 1 : 0;
    }
    EXPECT_GT(entered, 600);  // Most of the moves enter: the test looks at entries.
  }
}

// OUTSIDE skips its entry search for a move beyond one face of a box around
// the mesh (free air beside it): q follows p.
TEST(Proxy, AMoveInFreeAirBesideTheMeshFollowsP) {
  const auto space_owner = make_space(cube_mesh(10.0), 0);
  Proxy proxy(*space_owner);
  EXPECT_EQ(proxy.reset({-5, 3, 4}), StartKind::Outside);
  proxy.step({-8, 30, -4}, kDt);
  EXPECT_EQ(proxy.place().state, ProxyState::Outside);
  EXPECT_EQ(proxy.q(), Vec3(-8, 30, -4));
  EXPECT_EQ(count(proxy, ProxyState::Outside, ProxyState::Outside, false), 1u);
}

// A move just above the cube's top face, within the tolerance of it, is
// beyond the mesh's own box but still enters through the side face's rim:
// the box that skips the search is grown well past every entry it could miss.
TEST(Proxy, AMoveGrazingTheMeshWithinTheToleranceStillEnters) {
  const auto space_owner = make_space(cube_mesh(10.0), 0);
  const double z = 10.0 + 0.5 * space_owner->tolerance();
  Proxy proxy(*space_owner);
  EXPECT_EQ(proxy.reset({-5, 3, z}), StartKind::Outside);
  proxy.step({5, 3, z}, kDt);
  EXPECT_NE(proxy.place().state, ProxyState::Outside);
  EXPECT_EQ(count(proxy, ProxyState::Outside, ProxyState::Outside, false), 0u);
}

TEST(Proxy, RigidCubeStopsAnOutsideProxyOnItsSurface) {
  const auto space_owner = make_space(cube_mesh(10.0), 2);
  const Space& space = *space_owner;
  Proxy proxy(space);
  proxy.reset({-5, 3, 4});
  proxy.step({3, 3, 4}, kDt);
  EXPECT_EQ(proxy.place().state, ProxyState::Face);
  EXPECT_NEAR(proxy.q().x, 0.0, 1e-9);
  EXPECT_NEAR(proxy.force_N().x, -0.3, 1e-9);
  // Straight through a cube corner, where boundary triangles meet (repair 4, docs/method.md).
  Proxy corner(space);
  corner.reset({-1, -1, -1});
  corner.step({5, 5, 5}, kDt);
  EXPECT_NE(corner.place().state, ProxyState::Outside);
  EXPECT_LT(norm(corner.q()), 1e-6);
  EXPECT_EQ(corner.check_invariants(), "");
}

// Repair 4 (docs/method.md): a path exactly through a boundary vertex meets the triangles there
// only on their rims. Aimed into a tet that has no boundary face at that
// vertex, it used to miss them all and pass into the mesh as OUTSIDE.
TEST(Proxy, EntersExactlyThroughABoundaryVertexIntoAnInnerTet) {
  const auto space_owner =
      make_space(grid_mesh({0, 5, 10}, {0, 5, 10}, {0, 5, 10}, 0.3, 21), std::int32_t{0});
  const Space& space = *space_owner;
  const TetMesh& mesh = space.mesh();
  int checked = 0;
  for (std::int32_t v = 0; v < mesh.vertex_count(); ++v) {
    if (!mesh.is_boundary_vertex(v)) continue;
    for (const VertexFanEntry& entry : mesh.vertex_fan(v)) {
      bool touches_boundary = false;
      for (int f = 0; f < 4; ++f) {
        touches_boundary =
            touches_boundary || (f != entry.local_vertex && mesh.neighbour(entry.tet, f) == kNoTet);
      }
      if (touches_boundary) continue;
      Vec3 centroid;
      for (std::int32_t w : mesh.tet(entry.tet)) centroid += mesh.vertex(w) * 0.25;
      const Vec3 d = centroid - mesh.vertex(v);
      const Vec3 from = mesh.vertex(v) - d * 0.5;
      if (mesh.locate(from) != kNoTet) continue;  // Behind the vertex is still mesh.
      const Vec3 to = mesh.vertex(v) + d * 0.5;
      Proxy proxy(space);
      proxy.reset(from);
      proxy.step(to, kDt);
      EXPECT_EQ(proxy.place().state, ProxyState::Tet) << "vertex " << v;
      EXPECT_EQ(proxy.q(), to);
      EXPECT_EQ(proxy.check_invariants(), "");
      ++checked;
    }
  }
  EXPECT_GT(checked, 0) << "the grid should have inner tets at boundary vertices";
}

// On the jittered grid with every tet that has no boundary face rigid, a
// path from outside exactly through a boundary vertex and along the plane of
// a rigid tet's face through it can meet no fan tet strictly toward p; OUTSIDE
// must not then set q = p inside the mesh, or the next tick walks into the
// bone with zero force. The rim
// now lands on the vertex unless p - q points strictly out of every closed cone.
TEST(Proxy, EnteringThroughABoundaryVertexAlongAnInnerFacePlaneStopsAtTheBone) {
  const MeshData data = grid_mesh({0, 5, 10}, {0, 5, 10}, {0, 5, 10}, 0.3, 21);
  const TetMesh shape(data.vertices_mm, data.tets, std::vector<std::int32_t>(data.tets.size(), 0));
  std::vector<std::int32_t> materials(data.tets.size(), 0);
  for (std::int32_t t = 0; t < shape.tet_count(); ++t) {
    if (!has_boundary_face(shape, t)) materials[t] = 2;
  }
  const auto space_owner = make_space(data, materials);
  const Space& space = *space_owner;
  const TetMesh& mesh = space.mesh();
  int paths = 0;
  int between_rigid = 0;
  for (std::int32_t v = 0; v < mesh.vertex_count(); ++v) {
    if (!mesh.is_boundary_vertex(v)) continue;
    for (const VertexFanEntry& entry : mesh.vertex_fan(v)) {
      if (!space.tet_is_rigid(entry.tet)) continue;
      for (int f = 0; f < 4; ++f) {
        if (f == entry.local_vertex) continue;
        Vec3 face_centre;
        for (int w = 0; w < 4; ++w) {
          if (w != f) face_centre += mesh.vertex(mesh.tet(entry.tet)[w]) / 3.0;
        }
        const Vec3 along_face = face_centre - mesh.vertex(v);
        const Vec3 from = mesh.vertex(v) - along_face * 0.5;
        if (mesh.locate(from) != kNoTet) continue;  // Behind the vertex is still mesh.
        Proxy proxy(space);
        proxy.reset(from);
        proxy.step(mesh.vertex(v) + along_face * 0.5, kDt);
        EXPECT_NE(proxy.place().state, ProxyState::Outside) << "vertex " << v << " face " << f;
        EXPECT_EQ(proxy.check_invariants(), "") << "vertex " << v << " face " << f;
        // Then into the bone itself: the proxy must stay out and push back.
        const Vec3 deep = centroid(mesh, entry.tet);
        proxy.step(deep, kDt);
        EXPECT_FALSE(inside_rigid(space, proxy.q())) << "vertex " << v << " face " << f;
        EXPECT_GT(norm(proxy.force_N()), 0.0) << "vertex " << v << " face " << f;
        ++paths;
        const std::int32_t across = mesh.neighbour(entry.tet, f);
        between_rigid += across != kNoTet && space.tet_is_rigid(across) ? 1 : 0;
      }
    }
  }
  EXPECT_EQ(paths, 108);
  EXPECT_EQ(between_rigid, 48);  // The paths: a face between two rigid tets.
}

// A rim passed by outside does not end the search. The path of the test
// above first grazes the corner of a small cube set beside the grid, exactly,
// heading out of it; only the rim beyond, at the grid's vertex, enters.
TEST(Proxy, ARimPassedByOutsideLeavesTheSearchToTheRimBeyond) {
  const MeshData grid = grid_mesh({0, 5, 10}, {0, 5, 10}, {0, 5, 10}, 0.3, 21);
  const TetMesh shape(grid.vertices_mm, grid.tets, std::vector<std::int32_t>(grid.tets.size(), 0));
  int checked = 0;
  for (std::int32_t v = 0; v < shape.vertex_count() && checked < 6; ++v) {
    if (!shape.is_boundary_vertex(v)) continue;
    for (const VertexFanEntry& entry : shape.vertex_fan(v)) {
      if (has_boundary_face(shape, entry.tet) || checked >= 6) continue;
      const int f = (entry.local_vertex + 1) % 4;
      Vec3 face_centre;
      for (int w = 0; w < 4; ++w) {
        if (w != f) face_centre += shape.vertex(shape.tet(entry.tet)[w]) / 3.0;
      }
      const Vec3 along_face = face_centre - shape.vertex(v);
      const Vec3 corner = shape.vertex(v) - along_face * 0.75;
      if (along_face.x == 0.0 || along_face.y == 0.0) continue;
      // A 1 mm cube with its corner on the path, in the octant the path leaves on both sides.
      const Vec3 octant{along_face.x > 0 ? -1.0 : 1.0, along_face.y > 0 ? 1.0 : -1.0,
                        along_face.z > 0 ? -1.0 : 1.0};
      MeshData both = grid;
      const MeshData cube = cube_mesh(1.0);
      const auto first = static_cast<std::int32_t>(both.vertices_mm.size());
      bool apart = true;
      for (const Vec3& c : cube.vertices_mm) {
        both.vertices_mm.push_back(corner + Vec3{c.x * octant.x, c.y * octant.y, c.z * octant.z});
        apart = apart && shape.locate(both.vertices_mm.back()) == kNoTet;
      }
      if (!apart) continue;
      for (auto tet : cube.tets) {
        for (auto& w : tet) w += first;
        both.tets.push_back(tet);
      }
      std::vector<std::int32_t> materials(both.tets.size(), 0);
      for (std::int32_t t = 0; t < shape.tet_count(); ++t) {
        if (!has_boundary_face(shape, t)) materials[t] = 2;
      }
      const auto space_owner = make_space(both, materials);
      const Space& space = *space_owner;
      Proxy proxy(space);
      ASSERT_EQ(proxy.reset(shape.vertex(v) - along_face * 1.5), StartKind::Outside);
      const Vec3 p = shape.vertex(v) + along_face * 0.5;
      proxy.step(p, kDt);
      // Landed at the vertex, then perhaps slid nearer p on free faces.
      EXPECT_NE(proxy.place().state, ProxyState::Outside) << "vertex " << v;
      EXPECT_LE(norm(proxy.q() - p), norm(shape.vertex(v) - p) + 1e-9) << "vertex " << v;
      EXPECT_EQ(proxy.check_invariants(), "") << "vertex " << v;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 6);
}

// An OUTSIDE proxy on an inner vertex or face of the mesh fails the check
// (its tolerance points into the mesh); one on the boundary is fine.
TEST(Proxy, CheckInvariantsRejectsAnOutsideProxyInsideTheMesh) {
  const MeshData data = grid_mesh({0, 10, 20}, {0, 10, 20}, {0, 10, 20});
  const auto space_owner = make_space(data, 0);
  const Space& space = *space_owner;
  Proxy proxy(space);
  proxy.reset({-5, 5, 5});
  proxy.set_place({ProxyState::Outside, kNoTet, 0, {10, 10, 10}});  // The inner vertex.
  EXPECT_NE(proxy.check_invariants(), "");
  proxy.set_place({ProxyState::Outside, kNoTet, 0, {10, 4, 3}});  // On the inner plane x = 10.
  EXPECT_NE(proxy.check_invariants(), "");
  proxy.set_place({ProxyState::Outside, kNoTet, 0, {4, 3, 2}});  // Inside a tet.
  EXPECT_NE(proxy.check_invariants(), "");
  proxy.set_place({ProxyState::Outside, kNoTet, 0, {0, 4, 3}});  // On the boundary.
  EXPECT_EQ(proxy.check_invariants(), "");
  proxy.set_place({ProxyState::Outside, kNoTet, 0, {-1e-3, 4, 3}});  // Just outside.
  EXPECT_EQ(proxy.check_invariants(), "");
}

// A proxy both OUTSIDE and in a rigid tet is reported as in the rigid tet.
TEST(Proxy, CheckInvariantsNamesTheRigidTet) {
  const auto space_owner = make_space(two_tets_mesh(), {0, 2});
  const Space& space = *space_owner;
  Proxy proxy(space);
  proxy.reset({2, 2, -1});
  const Vec3 in_bone = centroid(space.mesh(), 1);
  proxy.set_place({ProxyState::Outside, kNoTet, 0, in_bone});
  EXPECT_EQ(proxy.check_invariants(), "q inside rigid tet 1");
  proxy.set_place({ProxyState::Face, 0, 3, in_bone});
  EXPECT_EQ(proxy.check_invariants(), "q inside rigid tet 1");
}

// The OUTSIDE safety net: q = p only where p is outside the mesh. From a
// (corrupt) OUTSIDE place inside the mesh no entry can be found; the proxy
// must hold rather than follow p through the bone.
TEST(Proxy, OutsideNeverSetsQToAPointInsideTheMesh) {
  const auto space_owner = make_space(two_tets_mesh(), {0, 2});
  const Space& space = *space_owner;
  Proxy proxy(space);
  proxy.reset({2, 2, -1});
  const Vec3 start = centroid(space.mesh(), 0);
  proxy.set_place({ProxyState::Outside, kNoTet, 0, start});
  proxy.step(centroid(space.mesh(), 1), kDt);
  EXPECT_EQ(proxy.q(), start);
  EXPECT_FALSE(inside_rigid(space, proxy.q()));
}

// A 12-tet fan around (0,0,-5)-(0,0,5), rigid where x > 0
// and y > 0. With q on the free face y = 0 and p at (0, 0.5, 0), exactly in
// the plane between a rigid and a free tet, the face slide landed on the fan
// edge and stayed there, pushing 0.05 N for as long as p was held (0.5 N
// with p = (0, 5, 3) outside the mesh), though p itself is free and reachable.
TEST(Proxy, AFaceSlideEndingOnAnEdgeLetsTheEdgeFanDecide) {
  const MeshData data = edge_fan_mesh(12, 10.0, 5.0);
  std::vector<std::int32_t> materials(data.tets.size(), 0);
  for (std::size_t t = 0; t < data.tets.size(); ++t) {
    Vec3 c;
    for (std::int32_t v : data.tets[t]) c += data.vertices_mm[v] * 0.25;
    if (c.x > 0 && c.y > 0) materials[t] = 2;
  }
  const auto space_owner = make_space(data, materials);
  const Space& space = *space_owner;
  for (const Vec3& start : {Vec3{-1, -1, 0}, Vec3{-1, -3, 1}}) {
    Proxy proxy(space);
    proxy.reset(start);
    proxy.step({2, 2, 0}, kDt);  // Pressed into the bone: held on the face y = 0.
    ASSERT_EQ(proxy.place().state, ProxyState::Face);
    ASSERT_NEAR(norm(proxy.q() - Vec3(2, 0, 0)), 0.0, 1e-9);
    for (int tick = 0; tick < 3; ++tick) {
      proxy.step({0, 0.5, 0}, kDt);
      EXPECT_EQ(proxy.q(), Vec3(0, 0.5, 0)) << "tick " << tick;
      EXPECT_EQ(proxy.force_N(), Vec3(0, 0, 0)) << "tick " << tick;
      EXPECT_EQ(proxy.check_invariants(), "");
    }
    proxy.step({2, 2, 0}, kDt);
    proxy.step({0, 5, 3}, kDt);  // Outside the mesh, past the free tets.
    EXPECT_EQ(proxy.place().state, ProxyState::Outside);
    EXPECT_EQ(proxy.q(), Vec3(0, 5, 3));
    EXPECT_EQ(proxy.force_N(), Vec3(0, 0, 0));
  }
}

// A jump to 1e18 mm and back must not leave q where q + d s lost every digit
// (inside the rigid sphere, OUTSIDE, 0 N, for good): the entry search runs on
// the segment clipped to the mesh's reach, so the way back gives the same
// place and force as no glitch at all.
TEST(Proxy, AHugeJumpOutAndBackEntersExactly) {
  const auto space_owner = Space::from_scene(load_scene(
      std::string(HAPTICUT_TEST_DATA_DIR) + "/../../examples/sphere80.hapticut.msgpack"));
  const Space& space = *space_owner;
  Proxy direct(space);
  direct.reset({0, 0, 40});
  direct.step({0, 0, 0}, kDt);
  ASSERT_GT(norm(direct.force_N()), 1.0);
  for (const double far : {1e6, 1e15, 1e18, 1e300, std::numeric_limits<double>::max()}) {
    for (const Vec3& away : {Vec3{0, 0, far}, Vec3{far, -far, far}, Vec3{-far, 0, 0}}) {
      Proxy proxy(space);
      proxy.reset({0, 0, 40});
      // Proxy::step rejects such a sample as a device fault (out of the
      // workspace); the walk itself must still handle it exactly, so drive
      // the transitions directly.
      EXPECT_TRUE(proxy.step(away, kDt).rejected);
      const MoveContext context{space.settings().stiffness_N_per_mm, 0.0, space.tolerance()};
      for (int i = 0; i < 64 && proxy.transition(away, context).changed; ++i) {
      }
      EXPECT_EQ(proxy.place().state, ProxyState::Outside);
      proxy.step({0, 0, 0}, kDt);
      EXPECT_FALSE(inside_rigid(space, proxy.q())) << "far " << far;
      EXPECT_NE(proxy.place().state, ProxyState::Outside) << "far " << far;
      EXPECT_GT(norm(proxy.force_N()), 1.0) << "far " << far;
      EXPECT_EQ(proxy.check_invariants(), "") << "far " << far;
      if (away.x == 0.0) {  // Straight back down the same line: exactly as without the jump.
        EXPECT_NEAR(norm(proxy.q() - direct.q()), 0.0, 1e-9) << "far " << far;
        EXPECT_NEAR(norm(proxy.force_N() - direct.force_N()), 0.0, 1e-10) << "far " << far;
      }
    }
  }
}

// The same on a grid of slivers with a rigid core, from 1e15 mm on every
// side and straight through from one side to the other.
TEST(Proxy, HugeJumpsOnASliverGridNeverEndInTheBone) {
  const MeshData data =
      grid_mesh({0, 7, 15, 16, 30, 41}, {0, 9, 12, 25, 33}, {0, 10, 19, 20.5, 32}, 0.45, 11);
  std::vector<std::int32_t> materials(data.tets.size(), 0);
  Vec3 middle{20.5, 16.5, 16};
  for (std::size_t t = 0; t < data.tets.size(); ++t) {
    Vec3 c;
    for (std::int32_t v : data.tets[t]) c += data.vertices_mm[v] * 0.25;
    if (norm(c - middle) < 9.0) materials[t] = 2;
  }
  const auto space_owner = make_space(data, materials);
  const Space& space = *space_owner;
  for (const double far : {1e15, 1e18, 1e200}) {
    for (int axis = 0; axis < 3; ++axis) {
      for (const double sign : {-1.0, 1.0}) {
        Vec3 offset;
        (axis == 0 ? offset.x : axis == 1 ? offset.y : offset.z) = sign * far;
        Proxy proxy(space);
        proxy.reset(middle + offset * (20.0 / far));
        proxy.step(middle + offset, kDt);
        proxy.step(middle, kDt);
        EXPECT_FALSE(inside_rigid(space, proxy.q())) << "far " << far << " axis " << axis;
        EXPECT_GT(norm(proxy.force_N()), 0.1) << "far " << far << " axis " << axis;
        EXPECT_EQ(proxy.check_invariants(), "");
        proxy.step(middle + offset, kDt);
        proxy.step(middle - offset, kDt);  // Both ends far: straight through the mesh.
        EXPECT_FALSE(inside_rigid(space, proxy.q())) << "far " << far << " axis " << axis;
        EXPECT_EQ(proxy.check_invariants(), "");
      }
    }
  }
}

TEST(Proxy, EdgeFanPicksTheTetTowardP) {
  const MeshData mesh = edge_fan_mesh(12);
  const auto space_owner = make_space(mesh, 0);
  const Space& space = *space_owner;
  Proxy proxy(space);
  proxy.reset({0.5, 0.2, 0.3});
  // Put the proxy on the axis edge, owned by tet 0.
  const int local_edge = kEdgeOfVertices[0][1];
  proxy.set_place({ProxyState::Edge, 0, static_cast<std::int8_t>(local_edge), {0, 0, 1}});
  const Vec3 target{-3, -2, 1};
  proxy.step(target, kDt);
  EXPECT_EQ(proxy.place().state, ProxyState::Tet);
  EXPECT_EQ(proxy.q(), target);
  EXPECT_LE(space.mesh().outside_distance(proxy.place().tet, target), 1e-9);
}

TEST(Proxy, IcosahedronVertexSlidesAlongARigidNeighbourhood) {
  // All 20 tets rigid but one: from the centre the proxy may only go into that one.
  const MeshData mesh = icosahedron_mesh(10.0);
  std::vector<std::int32_t> materials(20, 2);
  materials[7] = 0;
  const auto space_owner = make_space(mesh, materials);
  const Space& space = *space_owner;
  Proxy proxy(space);
  proxy.reset({50, 0, 0});
  proxy.set_place({ProxyState::Vertex, 7, 0, {0, 0, 0}});
  Vec3 inside;
  for (std::int32_t v : mesh.tets[7]) inside += mesh.vertices_mm[v] * 0.25;
  proxy.step(inside, kDt);
  EXPECT_EQ(proxy.place().state, ProxyState::Tet);
  EXPECT_EQ(proxy.place().tet, 7);
  EXPECT_EQ(proxy.check_invariants(), "");
  // Pushing into a rigid tet from the centre leaves the proxy on the free tet's boundary.
  proxy.set_place({ProxyState::Vertex, 7, 0, {0, 0, 0}});
  Vec3 rigid_centroid;
  for (std::int32_t v : mesh.tets[3]) rigid_centroid += mesh.vertices_mm[v] * 0.25;
  proxy.step(rigid_centroid, kDt);
  EXPECT_EQ(proxy.check_invariants(), "");
  EXPECT_NE(proxy.place().state, ProxyState::Outside);
}

TEST(Proxy, StartInsideRigidIsPushedToTheNearestFreeFace) {
  const auto space_owner =
      make_space(grid_mesh({0, 10, 20, 30}, {0, 10, 20, 30}, {0, 10, 20, 30}), [] {
        std::vector<std::int32_t> m(27 * 6, 0);
        for (int t = 13 * 6; t < 14 * 6; ++t) m[t] = 2;  // The middle cell is bone.
        return m;
      }());
  const Space& space = *space_owner;
  Proxy proxy(space);
  EXPECT_EQ(proxy.reset({15, 15, 11}), StartKind::PushedOutOfRigid);
  EXPECT_EQ(proxy.place().state, ProxyState::Face);
  EXPECT_NEAR(proxy.q().z, 10.0, 1e-9);
  EXPECT_NEAR(proxy.q().x, 15.0, 1e-9);
  EXPECT_EQ(proxy.check_invariants(), "");
  proxy.step({15, 15, 11}, kDt);
  EXPECT_NEAR(proxy.force_N().z, -0.1, 1e-9);
}

TEST(Proxy, NonFiniteInputIsRejectedAndZeroesTheForce) {
  const auto space_owner = make_space(two_tets_mesh(), {0, 2});
  const Space& space = *space_owner;
  Proxy proxy(space);
  proxy.reset({2, 2, -1});
  proxy.step({2, 2, 3}, kDt);
  const ProxyPlace before = proxy.place();
  const TickResult r = proxy.step({std::numeric_limits<double>::quiet_NaN(), 0, 0}, kDt);
  EXPECT_TRUE(r.rejected);
  EXPECT_EQ(proxy.force_N(), Vec3(0, 0, 0));
  EXPECT_EQ(proxy.place().q, before.q);
  EXPECT_EQ(proxy.counters().rejected_inputs, 1u);
  EXPECT_THROW(proxy.reset({0, std::numeric_limits<double>::infinity(), 0}), std::invalid_argument);
}

TEST(Proxy, CapIsCountedAndItsForceClamped) {
  EngineSettings settings;
  settings.max_transitions_per_tick = 3;
  settings.capped_tick_force_N = 0.5;
  const MeshData mesh = grid_mesh({0, 10, 20, 30, 40, 50}, {0, 10}, {0, 10});
  const auto space_owner = make_space(mesh, std::vector<std::int32_t>(mesh.tets.size(), 0),
                                      testing::paper_materials(), settings);
  const Space& space = *space_owner;
  Proxy proxy(space);
  proxy.reset({1, 5, 5});
  const TickResult r = proxy.step({49, 5, 5}, kDt);
  EXPECT_TRUE(r.capped);
  EXPECT_EQ(r.transitions, 3);
  EXPECT_EQ(proxy.counters().capped_ticks, 1u);
  // Unfinished: the last finished force is held (zero, in free air), no jump.
  EXPECT_EQ(proxy.force_N(), Vec3(0, 0, 0));
  EXPECT_EQ(proxy.check_invariants(), "");
  for (int i = 0; i < 20 && proxy.q() != Vec3(49, 5, 5); ++i) proxy.step({49, 5, 5}, kDt);
  EXPECT_EQ(proxy.q(), Vec3(49, 5, 5));  // It catches up over the following ticks.
}

}  // namespace
}  // namespace hapticut
