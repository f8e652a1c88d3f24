// The baselines of the evaluation (voxel proxy, surface god-object) and force
// shading: the invariants each method promises, on random walks.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "hapticut/baselines/god_object.h"
#include "hapticut/baselines/voxel_proxy.h"
#include "hapticut/force_shading.h"
#include "hapticut/proxy.h"
#include "test_support.h"

namespace hapticut {
namespace {

using baselines::SurfaceGodObject;
using baselines::TriangleSurface;
using baselines::VoxelGrid;
using baselines::VoxelProxy;

// A solid ball of radius 10 mm in a 1 mm grid over [-16, 16]^3.
VoxelGrid ball_grid(double cell_mm) {
  const int n = static_cast<int>(std::ceil(32.0 / cell_mm));
  std::vector<std::uint8_t> solid(static_cast<std::size_t>(n) * n * n, 0);
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        const Vec3 c = Vec3{-16.0, -16.0, -16.0} + Vec3{i + 0.5, j + 0.5, k + 0.5} * cell_mm;
        solid[(static_cast<std::size_t>(k) * n + j) * n + i] = norm(c) < 10.0 ? 1 : 0;
      }
    }
  }
  return VoxelGrid({-16.0, -16.0, -16.0}, cell_mm, {n, n, n}, std::move(solid));
}

TEST(VoxelProxy, NeverEndsATickInASolidCell) {
  const VoxelGrid grid = ball_grid(1.0);
  VoxelProxy proxy(grid, 0.1);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> step(0.0, 2.0);
  Vec3 p{0.0, 0.0, 14.0};
  proxy.reset(p);
  for (int k = 0; k < 20000; ++k) {
    p += Vec3{step(rng), step(rng), step(rng)};
    p = {std::clamp(p.x, -15.0, 15.0), std::clamp(p.y, -15.0, 15.0), std::clamp(p.z, -15.0, 15.0)};
    proxy.step(p);
    const auto& c = proxy.cell();
    ASSERT_FALSE(grid.is_solid(c[0], c[1], c[2])) << "tick " << k;
    ASSERT_FALSE(grid.is_solid_at(proxy.q() + (proxy.q() - p) * 1e-9)) << "tick " << k;
    ASSERT_TRUE(is_finite(proxy.q()));
  }
}

TEST(VoxelProxy, StopsOnTheBlockedCellFace) {
  const VoxelGrid grid = ball_grid(1.0);
  VoxelProxy proxy(grid, 0.1);
  proxy.reset({0.3, 0.2, 14.0});
  proxy.step({0.3, 0.2, 0.0});
  // The ball's top cell column at x, y in [0, 1] is solid from z = 9 up to 10.
  EXPECT_DOUBLE_EQ(proxy.q().z, 10.0);
  EXPECT_EQ(proxy.active_constraints(), 1);
  EXPECT_GT(proxy.force_N().z, 0.0);
}

