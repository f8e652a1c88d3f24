// A bounding-volume hierarchy over axis-aligned boxes, built once and queried
// without allocation. Used for the boundary faces (entering the mesh from
// OUTSIDE is not linear in their number) and for locating a point's tet.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "hapticut/vec3.h"

namespace hapticut {

struct Aabb {
  Vec3 lo{1e300, 1e300, 1e300};
  Vec3 hi{-1e300, -1e300, -1e300};

  void grow(const Vec3& p);
  void grow(const Aabb& b);
  bool contains(const Vec3& p, double pad) const;
  bool overlaps(const Aabb& other) const {
    return lo.x <= other.hi.x && other.lo.x <= hi.x && lo.y <= other.hi.y && other.lo.y <= hi.y &&
           lo.z <= other.hi.z && other.lo.z <= hi.z;
  }
  // Slab test: does the segment a->b touch the box inflated by pad?
  bool hits_segment(const Vec3& a, const Vec3& inv_dir, const Vec3& dir, double pad) const;
};

namespace detail {
// One axis of the slab test: narrows [t_enter, t_exit] to where the segment
// a + t dir is within [lo, hi] on this axis. An axis the segment does not move
// along (dir = 0, or so small that 1 / dir overflows) must contain a itself.
inline bool clip_slab(double a, double inv_dir, double dir, double lo, double hi, double& t_enter,
                      double& t_exit) {
  if (dir == 0.0 || !(std::abs(inv_dir) <= std::numeric_limits<double>::max())) {
    return a >= lo && a <= hi;
  }
  const double t0 = (lo - a) * inv_dir;
  const double t1 = (hi - a) * inv_dir;
  t_enter = std::max(t_enter, std::min(t0, t1));
  t_exit = std::min(t_exit, std::max(t0, t1));
  return t_enter <= t_exit;
}
}  // namespace detail

// Slab test on the parameter range [0, 1]; inline, as the tree walks call it per node.
inline bool Aabb::hits_segment(const Vec3& a, const Vec3& inv_dir, const Vec3& dir,
                               double pad) const {
  double t_enter = 0.0;
  double t_exit = 1.0;
  return detail::clip_slab(a.x, inv_dir.x, dir.x, lo.x - pad, hi.x + pad, t_enter, t_exit) &&
         detail::clip_slab(a.y, inv_dir.y, dir.y, lo.y - pad, hi.y + pad, t_enter, t_exit) &&
         detail::clip_slab(a.z, inv_dir.z, dir.z, lo.z - pad, hi.z + pad, t_enter, t_exit);
}

class AabbTree {
 public:
  static constexpr int kMaxDepth = 64;

  AabbTree() = default;
  explicit AabbTree(const std::vector<Aabb>& item_boxes);

  // Calls visit(item) for every item whose box (inflated by pad) contains p.
  template <class Visit>
  void for_each_containing(const Vec3& p, double pad, Visit&& visit) const;
  // Calls visit(item) for every item whose box (inflated by pad) the segment a->b touches.
  template <class Visit>
  void for_each_on_segment(const Vec3& a, const Vec3& b, double pad, Visit&& visit) const;

  // Calls visit(item) for every item whose box overlaps `box`.
  template <class Visit>
  void for_each_overlapping(const Aabb& box, Visit&& visit) const;
  // The same while visit(item) returns true; false once it has returned false
  // (the walk then stops).
  template <class Visit>
  bool for_each_overlapping_while(const Aabb& box, Visit&& visit) const;

  std::size_t node_count() const { return nodes_.size(); }
  std::size_t memory_bytes() const;

 private:
  struct Node {
    Aabb box;
    std::int32_t first =
        0;  // Leaf: first index in items_; inner: left child (right = first + 1... see build).
    std::int32_t count = 0;  // Leaf: item count; inner: 0.
    std::int32_t right = 0;  // Inner: right child.
  };
  std::int32_t build(const std::vector<Aabb>& boxes, std::vector<Vec3>& centres, int begin, int end,
                     int depth);
  // Calls visit(item) for every item in a leaf whose box, and every box above
  // it, touches(box) accepts.
  template <class Touches, class Visit>
  void for_each_where(Touches&& touches, Visit&& visit) const;

  std::vector<Node> nodes_;
  std::vector<std::int32_t> items_;
};

template <class Touches, class Visit>
void AabbTree::for_each_where(Touches&& touches, Visit&& visit) const {
  if (nodes_.empty()) return;
  // Not zeroed: only entries below top are read, and a walk need not pay to clear it.
  std::array<std::int32_t, kMaxDepth + 1> stack;  // NOLINT(cppcoreguidelines-pro-type-member-init)
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[stack[--top]];
    if (!touches(node.box)) continue;
    if (node.count > 0) {
      for (std::int32_t k = 0; k < node.count; ++k) visit(items_[node.first + k]);
    } else {
      stack[top++] = node.first;
      stack[top++] = node.right;
    }
  }
}

template <class Visit>
void AabbTree::for_each_containing(const Vec3& p, double pad, Visit&& visit) const {
  for_each_where([&](const Aabb& box) { return box.contains(p, pad); }, visit);
}

template <class Visit>
void AabbTree::for_each_on_segment(const Vec3& a, const Vec3& b, double pad, Visit&& visit) const {
  const Vec3 dir = b - a;
  const Vec3 inv_dir{1.0 / dir.x, 1.0 / dir.y, 1.0 / dir.z};
  for_each_where([&](const Aabb& box) { return box.hits_segment(a, inv_dir, dir, pad); }, visit);
}

template <class Visit>
void AabbTree::for_each_overlapping(const Aabb& box, Visit&& visit) const {
  for_each_where([&](const Aabb& node_box) { return node_box.overlaps(box); }, visit);
}

template <class Visit>
bool AabbTree::for_each_overlapping_while(const Aabb& box, Visit&& visit) const {
  bool going = true;
  for_each_where([&](const Aabb& node_box) { return going && node_box.overlaps(box); },
                 [&](std::int32_t item) { going = going && visit(item); });
  return going;
}

}  // namespace hapticut
