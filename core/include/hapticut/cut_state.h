// CutState: which tets a blade has cut, one byte a tet, for one loaded scene
// (docs/decisions.md, "Cut memory"). The Space stays immutable and shared;
// the cut state is what a session's strokes change. A cut tet of a material
// with a cut_to acts as that material from the next tick on
// (Space::material_of_tet); without a cut_to it acts as before.
//
// The rule for cutting (Blade::step, after every tick; docs/decisions.md,
// "Cut memory"): a tet of cuttable material (drag, viscous, membrane: the
// tet's own material decides) is cut once one of a blade's ideal points has
// been in it and has left it: the tet the point's place owned at the start
// of the tick (cut_left_behind), and every tet whose inside the point's chord
// over the tick crosses (cut_along: the thin layers one tick passes, above
// all a membrane broken through at once); and a drag or viscous tet is cut
// once the edge between two neighbouring ideal points has lain across it
// and left it (cut_left_by_edge), so a stroke cuts the sheet its edge
// sweeps, not only the lines its points trace. These are the tets the bake's cut
// surface takes from the recorded proxies (core/hapticut/cut_surface.py,
// cutting_tets: a TET proxy in a tet of cuttable material), once the point
// has moved on. A point feels what it cuts only after leaving it: the tet it
// is in keeps its own material, so the first stroke feels the uncut tissue.
// A rigid blade's point seated on the skin it has not broken cuts nothing.
// The set only grows and follows from the places alone: the same ticks from
// the same reset_cuts() give the same bytes.
//
// Allocates once, in the constructor; mark, reset_cuts and the reads never do.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "hapticut/proxy_place.h"
#include "hapticut/vec3.h"

namespace hapticut {

class Space;

class CutState {
 public:
  // Nothing cut, one byte for every tet of `space` (kept alive by the state).
  explicit CutState(std::shared_ptr<const Space> space);

  // Whether tet t has been cut (0 or 1): the byte the walk's lookup reads.
  std::uint8_t cut(std::int32_t t) const { return cut_[t]; }
  // Cuts the tets of cuttable material the chord a -> b passes through the
  // inside of and b lies outside, walking from `start_tet` (whose closure
  // holds a) through the faces it leaves by; stops at b's tet, where it
  // leaves the mesh, and after kMaxChordTets tets. Returns the tets newly
  // cut. Never allocates.
  int cut_along(std::int32_t start_tet, const Vec3& a, const Vec3& b);
  static constexpr int kMaxChordTets = 256;
  // The stretch of the edge between two neighbouring ideal points, at a0, b0
  // when the tick began and a1, b1 now: cuts the drag and viscous tets whose
  // inside it crossed between the points' own tets and that it has left
  // (the stretch now does not touch them, and neither point is in one). So
  // the edge cuts the sheet it sweeps, not only its points' paths, and only
  // behind it: a point of the blade that goes on into a tet the stretch lay
  // across still feels it uncut. A membrane is cut by points alone (a point
  // breaks it). Returns the tets newly cut. Never allocates.
  int cut_left_by_edge(const ProxyPlace& a0, const ProxyPlace& b0, const ProxyPlace& a1,
                       const ProxyPlace& b1);
  // The most tets a stretch between two points is followed through.
  static constexpr int kMaxEdgeTets = 32;
  // A point that was in tissue at `start` (its owner tet's own material
  // cuttable) and is now at `now` cuts its owner once `now` has left the
  // owner's closure, and, when `start` held it on a face, edge or vertex,
  // the drag and viscous tets round it that `now` has left: a drag point
  // often ends its ticks on faces and edges, where no chord is inside any
  // tet, and the tissue it has passed is cut, not the tissue ahead that
  // holds it (nor the tet it is still in: what it cuts, it feels from when
  // it has left it). A membrane is cut only from inside: a TET point on its
  // face has not broken it. Returns the tets newly cut. Never allocates.
  int cut_left_behind(const ProxyPlace& start, const Vec3& now);
  // Uncuts every tet (a new stroke on fresh tissue). Never allocates.
  void reset_cuts();
  // Uncuts every tet, then cuts `tets` in their order (a saved cut set, or a
  // recording's cuts before its first tick). Throws std::invalid_argument,
  // naming the entry, for a tet out of range, one given twice, or one whose
  // own material is never cut; then the cuts are as they were. Allocates
  // (a load's, not the tick's).
  void set_cuts(std::span<const std::int32_t> tets);

  // One byte per tet, 1 where cut: what a recording or a save would copy.
  std::span<const std::uint8_t> bytes() const { return cut_; }
  // Tets cut since the last reset_cuts.
  std::int64_t cut_count() const { return cut_count_; }
  // Changes with every reset_cuts or set_cuts: a reader of cut_order that
  // has the same generation may append to what it read before.
  std::uint32_t generation() const { return generation_; }
  // The cut tets in the order they were cut: what the servo streams, records
  // and saves, so that a reader rebuilds the set by appending.
  std::span<const std::int32_t> cut_order() const {
    return {order_.data(), static_cast<std::size_t>(cut_count_)};
  }
  // The cut tets in increasing order (allocates; not for the tick).
  std::vector<std::int32_t> cut_tets() const;
  const Space& space() const { return *space_; }

 private:
  // Cuts tet t if not cut yet, its own material is cuttable and x lies inside
  // it by more than the tolerance.
  bool cut_if_inside(std::int32_t t, const Vec3& x);
  // The tets whose inside the segment a -> b crosses, from `start_tet`
  // (whose closure holds a) to b's, at most kMaxEdgeTets, into `out` (a
  // stretch along a face crosses neither side). Returns how many.
  int tets_crossed(std::int32_t start_tet, const Vec3& a, const Vec3& b,
                   std::array<std::int32_t, kMaxEdgeTets>& out) const;
  // Marks tet t cut (not cut yet) and appends it to the order.
  void mark(std::int32_t t);

  std::shared_ptr<const Space> space_;
  std::vector<std::uint8_t> cut_;
  std::vector<std::int32_t> order_;  // One entry a tet: the first cut_count_ are cut, in order.
  std::int64_t cut_count_ = 0;
  std::uint32_t generation_ = 0;
};

}  // namespace hapticut
