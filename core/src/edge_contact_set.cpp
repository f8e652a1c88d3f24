#include "hapticut/edge_contact_set.h"

#include <algorithm>
#include <cmath>

namespace hapticut {

bool EdgeContactSet::add(double fraction, const Plane& plane, double same_offset_mm,
                         const ContactFeature& feature) {
  for (int j = 0; j < plane_count_; ++j) {
    HeldPlane& held = planes_[j];
    if (squared_norm(held.plane.normal - plane.normal) <= kSameNormal * kSameNormal &&
        std::abs(held.plane.offset - plane.offset) <= same_offset_mm) {
      if (plane_before(plane, held.plane)) held.plane = plane;
      // An extreme met again keeps what it met last (nearer the pose the
      // tick ends on); only a wider range changes the constraints.
      if (fraction <= held.least_fraction) {
        if (fraction < held.least_fraction) ++changes_;
        held.least_fraction = fraction;
        held.least_feature = feature;
      }
      if (fraction >= held.greatest_fraction) {
        if (fraction > held.greatest_fraction) ++changes_;
        held.greatest_fraction = fraction;
        held.greatest_feature = feature;
      }
      return true;
    }
  }
  if (full()) return false;
  planes_[plane_count_++] = {plane, fraction, fraction, feature, feature};
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
