// The rigid blade's swept narrow phase: does the surface a stretch of the
// edge sweeps between two poses meet rigid material? A closed rigid feature
// that passes through that surface without crossing its border (the two
// points' walks and the stretch at both poses, which the blade walks anyway)
// must have an edge of its surface crossing it, however thin the feature: so
// the edges of the rigid surface near the motion are intersected with it (the
// classic edge-edge continuous test). The earliest hit along the motion
// becomes a contact plane like a walk's.
//
// The motion of a stretch is a ruled patch: each end moves along its path and
// the stretch stays straight. It is taken as pieces, each a bilinear patch
// between two poses cut into two triangles; the caller chooses the pieces so
// that a turn's arc stays within its bound of the pieces' chords
// (swept_pieces). Never allocates after construction.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "hapticut/aabb_tree.h"
#include "hapticut/geometry.h"
#include "hapticut/space.h"

namespace hapticut {

// The edges of the rigid material's surface: an edge of a rigid tet that is
// also an edge of a tet of another model or of the mesh's boundary. Edges
// wholly inside rigid material are left out: a feature that meets a patch
// crosses it with an edge of its surface.
class RigidSurfaceEdges {
 public:
  explicit RigidSurfaceEdges(const Space& space);

  std::size_t size() const { return segments_.size(); }
  const std::array<Vec3, 2>& segment(std::int32_t k) const { return segments_[k]; }
  std::int32_t mesh_edge(std::int32_t k) const { return mesh_edges_[k]; }
  // Which side of the plane through edge k with this normal the rigid tets
  // around the edge lie on: +1 or -1; 0 when they lie on both sides (the
  // plane cuts into the material, so it supports nothing there) or on it.
  // `rigid_tet` gets one of those tets (its material gives the friction).
  int material_side(std::int32_t k, const Vec3& normal, double tolerance_mm,
                    std::int32_t& rigid_tet) const;
  const AabbTree& tree() const { return tree_; }

 private:
  const Space* space_;  // The Space outlives the blade that owns this.
  std::vector<std::array<Vec3, 2>> segments_;
  std::vector<std::int32_t> mesh_edges_;
  AabbTree tree_;
};

struct SweptHit {
  bool hit = false;
  double motion = 1.0;  // Where along the motion (0 at the start poses, 1 at the end).
  double along = 0.0;   // Where along the stretch (0 at its first point, 1 at its second).
  // The plane through the rigid edge that runs along the stretch, its normal
  // away from the material around the edge (which lies wholly on one side:
  // where a moving segment first touches a solid, the plane through the
  // segment and the solid's edge supports the solid).
  Plane contact;
  std::int32_t wall_tet = kNoTet;  // A rigid tet at the edge.
  std::int32_t mesh_edge = -1;     // The rigid edge, as the tet mesh numbers it.
};

// The earliest rigid surface edge crossing the bilinear patch swept by the
// stretch a0 -> b0 moving to a1 -> b1 (each end along a straight chord);
// `motion_from` and `motion_to` map the patch's parameter onto the whole
// motion's. A crossing counts only where that plane supports the material
// around the edge (a crossing of another edge comes after a first touch of a
// supporting one) and the stretch moves into the material's side of it by
// more than `tolerance_mm` (a patch that slides along an edge, or leaves it,
// crosses it only within rounding).
SweptHit sweep_stretch(const RigidSurfaceEdges& edges, const Vec3& a0, const Vec3& b0,
                       const Vec3& a1, const Vec3& b1, double motion_from, double motion_to,
                       double tolerance_mm);

// The same test over the given edges only: a broad phase the caller ran once
// for the whole blade's motion (any edge the patch can cross among them).
SweptHit sweep_stretch_among(const RigidSurfaceEdges& edges,
                             std::span<const std::int32_t> candidates, const Vec3& a0,
                             const Vec3& b0, const Vec3& a1, const Vec3& b1, double motion_from,
                             double motion_to, double tolerance_mm);

// How many pieces a motion whose edge turns by `turn_rad` is cut into, so that
// the path of any sample (at most length_mm from the start) departs from the
// pieces' chords by at most deviation_mm: a turn by theta moves a sample on an
// arc whose chord it leaves by at most r theta^2 / 8. At most kMaxSweptPieces.
int swept_pieces(double turn_rad, double length_mm, double deviation_mm);
inline constexpr int kMaxSweptPieces = 64;

}  // namespace hapticut
