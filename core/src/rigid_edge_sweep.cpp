// RigidEdge's swept narrow phase over the whole edge (swept_stretch.h tests
// one stretch): a broad phase gathers the rigid surface's edges near a piece
// of the motion once, and the stretches, in order along the edge, test those
// that can reach them.
#include <algorithm>

#include "hapticut/rigid_edge.h"

namespace hapticut {

namespace {

// Rigid surface edges per stretch, at most, that the swept test's broad
// phase gathers for a piece of the motion.
constexpr std::size_t kBroadPhasePerStretch = 4;

}  // namespace

void RigidEdge::take_swept_hit(const SweptHit& hit, double f0, double f1, double& advance,
                               bool add_contacts) {
  const double fraction = f0 + hit.along * (f1 - f0);
  if (hit.motion < advance) {
    advance = hit.motion;
    earliest_hit_fraction_ = fraction;
  }
  if (add_contacts) {
    add_contact(fraction, hit.contact, hit.wall_tet,
                {ContactFeature::Kind::Edge, hit.mesh_edge, 0});
  }
}

bool RigidEdge::sweep_stretches_each(const EdgePose& first, const EdgePose& last, double from,
                                     double to, double& advance, bool add_contacts) {
  const std::size_t n = fractions_.size();
  const double tolerance = space_->tolerance();
  bool free = true;
  for (std::size_t i = 0; i + 1 < n; ++i) {
    const double f0 = fractions_[i];
    const double f1 = fractions_[i + 1];
    const SweptHit hit =
        sweep_stretch(*rigid_edges_, first.point(f0, length_mm_), first.point(f1, length_mm_),
                      last.point(f0, length_mm_), last.point(f1, length_mm_), from, to, tolerance);
    if (!hit.hit) continue;
    free = false;
    take_swept_hit(hit, f0, f1, advance, add_contacts);
  }
  return free;
}

bool RigidEdge::sweep_stretches(const EdgePose& first, const EdgePose& last, double from, double to,
                                double& advance, bool add_contacts) {
  if (!rigid_edges_ || rigid_edges_->size() == 0) return true;
  const std::size_t n = fractions_.size();
  const double tolerance = space_->tolerance();
  // The broad phase, once for the whole edge: the rigid surface's edges near
  // its motion, each with the span along the first pose's edge where it can
  // meet a stretch. A sample's move is a mix of the ends' moves, so it moves
  // along the edge by at most the larger of them.
  const Vec3 a0 = first.start_mm;
  const Vec3 b0 = first.point(1.0, length_mm_);
  const Vec3 a1 = last.start_mm;
  const Vec3 b1 = last.point(1.0, length_mm_);
  const Aabb box = motion_box(a0, b0, a1, b1, tolerance);
  const double reach = std::max(norm(a1 - a0), norm(b1 - b0)) + tolerance;
  // Where the surface's edges are small beside the motion (a fine mesh, a long
  // step) the stretches' own queries find fewer: past a few per stretch the
  // broad phase gives way to them.
  const std::size_t most = kBroadPhasePerStretch * (n - 1);
  swept_candidates_.clear();
  const bool broad = rigid_edges_->tree().for_each_overlapping_while(box, [&](std::int32_t k) {
    if (swept_candidates_.size() == most) return false;
    const auto& segment = rigid_edges_->segment(k);
    const double t0 = dot(segment[0] - a0, first.direction);
    const double t1 = dot(segment[1] - a0, first.direction);
    swept_candidates_.push_back({k, std::min(t0, t1) - reach, std::max(t0, t1) + reach});
    return true;
  });
  if (!broad) return sweep_stretches_each(first, last, from, to, advance, add_contacts);
  if (swept_candidates_.empty()) return true;
  // Along the edge in order: a candidate joins when the stretches reach its
  // span and leaves once they have passed it.
  std::sort(swept_candidates_.begin(), swept_candidates_.end(),
            [](const SweptCandidate& a, const SweptCandidate& b) {
              return a.least_mm < b.least_mm || (a.least_mm == b.least_mm && a.edge < b.edge);
            });
  std::size_t next = 0;
  active_candidates_.clear();
  bool free = true;
  for (std::size_t i = 0; i + 1 < n; ++i) {
    const double f0 = fractions_[i];
    const double f1 = fractions_[i + 1];
    while (next < swept_candidates_.size() && swept_candidates_[next].least_mm <= f1 * length_mm_) {
      active_candidates_.push_back(swept_candidates_[next++]);
    }
    std::erase_if(active_candidates_,
                  [&](const SweptCandidate& c) { return c.greatest_mm < f0 * length_mm_; });
    if (active_candidates_.empty()) continue;
    stretch_candidates_.clear();
    for (const SweptCandidate& c : active_candidates_) stretch_candidates_.push_back(c.edge);
    const SweptHit hit =
        sweep_stretch_among(*rigid_edges_, stretch_candidates_, first.point(f0, length_mm_),
                            first.point(f1, length_mm_), last.point(f0, length_mm_),
                            last.point(f1, length_mm_), from, to, tolerance);
    if (!hit.hit) continue;
    free = false;
    take_swept_hit(hit, f0, f1, advance, add_contacts);
  }
  return free;
}

}  // namespace hapticut
