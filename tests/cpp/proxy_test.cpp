#include "hapticut/proxy.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "test_support.h"

namespace hapticut {
namespace {

using testing::make_space;

constexpr double kDt = 0.001;

std::uint64_t count(const Proxy& proxy, ProxyState from, ProxyState to, bool neighbour) {
  return proxy.counters().transitions[int(from)][int(to)][neighbour ? 1 : 0];
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

TEST(Proxy, RigidCubeStopsAnOutsideProxyOnItsSurface) {
  const auto space_owner = make_space(cube_mesh(10.0), 2);
  const Space& space = *space_owner;
  Proxy proxy(space);
  proxy.reset({-5, 3, 4});
  proxy.step({3, 3, 4}, kDt);
  EXPECT_EQ(proxy.place().state, ProxyState::Face);
  EXPECT_NEAR(proxy.q().x, 0.0, 1e-9);
  EXPECT_NEAR(proxy.force_N().x, -0.3, 1e-9);
  // Straight through a cube corner, where boundary triangles meet (repair 4).
  Proxy corner(space);
  corner.reset({-1, -1, -1});
  corner.step({5, 5, 5}, kDt);
  EXPECT_NE(corner.place().state, ProxyState::Outside);
  EXPECT_LT(norm(corner.q()), 1e-6);
  EXPECT_EQ(corner.check_invariants(), "");
}

// Repair 4: a path exactly through a boundary vertex meets the triangles there
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
