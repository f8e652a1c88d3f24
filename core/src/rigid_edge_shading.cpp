// Force shading of a rigid blade (docs/decisions.md, "The rigid blade"): the
// contact planes' normals are shaded as a point proxy's face normal is, so the
// force on a faceted round bone follows the surface the facets approximate.
//
// The pose is final: the contacts touching it hold the springs' force F. F is
// split into a push along their normals, sum_j w_j n_j with w_j >= 0 (the
// least-squares split, NNLS), and the rest (what friction holds across them),
// which is kept. Touching planes next to one another along the edge whose
// normals lie within the shading's crease angle are one contact with one
// smooth surface: it takes the shaded normal where that surface touches the
// edge, and the push of its planes keeps its length. The whole push then
// keeps its length too. No push (F pulls off the contacts): F unchanged.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <span>

#include "hapticut/least_distance.h"
#include "hapticut/rigid_edge.h"

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
  Vec3 normal;
  if (feature.kind == ContactFeature::Kind::Face) {
    // The FACE path on a pure push answers the shaded normal times the push;
    // the push is the point spring's at that depth (at least the tolerance's,
    // so that it is not zero), which puts the path's device point at `device`.
    const double depth = -plane.signed_distance(device);
    const double push_N = std::max(depth, space.tolerance()) * space.settings().stiffness_N_per_mm;
    const ProxyPlace place{ProxyState::Face, feature.index, feature.face,
                           device + plane.normal * depth};
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

// A sample of the surface along the edge: where, its shaded normal, and
// whether the edge touches the surface there.
struct Sample {
  double fraction = 0.0;
  Vec3 normal;
  bool touching = false;
};

// Where the smooth surface the samples' normals describe touches the edge
// (direction `along`), from samples sorted by fraction (those at one fraction
// merged): where the normals lean apart along the edge (convex), the point
// where the normal is across it, the normals taken as linear between samples
// (of several, the one nearest where the edge touches); elsewhere (concave,
// or leaning one way all along) the touching samples' mean.
Sample touching_point(std::span<const Sample> samples, const Vec3& along) {
  const std::size_t n = samples.size();
  const auto from_touching = [&](double fraction) {
    double least = std::numeric_limits<double>::infinity();
    for (const Sample& s : samples) {
      if (s.touching) least = std::min(least, std::abs(s.fraction - fraction));
    }
    return least;
  };
  Sample best;
  double best_distance = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i + 1 < n; ++i) {
    const double a = dot(samples[i].normal, along);
    const double b = dot(samples[i + 1].normal, along);
    if (!(a <= 0.0 && b >= 0.0)) continue;
    const double t = b > a ? -a / (b - a) : 0.5;
    const double fraction =
        samples[i].fraction + t * (samples[i + 1].fraction - samples[i].fraction);
    const double distance = from_touching(fraction);
    if (distance < best_distance) {
      best_distance = distance;
      const Vec3 normal = samples[i].normal + (samples[i + 1].normal - samples[i].normal) * t;
      best = {fraction, unit_or(normal, samples[i].normal), true};
    }
  }
  if (best_distance < std::numeric_limits<double>::infinity()) return best;
  Vec3 sum;
  double fraction_sum = 0.0;
  int count = 0;
  for (const Sample& s : samples) {
    if (!s.touching) continue;
    sum += s.normal;
    fraction_sum += s.fraction;
    ++count;
  }
  return {fraction_sum / std::max(count, 1), unit_or(sum, samples[0].normal), true};
}

}  // namespace

