// Force shading of a rigid blade (docs/decisions.md, "The rigid blade"): the
// contact planes' normals are shaded as a point proxy's face normal is, so the
// force on a faceted round bone follows the surface the facets approximate.
//
// The pose is final: the contacts touching it hold the springs' force F. F is
// split into a push along their normals, sum_j w_j n_j with w_j >= 0 (the
// least-squares split, NNLS), and the rest (what friction holds across them).
// Each touching plane's normal takes the shaded normal where the edge touches
// the surface the normals describe; the push then points along
// sum_j w_j ñ_j and keeps its size; the rest is kept. No push (F pulls off
// the contacts): F unchanged.
#include <algorithm>
#include <array>
#include <cmath>
#include <span>

#include "hapticut/blade.h"
#include "hapticut/least_distance.h"

namespace hapticut {

namespace {

// The shaded unit normal where the sample whose device point is `device`
// presses on `plane`, from what the sample met: a face of the rigid surface by
// the FACE path of ForceShading::shade, as a point proxy held there with that
// device point (its contact point found as the path finds it); a rigid
// surface edge (a ridge the edge rests on) by the faces through it
// (ForceShading::edge_contact_normal). The plane's own normal where shading
// names nothing there.
Vec3 shaded_normal(const ForceShading& shading, const Space& space, const ContactFeature& feature,
                   const Plane& plane, const Vec3& device) {
  const double depth = -plane.signed_distance(device);
  const Vec3 on_plane = device + plane.normal * depth;
  Vec3 normal;
  if (feature.kind == ContactFeature::Kind::Face) {
    // The FACE path on a pure push answers the shaded normal times the push;
    // the push is the point spring's at that depth (at least the tolerance's,
    // so that it is not zero), which puts the path's device point at `device`.
    const double push_N = std::max(depth, space.tolerance()) * space.settings().stiffness_N_per_mm;
    const ProxyPlace place{ProxyState::Face, feature.index, feature.face, on_plane};
    normal = shading.shade(place, plane.normal * push_N) / push_N;
  } else if (feature.kind == ContactFeature::Kind::Edge) {
    normal = shading.edge_contact_normal(feature.index, device);
  }
  const double size = norm(normal);
  if (!(size > 0.0) || !(dot(normal, plane.normal) > 0.0)) return plane.normal;
  return normal / size;
}

Vec3 unit_or(const Vec3& v, const Vec3& fallback) {
  const double size = norm(v);
  return size > 0.0 && std::isfinite(size) ? v / size : fallback;
}

}  // namespace

void Blade::shade_rigid_force(Vec3& force_N, Vec3& torque_N_mm) const {
  const std::span<const EdgeContactSet::HeldPlane> held = contacts_.planes();
  if (held.empty() || !shading_) return;
  const double touching = touching_distance();
  const EdgePose device = device_edge();
  // Across the device's edge, not the ideal one's: the facets tilt the ideal
  // edge a little where the surface they approximate would not.
  const Vec3& along = device.direction;
  std::array<NonnegativeColumn, EdgeContactSet::kMaxPlanes> normals{};
  std::array<Vec3, EdgeContactSet::kMaxPlanes> shaded{};
  std::array<double, EdgeContactSet::kMaxPlanes> fractions{};
  int count = 0;
  for (const EdgeContactSet::HeldPlane& h : held) {
    const bool least_touches =
        h.plane.signed_distance(ideal_edge_.point(h.least_fraction, length_mm_)) <= touching;
    const bool greatest_touches =
        h.greatest_fraction > h.least_fraction &&
        h.plane.signed_distance(ideal_edge_.point(h.greatest_fraction, length_mm_)) <= touching;
    if (!least_touches && !greatest_touches) continue;
    const Vec3 least = shaded_normal(*shading_, *space_, h.least_feature, h.plane,
                                     device.point(h.least_fraction, length_mm_));
    double fraction = h.least_fraction;
    Vec3 normal = least;
    if (greatest_touches) {
      const Vec3 greatest = shaded_normal(*shading_, *space_, h.greatest_feature, h.plane,
                                          device.point(h.greatest_fraction, length_mm_));
      fraction = h.greatest_fraction;
      normal = greatest;
      // The edge lies on the plane from one end to the other. Where the
      // normals lean apart along it (the surface they describe is convex
      // there), that surface touches the edge where its normal is across the
      // device's edge: there, the normals taken as linear between the ends.
      // Where they lean together (concave), it holds the edge at both ends alike.
      const double least_lean = dot(least, along);
      const double greatest_lean = dot(greatest, along);
      if (least_touches && least_lean <= 0.0 && greatest_lean >= 0.0) {
        const double spread = greatest_lean - least_lean;
        const double t = spread > 0.0 ? -least_lean / spread : 0.5;
        fraction = h.least_fraction + t * (h.greatest_fraction - h.least_fraction);
        normal = unit_or(least + (greatest - least) * t, h.plane.normal);
      } else if (least_touches && least_lean > 0.0 && greatest_lean < 0.0) {
        fraction = 0.5 * (h.least_fraction + h.greatest_fraction);
        normal = unit_or(least + greatest, h.plane.normal);
      } else if (least_touches && std::abs(least_lean) < std::abs(greatest_lean)) {
        // Leaning one way all along: the end nearer across the edge.
        fraction = h.least_fraction;
        normal = least;
      }
    }
    shaded[count] = normal;
    fractions[count] = fraction;
    normals[count] = {h.plane.normal.x, h.plane.normal.y, h.plane.normal.z};
    ++count;
  }
  if (count == 0) return;
  std::array<double, EdgeContactSet::kMaxPlanes> weights{};
  solve_nonnegative_least_squares(3, std::span(normals.data(), count),
                                  {force_N.x, force_N.y, force_N.z},
                                  std::span(weights.data(), count));
  Vec3 push;
  Vec3 shaded_push;
  for (int j = 0; j < count; ++j) {
    push += Vec3{normals[j][0], normals[j][1], normals[j][2]} * weights[j];
    shaded_push += shaded[j] * weights[j];
  }
  const double push_size = norm(push);
  const double shaded_size = norm(shaded_push);
  if (!(push_size > 0.0) || !(shaded_size > 0.0) || !std::isfinite(push_size + shaded_size)) {
    return;
  }
  // Each plane's share of the change acts where the edge touches it: the
  // torque about the tool origin takes it at that sample's device point, as
  // the springs' torque takes each point's force.
  const double scale = push_size / shaded_size;
  for (int j = 0; j < count; ++j) {
    if (weights[j] == 0.0) continue;
    const Vec3 change =
        (shaded[j] * scale - Vec3{normals[j][0], normals[j][1], normals[j][2]}) * weights[j];
    force_N += change;
    torque_N_mm += cross(world_lever_ + world_span_ * fractions[j], change);
  }
}

}  // namespace hapticut
