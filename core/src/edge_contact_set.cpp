#include "hapticut/edge_contact_set.h"

#include <algorithm>
#include <cmath>

namespace hapticut {

bool EdgeContactSet::add(double fraction, const Plane& plane, double same_offset_mm) {
  for (int j = 0; j < plane_count_; ++j) {
    HeldPlane& held = planes_[j];
    if (squared_norm(held.plane.normal - plane.normal) <= kSameNormal * kSameNormal &&
        std::abs(held.plane.offset - plane.offset) <= same_offset_mm) {
      if (plane_before(plane, held.plane)) held.plane = plane;
      if (fraction < held.least_fraction) {
        held.least_fraction = fraction;
        ++changes_;
      } else if (fraction > held.greatest_fraction) {
        held.greatest_fraction = fraction;
        ++changes_;
      }
      return true;
    }
  }
  if (full()) return false;
  planes_[plane_count_++] = {plane, fraction, fraction};
  ++changes_;
  return true;
}

std::span<const EdgeContact> EdgeContactSet::constraints() {
  int count = 0;
  for (int j = 0; j < plane_count_; ++j) {
    const HeldPlane& held = planes_[j];
    constraints_[count++] = {held.least_fraction, held.plane};
    if (held.greatest_fraction > held.least_fraction) {
      constraints_[count++] = {held.greatest_fraction, held.plane};
    }
  }
  return {constraints_.data(), static_cast<std::size_t>(count)};
}

}  // namespace hapticut
