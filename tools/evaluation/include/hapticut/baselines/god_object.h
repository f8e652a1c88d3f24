// Baseline: the surface god-object of Zilles and Salisbury (1995) on a closed
// triangle surface. The proxy (god-object) moves toward the device point p
// along a straight segment; the first triangle the segment enters becomes a
// constraint plane, the target becomes the point of the active planes nearest
// p (Lagrange multipliers, up to three planes), and the walk repeats. A
// bounding-volume tree (hapticut/aabb_tree.h) answers the segment query.
// Knows only the surface: no drag, no layers, no inside.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "hapticut/aabb_tree.h"
#include "hapticut/vec3.h"

namespace hapticut::baselines {

// The closed surface with everything a query needs, built once and shared
// by any number of god-objects.
class TriangleSurface {
 public:
  struct Triangle {
    Vec3 normal;  // Unit, out of the solid.
    double offset = 0.0;
    std::array<Vec3, 3> edge_normal;  // Unit, in the plane, pointing into the triangle.
    std::array<double, 3> edge_offset{};
  };

  // vertices_mm, #T by 3 triangles wound counter-clockwise seen from outside.
  // use_tree = false makes queries test every triangle (to show what the tree
  // buys). tolerance_mm <= 0: 1e-9 x the bounding-box diagonal, as TetMesh.
  TriangleSurface(std::vector<Vec3> vertices_mm, std::vector<std::array<std::int32_t, 3>> triangles,
                  bool use_tree = true, double tolerance_mm = 0.0);

  std::int32_t triangle_count() const { return static_cast<std::int32_t>(triangles_.size()); }
  const Triangle& triangle(std::int32_t t) const { return planes_[t]; }
  bool uses_tree() const { return use_tree_; }
  const AabbTree& tree() const { return tree_; }
  double tolerance() const { return tolerance_; }
  std::size_t memory_bytes() const;

 private:
  std::vector<Vec3> vertices_;
  std::vector<std::array<std::int32_t, 3>> triangles_;
  std::vector<Triangle> planes_;
  AabbTree tree_;
  bool use_tree_;
  double tolerance_ = 0.0;
};

class SurfaceGodObject {
 public:
  static constexpr int kMaxConstraints = 3;

  SurfaceGodObject(const TriangleSurface& surface, double stiffness_N_per_mm);

  // q = p: the start must be outside the surface.
  void reset(const Vec3& p);
  // One tick; returns the number of triangles tested.
  int step(const Vec3& p);

  const Vec3& q() const { return q_; }
  Vec3 force_N() const { return (q_ - last_p_) * stiffness_N_per_mm_; }
  int active_constraints() const { return active_count_; }

 private:
  struct Hit {
    std::int32_t triangle = -1;
    double parameter = 2.0;
    double target_depth = 0.0;
  };
  void consider(std::int32_t t, const Vec3& a, const Vec3& b, Hit& best) const;
  Vec3 constrained_target(const Vec3& p) const;

  const TriangleSurface* surface_;
  double stiffness_N_per_mm_;
  Vec3 q_;
  Vec3 last_p_;
  std::array<std::int32_t, kMaxConstraints> active_{};
  int active_count_ = 0;
};

}  // namespace hapticut::baselines
