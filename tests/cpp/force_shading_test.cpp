// Force shading's normals: the nearest source triangle
// found exactly, and normals smoothed at the scale of the rigid surface's facets.
#include "hapticut/force_shading.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <vector>

#include "hapticut/reference_meshes.h"
#include "test_support.h"

namespace hapticut {
namespace {

using Triangles = std::vector<std::array<std::int32_t, 3>>;

double degrees_between(const Vec3& a, const Vec3& b) {
  return std::acos(std::clamp(dot(a, b) / (norm(a) * norm(b)), -1.0, 1.0)) * 180.0 / M_PI;
}

// A rigid block |x|, |y| < half_mm, |z| < half_z_mm (default half_mm) in a
// Kuhn grid of the given planes, its vertices moved by up to jitter x spacing.
std::shared_ptr<const Space> rigid_block(const std::vector<double>& planes, double half_mm,
                                         double jitter = 0.0, double half_z_mm = 0.0) {
  const MeshData data = grid_mesh(planes, planes, planes, jitter, 7);
  const double half_z = half_z_mm > 0.0 ? half_z_mm : half_mm;
  std::vector<std::int32_t> labels;
  for (const auto& tet : data.tets) {
    Vec3 c;
    for (std::int32_t v : tet) c += data.vertices_mm[v] * 0.25;
    const bool inside =
        std::abs(c.x) < half_mm && std::abs(c.y) < half_mm && std::abs(c.z) < half_z;
    labels.push_back(inside ? 2 : 0);
  }
  return testing::make_space(data, labels);
}

std::vector<double> planes(double from, double to, double step) {
  std::vector<double> out;
  for (double x = from; x <= to + 1e-9; x += step) out.push_back(x);
  return out;
}

// The mesh vertex at x (exactly: the grid is not jittered).
std::int32_t vertex_at(const Space& space, const Vec3& x) {
  for (std::int32_t v = 0; v < space.mesh().vertex_count(); ++v) {
    if (space.mesh().vertex(v) == x) return v;
  }
  ADD_FAILURE() << "no vertex at " << x.x << " " << x.y << " " << x.z;
  return 0;
}

TEST(ForceShadingSource, FindsTheNearestTriangleBeyondTheFirstSearchRadius) {
  const auto space_owner = rigid_block(planes(-10, 10, 5), 5.0);
  const Space& space = *space_owner;
  const Vec3 x{0.0, 0.0, 5.0};  // The top face's centre vertex.
  // A: large and tilted, its box holds x, its plane x + z = 5 + 3 sqrt(2)
  // passes 3 mm from x. B: small, 1 mm above x, its box 1 mm from x: outside
  // the first search radius (1e-4 of the source's diagonal), which A's box
  // already satisfies. Their normals face away from each other. Small
  // triangles beside B and far above put B and A in different leaves of the
  // source's tree (4 a leaf, split at the median along z).
  const double c = 5.0 + 3.0 * std::sqrt(2.0);
  std::vector<Vec3> vertices{{-20.0, -20.0, c + 20.0}, {0.0, 20.0, c},   {20.0, -20.0, c - 20.0},
                             {-0.5, -0.5, 6.0},        {0.5, -0.5, 6.0}, {0.0, 0.5, 6.0}};
  Triangles triangles{{0, 1, 2}, {3, 4, 5}};
  ASSERT_LT(dot(cross(vertices[1] - vertices[0], vertices[2] - vertices[0]), Vec3{1, 0, 1}), 0.0);
  for (const Vec3& at : std::vector<Vec3>{{2.5, 2.5, 7.0},
                                          {-2.5, 2.5, 7.0},
                                          {0.0, -2.5, 7.0},
                                          {0, 0, 60},
                                          {0, 0, 70},
                                          {0, 0, 80}}) {
    const auto first = static_cast<std::int32_t>(vertices.size());
    vertices.insert(vertices.end(), {at, at + Vec3{0.2, 0, 0}, at + Vec3{0, 0.2, 0}});
    triangles.push_back({first, first + 1, first + 2});
  }
  const ForceShading shading(space, vertices, triangles);
  const Vec3& n = shading.vertex_normal(vertex_at(space, x));
  EXPECT_LT(degrees_between(n, {0.0, 0.0, 1.0}), 1e-9) << n.x << " " << n.y << " " << n.z;
}

// The icosahedron's faces split in 4 on a sphere: every vertex lies on mirror
// planes of the icosahedron, so its angle-weighted normal is exactly radial.
void sphere80(double radius_mm, std::vector<Vec3>& vertices, Triangles& triangles) {
  const MeshData ball = vertex_fan_mesh(1, radius_mm);
  vertices = ball.vertices_mm;
  for (const auto& tet : ball.tets) {
    std::array<std::int32_t, 3> tri{};
    int k = 0;
    for (std::int32_t v : tet) {
      if (v != 0) tri[k++] = v;
    }
    const Vec3 n = cross(vertices[tri[1]] - vertices[tri[0]], vertices[tri[2]] - vertices[tri[0]]);
    if (dot(n, vertices[tri[0]]) < 0.0) std::swap(tri[1], tri[2]);
    triangles.push_back(tri);
  }
}

TEST(ForceShadingSource, ASphereIsFittedExactly) {
  // The smoothed normal of a source sphere is the sphere's own at every
  // surface vertex, wherever the vertex lies against the source's facets
  // (the unsmoothed field at the nearest source point is radial through
  // that point instead, off by up to several degrees).
  const auto space_owner = rigid_block(planes(-10, 10, 2.5), 5.0);
  const Space& space = *space_owner;
  std::vector<Vec3> vertices;
  Triangles triangles;
  sphere80(20.0, vertices, triangles);
  const ForceShading shading(space, vertices, triangles);
  int checked = 0;
  for (std::int32_t v = 0; v < space.mesh().vertex_count(); ++v) {
    const Vec3& n = shading.vertex_normal(v);
    if (n == Vec3{}) continue;
    ++checked;
    EXPECT_LT(degrees_between(n, space.mesh().vertex(v)), 1e-5) << v;
  }
  EXPECT_EQ(checked, 98);  // The block's surface: 6 x 16 + 2 vertices.
}

TEST(ForceShadingSource, BumpsSmallerThanTheFacetsAverageOut) {
  // The source: the plane z = 5 carrying bumps 1.5 mm across and 0.1 mm
  // high (normals up to 23 degrees off), on a 0.25 mm grid. The block's top
  // face has 2.5 mm facets: at that scale the surface is the plane.
  const auto space_owner = rigid_block(planes(-10, 10, 2.5), 5.0);
  const Space& space = *space_owner;
  std::vector<Vec3> vertices;
  Triangles triangles;
  const int n = 161;  // -20 to 20 mm.
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const double x = -20.0 + 0.25 * i;
      const double y = -20.0 + 0.25 * j;
      const double bump =
          0.1 * std::sin(2.0 * M_PI * x / 1.5) * std::sin(2.0 * M_PI * y / 1.5 + 1.0);
      vertices.push_back({x, y, 5.0 + bump});
    }
  }
  for (int i = 0; i + 1 < n; ++i) {
    for (int j = 0; j + 1 < n; ++j) {
      const std::int32_t a = i * n + j;
      triangles.push_back({a, a + n, a + n + 1});
      triangles.push_back({a, a + n + 1, a + 1});
    }
  }
  const ForceShading shading(space, vertices, triangles);
  double worst = 0.0;
  for (double x = -2.5; x <= 2.5; x += 2.5) {
    for (double y = -2.5; y <= 2.5; y += 2.5) {
      const Vec3& normal = shading.vertex_normal(vertex_at(space, {x, y, 5.0}));
      worst = std::max(worst, degrees_between(normal, {0.0, 0.0, 1.0}));
    }
  }
  EXPECT_LT(worst, 1.0);
}