void RigidEdge::shade_force(const ForceShading& shading, const EdgePose& device, const Vec3& origin,
                            Vec3& force_N, Vec3& torque_N_mm) const {
  const std::span<const EdgeContactSet::HeldPlane> held = contacts_.planes();
  if (held.empty()) return;
  constexpr int kMax = EdgeContactSet::kMaxPlanes;
  const int planes = static_cast<int>(held.size());
  const double touching = touching_distance();
  // Every plane met samples the surface along the edge at both its ends; the
  // touching ones (within the support's reach at an end) hold the push.
  std::array<Sample, 2 * kMax> samples{};
  std::array<int, 2 * kMax> sample_plane{};
  std::array<bool, kMax> holds{};
  int sample_count = 0;
  for (int j = 0; j < planes; ++j) {
    const EdgeContactSet::HeldPlane& h = held[j];
    h.for_each_end([&](double fraction, const ContactFeature& feature) {
      const bool touches =
          h.plane.signed_distance(ideal_edge_.point(fraction, length_mm_)) <= touching;
      samples[sample_count] = {
          fraction,
          shaded_normal(shading, *space_, feature, h.plane, device.point(fraction, length_mm_)),
          touches};
      sample_plane[sample_count++] = j;
      holds[j] = holds[j] || touches;
    });
  }
  // Contacts: planes joined when next to one another along the edge (within
  // a point spacing) and within the crease angle, transitively: one smooth
  // surface, as the shading sees it.
  std::array<int, kMax> contact{};
  for (int j = 0; j < planes; ++j) contact[j] = j;
  const double spacing = fractions_.size() > 1 ? 1.0 / double(fractions_.size() - 1) : 0.0;
  for (int j = 0; j < planes; ++j) {
    for (int k = j + 1; k < planes; ++k) {
      const double gap = std::max(held[j].least_fraction, held[k].least_fraction) -
                         std::min(held[j].greatest_fraction, held[k].greatest_fraction);
      if (contact[j] == contact[k] || !(gap <= spacing * (1.0 + 1e-9)) ||
          !(dot(held[j].plane.normal, held[k].plane.normal) > ForceShading::kCreaseCosine)) {
        continue;
      }
      const int from = contact[k];
      for (int m = 0; m < planes; ++m) {
        if (contact[m] == from) contact[m] = contact[j];
      }
    }
  }
  // The push: F split along the holding planes' normals.
  std::array<NonnegativeColumn, kMax> columns{};
  std::array<int, kMax> column_plane{};
  int column_count = 0;
  for (int j = 0; j < planes; ++j) {
    if (!holds[j]) continue;
    const Vec3& n = held[j].plane.normal;
    columns[column_count] = {n.x, n.y, n.z};
    column_plane[column_count++] = j;
  }
  if (column_count == 0) return;
  std::array<double, kMax> weights{};
  solve_nonnegative_least_squares(3, std::span(columns.data(), column_count),
                                  {force_N.x, force_N.y, force_N.z},
                                  std::span(weights.data(), column_count));
  // Each contact's push, its touching point and shaded normal.
  std::array<Vec3, kMax> push{};
  for (int c = 0; c < column_count; ++c) {
    const int j = column_plane[c];
    push[contact[j]] += held[j].plane.normal * weights[c];
  }
  std::array<Sample, kMax> shaded{};
  std::array<Sample, 2 * kMax> own{};
  Vec3 total_push;
  Vec3 total_shaded;
  for (int c = 0; c < planes; ++c) {
    if (!(norm(push[c]) > 0.0)) continue;
    // Its samples in order along the edge, those at one fraction merged (the
    // touching ones only, where one touches: a plane the edge has left
    // describes the surface there less well).
    int count = 0;
    for (int s = 0; s < sample_count; ++s) {
      if (contact[sample_plane[s]] != c) continue;
      int at = count;
      while (at > 0 && own[at - 1].fraction > samples[s].fraction) --at;
      if (at > 0 && own[at - 1].fraction == samples[s].fraction) {
        Sample& merged = own[at - 1];
        if (samples[s].touching && !merged.touching) {
          merged = samples[s];
        } else if (samples[s].touching == merged.touching) {
          merged.normal += samples[s].normal;
        }
        continue;
      }
      std::copy_backward(own.begin() + at, own.begin() + count, own.begin() + count + 1);
      own[at] = samples[s];
      ++count;
    }
    for (int s = 0; s < count; ++s) own[s].normal = unit_or(own[s].normal, held[c].plane.normal);
    shaded[c] = touching_point(std::span(own.data(), count), device.direction);
    total_push += push[c];
    total_shaded += shaded[c].normal * norm(push[c]);
  }
  const double push_size = norm(total_push);
  const double shaded_size = norm(total_shaded);
  if (!(push_size > 0.0) || !(shaded_size > 0.0) || !std::isfinite(push_size + shaded_size)) {
    return;
  }
  // Each contact's change acts where the edge touches it: the torque about
  // the tool origin takes it at that sample's device point, as the springs'
  // torque takes each point's force.
  const double scale = push_size / shaded_size;
  for (int c = 0; c < planes; ++c) {
    const double size = norm(push[c]);
    if (!(size > 0.0)) continue;
    const Vec3 change = shaded[c].normal * (size * scale) - push[c];
    force_N += change;
    torque_N_mm += cross(device.point(shaded[c].fraction, length_mm_) - origin, change);
  }
}

}  // namespace hapticut
