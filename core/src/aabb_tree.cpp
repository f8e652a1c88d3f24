#include "hapticut/aabb_tree.h"

#include <algorithm>
#include <numeric>

namespace hapticut {

namespace {
constexpr int kLeafSize = 4;
}

void Aabb::grow(const Vec3& p) {
  lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
  hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
}

void Aabb::grow(const Aabb& b) {
  grow(b.lo);
  grow(b.hi);
}

bool Aabb::contains(const Vec3& p, double pad) const {
  return p.x >= lo.x - pad && p.x <= hi.x + pad && p.y >= lo.y - pad && p.y <= hi.y + pad &&
         p.z >= lo.z - pad && p.z <= hi.z + pad;
}

AabbTree::AabbTree(const std::vector<Aabb>& item_boxes) {
  if (item_boxes.empty()) return;
  items_.resize(item_boxes.size());
  std::iota(items_.begin(), items_.end(), 0);
  std::vector<Vec3> centres(item_boxes.size());
  for (std::size_t i = 0; i < item_boxes.size(); ++i) {
    centres[i] = (item_boxes[i].lo + item_boxes[i].hi) * 0.5;
  }
  nodes_.reserve(2 * item_boxes.size() / kLeafSize + 2);
  build(item_boxes, centres, 0, static_cast<int>(item_boxes.size()), 0);
}

std::int32_t AabbTree::build(const std::vector<Aabb>& boxes, std::vector<Vec3>& centres, int begin,
                             int end, int depth) {
  const auto index = static_cast<std::int32_t>(nodes_.size());
  nodes_.push_back({});
  Aabb box;
  Aabb centre_box;
  for (int k = begin; k < end; ++k) {
    box.grow(boxes[items_[k]]);
    centre_box.grow(centres[items_[k]]);
  }
  nodes_[index].box = box;
  if (end - begin <= kLeafSize || depth >= kMaxDepth - 1) {
    nodes_[index].first = begin;
    nodes_[index].count = end - begin;
    return index;
  }
  const Vec3 extent = centre_box.hi - centre_box.lo;
  const int axis =
      extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
  const int middle = begin + (end - begin) / 2;
  std::nth_element(
      items_.begin() + begin, items_.begin() + middle, items_.begin() + end,
      [&](std::int32_t a, std::int32_t b) { return centres[a][axis] < centres[b][axis]; });
  const std::int32_t left = build(boxes, centres, begin, middle, depth + 1);
  const std::int32_t right = build(boxes, centres, middle, end, depth + 1);
  nodes_[index].first = left;
  nodes_[index].right = right;
  nodes_[index].count = 0;
  return index;
}

std::size_t AabbTree::memory_bytes() const {
  return nodes_.capacity() * sizeof(Node) + items_.capacity() * sizeof(std::int32_t);
}

}  // namespace hapticut
