// The rigid blade's contact set, reduced per plane (a contact manifold, as
// Box2D's b2Manifold keeps at most two points per polygon edge). A straight
// edge's signed distance to a plane is affine along the edge, so of all the
// samples held by one plane only the two extreme ones along the edge can be
// active: the set keeps, per plane, the least and the greatest fraction that
// met it. A crease is then two planes and four constraints whatever the
// number of points, and any number of contacts on few planes fits in fixed
// storage. Never allocates.
#pragma once

#include <array>
#include <cstdint>
#include <span>

#include "hapticut/edge_fit.h"
#include "hapticut/tet_mesh.h"

namespace hapticut {

// What a contact's sample met, for force shading: a face of the rigid surface
// as seen from the non-rigid tet the walk left through it, an edge of the
// rigid surface (the swept test's), or nothing shading can name (a boundary
// face met from outside the mesh, the plane through a stretch's entry and exit).
struct ContactFeature {
  enum class Kind : std::uint8_t { None, Face, Edge };
  Kind kind = Kind::None;
  std::int32_t index = kNoTet;  // Face: the owner tet. Edge: the mesh's edge.
  std::int8_t face = 0;         // Face: the owner's local face.
};

class EdgeContactSet {
 public:
  // A plane met along the edge: its extreme samples and what each met.
  struct HeldPlane {
    Plane plane;
    double least_fraction = 0.0;
    double greatest_fraction = 0.0;
    ContactFeature least_feature;
    ContactFeature greatest_feature;
    // Calls f(fraction, feature) for each end of the range: once where the
    // plane holds a single sample, else its least and its greatest.
    template <class F>
    void for_each_end(F f) const {
      f(least_fraction, least_feature);
      if (greatest_fraction > least_fraction) f(greatest_fraction, greatest_feature);
    }
  };

  // Planes kept at most: each gives two constraints of the fit.
  static constexpr int kMaxPlanes = kMaxEdgeContacts / 2;
  // Two planes are one when their unit normals differ by at most this much and
  // their offsets by at most the tolerance given to add().
  static constexpr double kSameNormal = 1e-6;

  void clear() {
    plane_count_ = 0;
    changes_ = 0;
  }
  // Adds the sample at `fraction` of the edge held by `plane`: widens the
  // range of a plane already kept (within same_offset_mm), or keeps a new
  // one. False when the plane is new and the set is full (the walks still
  // refuse every pose that enters the material; the fit only lacks it).
  bool add(double fraction, const Plane& plane, double same_offset_mm,
           const ContactFeature& feature = {});

  int plane_count() const { return plane_count_; }
  // Grows with every add() that changed the constraints (a new plane, or a
  // plane's range widened): a round whose walks changed nothing has nothing
  // new to fit.
  int changes() const { return changes_; }
  bool full() const { return plane_count_ == kMaxPlanes; }
  // The fit's constraints: one per plane met at a single fraction, two (its
  // extremes) per plane met along a stretch of the edge. Valid until the
  // next add() or clear().
  std::span<const EdgeContact> constraints();
  std::span<const HeldPlane> planes() const {
    return {planes_.data(), static_cast<std::size_t>(plane_count_)};
  }

 private:
  std::array<HeldPlane, kMaxPlanes> planes_{};
  int plane_count_ = 0;
  int changes_ = 0;
  std::array<EdgeContact, kMaxEdgeContacts> constraints_{};
};

}  // namespace hapticut
