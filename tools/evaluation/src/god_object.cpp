#include "hapticut/baselines/god_object.h"

#include <cmath>
#include <stdexcept>

namespace hapticut::baselines {

TriangleSurface::TriangleSurface(std::vector<Vec3> vertices_mm,
                                 std::vector<std::array<std::int32_t, 3>> triangles, bool use_tree,
                                 double tolerance_mm)
    : vertices_(std::move(vertices_mm)), triangles_(std::move(triangles)), use_tree_(use_tree) {
  Aabb all;
  std::vector<Aabb> boxes;
  boxes.reserve(triangles_.size());
  for (const auto& tri : triangles_) {
    Aabb box;
    for (std::int32_t v : tri) {
      if (v < 0 || v >= static_cast<std::int32_t>(vertices_.size())) {
        throw std::invalid_argument("god-object: triangle refers to a missing vertex");
      }
      box.grow(vertices_[v]);
    }
    all.grow(box);
    boxes.push_back(box);
    const Vec3& a = vertices_[tri[0]];
    const Vec3& b = vertices_[tri[1]];
    const Vec3& c = vertices_[tri[2]];
    Vec3 n = cross(b - a, c - a);
    const double length = norm(n);
    if (!(length > 0.0)) throw std::invalid_argument("god-object: degenerate triangle");
    n = n / length;
    Triangle plane;
    plane.normal = n;
    plane.offset = dot(n, a);
    const std::array<Vec3, 3> corner{a, b, c};
    for (int k = 0; k < 3; ++k) {
      const Vec3& from = corner[k];
      const Vec3& to = corner[(k + 1) % 3];
      Vec3 m = cross(n, to - from);
      m = m / norm(m);
      plane.edge_normal[k] = m;
      plane.edge_offset[k] = dot(m, from);
    }
    planes_.push_back(plane);
  }
  tolerance_ = tolerance_mm > 0.0 ? tolerance_mm : 1e-9 * norm(all.hi - all.lo);
  if (use_tree_) tree_ = AabbTree(boxes);
}

std::size_t TriangleSurface::memory_bytes() const {
  return vertices_.capacity() * sizeof(Vec3) + triangles_.capacity() * sizeof(triangles_[0]) +
         planes_.capacity() * sizeof(Triangle) + tree_.memory_bytes();
}

SurfaceGodObject::SurfaceGodObject(const TriangleSurface& surface, double stiffness_N_per_mm)
    : surface_(&surface), stiffness_N_per_mm_(stiffness_N_per_mm) {}

void SurfaceGodObject::reset(const Vec3& p) {
  q_ = p;
  last_p_ = p;
  active_count_ = 0;
}

// Does segment a->b enter the solid through triangle t (from its front side,
// within the tolerance; edges and vertices count), earlier than `best`?
void SurfaceGodObject::consider(std::int32_t t, const Vec3& a, const Vec3& b, Hit& best) const {
  for (int k = 0; k < active_count_; ++k) {
    if (active_[k] == t) return;
  }
  const double tolerance = surface_->tolerance();
  const TriangleSurface::Triangle& tri = surface_->triangle(t);
  const double d0 = dot(tri.normal, a) - tri.offset;
  const double d1 = dot(tri.normal, b) - tri.offset;
  if (!(d0 >= -tolerance && d1 < -tolerance && d1 < d0)) return;
  const double s = d0 <= 0.0 ? 0.0 : d0 / (d0 - d1);
  if (s > best.parameter || (s == best.parameter && d1 >= best.target_depth)) return;
  const Vec3 c = a + (b - a) * s;
  for (int k = 0; k < 3; ++k) {
    if (dot(tri.edge_normal[k], c) - tri.edge_offset[k] < -tolerance) return;
  }
  best = {t, s, d1};
}

// The point nearest p on every active plane: x = p - N^T lambda with
// (N N^T) lambda = N p - offsets (Zilles and Salisbury's Lagrange multipliers).
Vec3 SurfaceGodObject::constrained_target(const Vec3& p) const {
  std::array<Vec3, kMaxConstraints> n{};
  std::array<double, kMaxConstraints> r{};
  int m = 0;
  for (int k = 0; k < active_count_; ++k) {
    const TriangleSurface::Triangle& tri = surface_->triangle(active_[k]);
    // A plane (nearly) parallel to one already kept adds nothing solvable.
    bool parallel = false;
    for (int j = 0; j < m; ++j) parallel = parallel || norm(cross(n[j], tri.normal)) < 1e-9;
    if (parallel) continue;
    n[m] = tri.normal;
    r[m] = dot(tri.normal, p) - tri.offset;
    ++m;
  }
  if (m == 3 && std::abs(dot(n[0], cross(n[1], n[2]))) < 1e-9) m = 2;
  if (m == 0) return p;
  if (m == 1) return p - n[0] * r[0];
  if (m == 2) {
    const double g01 = dot(n[0], n[1]);
    const double det = 1.0 - g01 * g01;
    const double l0 = (r[0] - g01 * r[1]) / det;
    const double l1 = (r[1] - g01 * r[0]) / det;
    return p - n[0] * l0 - n[1] * l1;
  }
  // Three planes meet in one point: solve N x = offsets by Cramer's rule.
  const Vec3 c12 = cross(n[1], n[2]);
  const Vec3 c20 = cross(n[2], n[0]);
  const Vec3 c01 = cross(n[0], n[1]);
  const double det = dot(n[0], c12);
  const std::array<double, 3> offsets{dot(n[0], p) - r[0], dot(n[1], p) - r[1],
                                      dot(n[2], p) - r[2]};
  return (c12 * offsets[0] + c20 * offsets[1] + c01 * offsets[2]) / det;
}

int SurfaceGodObject::step(const Vec3& p) {
  last_p_ = p;
  active_count_ = 0;
  int tested = 0;
  Vec3 target = p;
  for (int pass = 0; pass <= kMaxConstraints; ++pass) {
    Hit best;
    if (surface_->uses_tree()) {
      surface_->tree().for_each_on_segment(q_, target, surface_->tolerance(), [&](std::int32_t t) {
        ++tested;
        consider(t, q_, target, best);
      });
    } else {
      const std::int32_t count = surface_->triangle_count();
      for (std::int32_t t = 0; t < count; ++t) consider(t, q_, target, best);
      tested += count;
    }
    if (best.triangle < 0) {
      q_ = target;
      break;
    }
    const TriangleSurface::Triangle& tri = surface_->triangle(best.triangle);
    Vec3 c = q_ + (target - q_) * best.parameter;
    // Exactly onto the plane it hit, never a rounding error behind it.
    const double d = dot(tri.normal, c) - tri.offset;
    if (d < 0.0) c = c - tri.normal * d;
    q_ = c;
    if (active_count_ == kMaxConstraints) break;
    active_[active_count_++] = best.triangle;
    target = constrained_target(p);
  }
  return tested;
}

}  // namespace hapticut::baselines