// A closed cube surface of half-size h, wound outward.
TriangleSurface cube_surface(double h, bool use_tree = true) {
  std::vector<Vec3> v;
  for (int z = 0; z < 2; ++z) {
    for (int y = 0; y < 2; ++y) {
      for (int x = 0; x < 2; ++x) v.push_back({x ? h : -h, y ? h : -h, z ? h : -h});
    }
  }
  std::vector<std::array<std::int32_t, 3>> t{{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6},
                                             {0, 1, 5}, {0, 5, 4}, {2, 6, 7}, {2, 7, 3},
                                             {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  return TriangleSurface(v, t, use_tree);
}

TEST(SurfaceGodObject, StaysOutsideTheCubeOnARandomWalk) {
  for (bool tree : {true, false}) {
    const TriangleSurface cube = cube_surface(5.0, tree);
    SurfaceGodObject proxy(cube, 0.1);
    std::mt19937_64 rng(7);
    std::normal_distribution<double> step(0.0, 1.5);
    Vec3 p{0.0, 0.0, 9.0};
    proxy.reset(p);
    for (int k = 0; k < 20000; ++k) {
      p += Vec3{step(rng), step(rng), step(rng)};
      p = {std::clamp(p.x, -9.0, 9.0), std::clamp(p.y, -9.0, 9.0), std::clamp(p.z, -9.0, 9.0)};
      proxy.step(p);
      const Vec3& q = proxy.q();
      const double inside =
          std::min({5.0 - std::abs(q.x), 5.0 - std::abs(q.y), 5.0 - std::abs(q.z)});
      ASSERT_LE(inside, 1e-6) << "tick " << k;
    }
  }
}

TEST(SurfaceGodObject, PressesOntoAFaceAndSlidesOffItsEdge) {
  const TriangleSurface cube = cube_surface(5.0);
  SurfaceGodObject proxy(cube, 0.1);
  proxy.reset({1.0, 2.0, 8.0});
  proxy.step({1.0, 2.0, 3.0});
  EXPECT_NEAR(proxy.q().x, 1.0, 1e-9);
  EXPECT_NEAR(proxy.q().y, 2.0, 1e-9);
  EXPECT_NEAR(proxy.q().z, 5.0, 1e-9);
  // Past the edge x = 5, p is outside: the proxy slides over the top face,
  // off the edge and reaches p in free space (zero force).
  proxy.step({6.0, 2.0, 3.0});
  EXPECT_NEAR(proxy.q().z, 5.0, 1e-9);
  proxy.step({6.0, 2.0, 3.0});
  EXPECT_NEAR(norm(proxy.q() - Vec3{6.0, 2.0, 3.0}), 0.0, 1e-12);
  EXPECT_EQ(proxy.force_N(), Vec3{});
}

TEST(ForceShading, RigidSurfaceOfABlockIsClosedAndNormalsAreUnit) {
  const MeshData data = grid_mesh({-10, -5, 0, 5, 10}, {-10, -5, 0, 5, 10}, {-10, -5, 0, 5, 10});
  std::vector<std::int32_t> labels;
  for (const auto& tet : data.tets) {
    Vec3 c;
    for (std::int32_t v : tet) c += data.vertices_mm[v] * 0.25;
    labels.push_back(std::abs(c.x) < 5 && std::abs(c.y) < 5 && std::abs(c.z) < 5 ? 2 : 0);
  }
  const auto space_owner = testing::make_space(data, labels);
  const Space& space = *space_owner;
  const RigidSurface surface = extract_rigid_surface(space);
  double volume = 0.0;
  for (const auto& t : surface.triangles) {
    volume += dot(surface.vertices_mm[t[0]],
                  cross(surface.vertices_mm[t[1]], surface.vertices_mm[t[2]])) /
              6.0;
  }
  EXPECT_NEAR(volume, 1000.0, 1e-9);
  const ForceShading shading(space);
  int on_surface = 0;
  for (std::int32_t v = 0; v < space.mesh().vertex_count(); ++v) {
    const double n = norm(shading.vertex_normal(v));
    if (n > 0.0) {
      ++on_surface;
      EXPECT_NEAR(n, 1.0, 1e-12);
    }
  }
  EXPECT_EQ(on_surface, static_cast<int>(surface.vertices_mm.size()));
  // A proxy in a tet (no contact) feels the raw force.
  ProxyPlace free_place{ProxyState::Tet, 0, 0, {-8, -8, -8}};
  EXPECT_EQ(shading.shade(free_place, {0.1, 0.2, 0.3}), (Vec3{0.1, 0.2, 0.3}));
}

TEST(ForceShading, PressingTheCentreOfABlockFaceKeepsTheFaceNormal) {
  const MeshData data = grid_mesh({-10, -5, 0, 5, 10}, {-10, -5, 0, 5, 10}, {-10, -5, 0, 5, 10});
  std::vector<std::int32_t> labels;
  for (const auto& tet : data.tets) {
    Vec3 c;
    for (std::int32_t v : tet) c += data.vertices_mm[v] * 0.25;
    labels.push_back(std::abs(c.x) < 5 && std::abs(c.y) < 5 && std::abs(c.z) < 5 ? 2 : 0);
  }
  const auto space_owner = testing::make_space(data, labels);
  const Space& space = *space_owner;
  const ForceShading shading(space);
  Proxy proxy(space);
  proxy.reset({0.0, 0.0, 8.0});
  proxy.step({0.0, 0.0, 3.0}, 0.001);
  ASSERT_NEAR(proxy.q().z, 5.0, 1e-9);
  // The face's centre vertex (0, 0, 5) has the face normal: the shaded force
  // there is the raw force.
  const Vec3 shaded = shading.shade(proxy.place(), proxy.force_N());
  EXPECT_NEAR(shaded.x, 0.0, 1e-9);
  EXPECT_NEAR(shaded.y, 0.0, 1e-9);
  EXPECT_NEAR(shaded.z, proxy.force_N().z, 1e-9);
}

// The FACE path of shade() written out as in Morgenbesser and Srinivasan:
// barycentric weights from signed sub-triangle areas at each evaluation, two
// fixed-point steps. shade() evaluates the same affine field from
// precomputed per-face data; the two must agree.
Vec3 shade_on_face_directly(const Space& space, const ForceShading& shading,
                            const ProxyPlace& place, const Vec3& raw) {
  const TetMesh& mesh = space.mesh();
  const Vec3 face_normal = -mesh.face_plane(place.tet, place.local).normal;
  std::array<Vec3, 3> corner;
  const std::array<Vec3, 3> normal = shading.face_corner_normals(place.tet, place.local);
  int count = 0;
  for (int v = 0; v < 4; ++v) {
    if (v == place.local) continue;
    corner[count++] = mesh.vertex(mesh.tet(place.tet)[v]);
  }
  const double area = dot(cross(corner[1] - corner[0], corner[2] - corner[0]), face_normal);
  auto normal_at = [&](const Vec3& x) {
    Vec3 n;
    for (int k = 0; k < 3; ++k) {
      n += normal[k] *
           (dot(cross(corner[(k + 1) % 3] - x, corner[(k + 2) % 3] - x), face_normal) / area);
    }
    return n / norm(n);
  };
  const double normal_part = dot(raw, face_normal);
  const Vec3 p = place.q - raw / space.settings().stiffness_N_per_mm;
  const double p_height = dot(p - place.q, face_normal);
  Vec3 n = normal_at(place.q);
  for (int iteration = 0; iteration < 2; ++iteration) {
    const double along = dot(n, face_normal);
    if (!(along > 0.5)) break;  // Leaning 60 degrees or more off the facet: keep n.
    n = normal_at(p - n * (p_height / along));
  }
  return raw - face_normal * normal_part + n * normal_part;
}

TEST(ForceShading, PrecomputedFaceFieldMatchesTheDirectInterpolation) {
  // Jittered, so that the fitted corner normals lean off the facets.
  const MeshData data =
      grid_mesh({-10, -5, 0, 5, 10}, {-10, -5, 0, 5, 10}, {-10, -5, 0, 5, 10}, 0.1, 3);
  std::vector<std::int32_t> labels;
  for (const auto& tet : data.tets) {
    Vec3 c;
    for (std::int32_t v : tet) c += data.vertices_mm[v] * 0.25;
    labels.push_back(std::abs(c.x) < 5 && std::abs(c.y) < 5 && std::abs(c.z) < 5 ? 2 : 0);
  }
  const auto space_owner = testing::make_space(data, labels);
  const Space& space = *space_owner;
  const ForceShading shading(space);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> across(-4.9, 4.9);
  std::uniform_real_distribution<double> depth(0.1, 3.0);
  int shaded_faces = 0;
  int turned = 0;
  for (int trial = 0; trial < 200; ++trial) {
    // Press onto the top face (z = 5, rough) near anywhere, corners
    // included, where the shading turns the force.
    const double x = across(rng);
    const double y = across(rng);
    Proxy proxy(space);
    proxy.reset({x, y, 8.0});
    proxy.step({x, y, 5.0 - depth(rng)}, 0.001);
    if (proxy.place().state != ProxyState::Face) continue;
    ++shaded_faces;
    const Vec3 expected = shade_on_face_directly(space, shading, proxy.place(), proxy.force_N());
    const Vec3 shaded = shading.shade(proxy.place(), proxy.force_N());
    EXPECT_NEAR(norm(shaded - expected), 0.0, 1e-12 * norm(expected)) << x << " " << y;
    turned += norm(shaded - proxy.force_N()) > 1e-3 * norm(shaded) ? 1 : 0;
  }
  EXPECT_GT(shaded_faces, 150);
  EXPECT_GT(turned, 100);
}

}  // namespace
}  // namespace hapticut