TEST(ForceShadingSource, RejectsABrokenSource) {
  const auto space_owner = rigid_block(planes(-10, 10, 5), 5.0);
  const Space& space = *space_owner;
  const std::vector<Vec3> vertices{{0, 0, 6}, {1, 0, 6}, {0, 1, 6}};
  EXPECT_THROW(ForceShading(space, vertices, Triangles{{0, 1, 3}}), std::invalid_argument);
  EXPECT_THROW(ForceShading(space, vertices, Triangles{{0, -1, 2}}), std::invalid_argument);
  std::vector<Vec3> broken = vertices;
  broken[1].y = std::nan("");
  EXPECT_THROW(ForceShading(space, broken, Triangles{{0, 1, 2}}), std::invalid_argument);
}

TEST(ForceShadingOwnSurface, NormalsOfARoughSurfaceAreSmoothed) {
  // A jittered grid: the slab's top face z = 5 is rough at the scale of its
  // own facets. Its vertex normals, fitted over twice the longest facet
  // edge, lean from the face's normal by well under half of what the
  // one-ring (angle-weighted) normals lean. (Near the slab's edges, 10 mm
  // away, the fit rounds them: smoothing bends what is sharp at its scale.)
  const auto space_owner = rigid_block(planes(-20, 20, 2.5), 15.0, 0.3, 5.0);
  const Space& space = *space_owner;
  const RigidSurface surface = extract_rigid_surface(space);
  std::vector<Vec3> one_ring(surface.vertices_mm.size());
  for (const auto& t : surface.triangles) {
    const Vec3 n = cross(surface.vertices_mm[t[1]] - surface.vertices_mm[t[0]],
                         surface.vertices_mm[t[2]] - surface.vertices_mm[t[0]]);
    for (int k = 0; k < 3; ++k) {
      const Vec3& x = surface.vertices_mm[t[k]];
      const Vec3 e1 = surface.vertices_mm[t[(k + 1) % 3]] - x;
      const Vec3 e2 = surface.vertices_mm[t[(k + 2) % 3]] - x;
      one_ring[t[k]] += n / norm(n) * std::acos(dot(e1, e2) / (norm(e1) * norm(e2)));
    }
  }
  const ForceShading shading(space);
  double smoothed = 0.0;
  double raw = 0.0;
  int count = 0;
  for (std::size_t i = 0; i < surface.vertices_mm.size(); ++i) {
    const Vec3& x = surface.vertices_mm[i];
    // The top face away from its edges (within 1 mm of the facets' jitter).
    if (x.z < 4.0 || std::abs(x.x) > 6.0 || std::abs(x.y) > 6.0) continue;
    ++count;
    smoothed += degrees_between(shading.vertex_normal(surface.mesh_vertex[i]), {0, 0, 1});
    raw += degrees_between(one_ring[i], {0, 0, 1});
  }
  ASSERT_EQ(count, 25);
  EXPECT_GT(raw / count, 3.0) << smoothed / count;  // The face is rough.
  EXPECT_LT(smoothed, 0.5 * raw) << raw / count << " " << smoothed / count;
}

}  // namespace
}  // namespace hapticut
