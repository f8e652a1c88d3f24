// A bounding-volume hierarchy over axis-aligned boxes, built once and queried
// without allocation. Used for the boundary faces (entering the mesh from
// OUTSIDE is not linear in their number) and for locating a point's tet.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "hapticut/vec3.h"

namespace hapticut {

struct Aabb {
  Vec3 lo{1e300, 1e300, 1e300};
  Vec3 hi{-1e300, -1e300, -1e300};

  void grow(const Vec3& p);
  void grow(const Aabb& b);
  bool contains(const Vec3& p, double pad) const;
  // Slab test: does the segment a->b touch the box inflated by pad?
  bool hits_segment(const Vec3& a, const Vec3& inv_dir, const Vec3& dir, double pad) const;
};

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

  std::vector<Node> nodes_;
  std::vector<std::int32_t> items_;
};

template <class Visit>
void AabbTree::for_each_containing(const Vec3& p, double pad, Visit&& visit) const {
  if (nodes_.empty()) return;
  std::array<std::int32_t, kMaxDepth + 1> stack{};
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[stack[--top]];
    if (!node.box.contains(p, pad)) continue;
    if (node.count > 0) {
      for (std::int32_t k = 0; k < node.count; ++k) visit(items_[node.first + k]);
    } else {
      stack[top++] = node.first;
      stack[top++] = node.right;
    }
  }
}

template <class Visit>
void AabbTree::for_each_on_segment(const Vec3& a, const Vec3& b, double pad, Visit&& visit) const {
  if (nodes_.empty()) return;
  const Vec3 dir = b - a;
  const Vec3 inv_dir{1.0 / dir.x, 1.0 / dir.y, 1.0 / dir.z};
  std::array<std::int32_t, kMaxDepth + 1> stack{};
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[stack[--top]];
    if (!node.box.hits_segment(a, inv_dir, dir, pad)) continue;
    if (node.count > 0) {
      for (std::int32_t k = 0; k < node.count; ++k) visit(items_[node.first + k]);
    } else {
      stack[top++] = node.first;
      stack[top++] = node.right;
    }
  }
}

}  // namespace hapticut
