// The rigid blade's collision test: does the straight segment a -> b, started
// in a known tet, enter rigid material, and where first? It walks the tets the
// segment crosses (the proxy's exit rule, docs/method.md repair 1), and outside
// the mesh looks for the boundary face it enters through (the boundary tree).
// Never allocates; bounded work (kMaxSteps tets, then it reports a stop).
#pragma once

#include <cstdint>

#include "hapticut/geometry.h"
#include "hapticut/space.h"

namespace hapticut {

struct SegmentProbe {
  // The segment enters rigid material at `fraction` of the way (0 when a
  // starts on a rigid face and b lies beyond it).
  bool hit = false;
  // The walk used kMaxSteps without reaching b: treated as a stop at fraction
  // (no plane), so a caller never accepts a segment it did not verify.
  bool exhausted = false;
  double fraction = 1.0;
  // Where it hit: the face's plane with its normal out of the rigid material,
  // so the free side is signed_distance >= 0.
  Plane contact;
  // The wall's tet (its material gives the contact's friction), kNoTet when
  // exhausted.
  std::int32_t wall_tet = kNoTet;
  // The face it hit as seen from the tet the walk left through it (a face of
  // the rigid surface owned by a non-rigid tet, what force shading reads):
  // kNoTet when the segment entered from outside the mesh or was exhausted.
  std::int32_t owner_tet = kNoTet;
  std::int8_t owner_face = 0;
  // The tet holding b (within the tolerance) when nothing was hit, kNoTet when
  // b lies outside the mesh.
  std::int32_t end_tet = kNoTet;
};

inline constexpr int kSegmentProbeMaxSteps = 4096;

// What stops the segment: rigid material, or also a membrane (a membrane the
// point has not broken is a wall for the rigid blade).
enum class ProbeWalls : std::uint8_t { Rigid, RigidAndMembrane };

// start_tet must hold a (within the tolerance) and not be a wall, or be kNoTet
// with a outside the mesh.
// A membrane wall is a tet whose material acts as a membrane now, through `cuts`
// (Space::material_of_tet).
SegmentProbe probe_segment(const Space& space, std::int32_t start_tet, const Vec3& a, const Vec3& b,
                           ProbeWalls walls = ProbeWalls::Rigid, const CutState* cuts = nullptr);

// The tet a point lies in for the probe: a non-rigid tet holding it, kNoTet
// outside the mesh; `inside_rigid` when only rigid tets hold it.
std::int32_t locate_for_probe(const Space& space, const Vec3& p, bool& inside_rigid);

}  // namespace hapticut
