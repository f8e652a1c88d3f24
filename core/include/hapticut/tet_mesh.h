// TetMesh: the space split into tetrahedra, each with a material index, and
// everything the paper precomputes (section 3) so that a servo tick never
// searches or allocates. Immutable after construction.
//
// Local conventions (used by every file that walks the mesh):
//   - face i of a tet is the face opposite its local vertex i;
//   - local edge e joins local vertices kEdgeVertices[e];
//   - tets are stored positively oriented (inverted input is re-oriented).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "hapticut/aabb_tree.h"
#include "hapticut/geometry.h"  // Plane.
#include "hapticut/vec3.h"

namespace hapticut {

// Sentinel for "no tet here" (the outside of a boundary face, or a failed locate).
inline constexpr std::int32_t kNoTet = -1;

inline constexpr std::array<std::array<int, 2>, 6> kEdgeVertices{
    {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}}};

// The signed volume of the tet (a, b, c, d): positive when d lies on the side
// that (b - a) x (c - a) points to.
inline double signed_tet_volume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return dot(b - a, cross(c - a, d - a)) / 6.0;
}

// The one flatness test of tets (the mesh and the scene reader): a tet whose
// |6 V| is not above this fraction of (longest edge)^3 has no volume (NaN neither).
inline constexpr double kZeroVolumeRatio = 1e-12;
inline bool tet_has_no_volume(const std::array<Vec3, 4>& corners, double volume6) {
  double longest = 0.0;
  for (const auto& e : kEdgeVertices) {
    longest = std::max(longest, norm(corners[e[0]] - corners[e[1]]));
  }
  return !(std::abs(volume6) > kZeroVolumeRatio * longest * longest * longest);
}
// The two faces that contain local edge e (the faces opposite the other two vertices).
inline constexpr std::array<std::array<int, 2>, 6> kEdgeFaces{
    {{2, 3}, {1, 3}, {1, 2}, {0, 3}, {0, 2}, {0, 1}}};
// The faces of a tet other than the one indexed: a face's three sides.
inline constexpr std::array<std::array<int, 3>, 4> kOtherFaces{
    {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}}};
// The local edge shared by faces i and j (i != j); -1 on the diagonal.
inline constexpr std::array<std::array<int, 4>, 4> kEdgeOfFaces{
    {{-1, 5, 4, 3}, {5, -1, 2, 1}, {4, 2, -1, 0}, {3, 1, 0, -1}}};
// The local edge joining local vertices a and b (a != b); -1 on the diagonal.
inline constexpr std::array<std::array<int, 4>, 4> kEdgeOfVertices{
    {{-1, 0, 1, 2}, {0, -1, 3, 4}, {1, 3, -1, 5}, {2, 4, 5, -1}}};

class MeshError : public std::runtime_error {
 public:
  MeshError(const std::string& what, std::int64_t index)
      : std::runtime_error(what), index_(index) {}
  // The offending vertex, tet or face index (-1 when none applies).
  std::int64_t index() const { return index_; }

 private:
  std::int64_t index_;
};

struct FaceRef {
  std::int32_t tet = kNoTet;
  std::int8_t face = 0;
};

struct EdgeFanEntry {
  std::int32_t tet = kNoTet;
  std::int8_t local_edge = 0;
  std::array<std::int8_t, 2> faces{};  // The tet's two faces through the edge.
};

struct VertexFanEntry {
  std::int32_t tet = kNoTet;
  std::int8_t local_vertex = 0;
};

struct MeshStats {
  std::int64_t reoriented_tets = 0;
  int max_tets_per_edge = 0;
  double mean_tets_per_edge = 0.0;
  int max_tets_per_vertex = 0;
  double mean_tets_per_vertex = 0.0;
  double min_dihedral_deg = 0.0;
  std::int64_t boundary_faces = 0;
};

class TetMesh {
 public:
  // Validates and precomputes. Throws MeshError naming the offending index for:
  // an index out of range, a NaN/inf coordinate, a zero-volume tet, a face
  // shared by more than two tets, a material index < 0, a tet listed twice,
  // two tets on the same side of their shared face (folded), two tets whose
  // interiors overlap (sampled: see reject_overlapping_tets). tolerance_mm = 0
  // derives the tolerance from the mesh size (kRelativeTolerance x bbox diagonal);
  // a tolerance outside setting_range::kTolerance (negative, NaN, above 0.1 um)
  // throws std::invalid_argument.
  TetMesh(std::vector<Vec3> vertices_mm, std::vector<std::array<std::int32_t, 4>> tets,
          std::vector<std::int32_t> tet_materials, double tolerance_mm = 0.0);

  static constexpr double kRelativeTolerance = 1e-9;

  std::int32_t vertex_count() const { return static_cast<std::int32_t>(vertices_.size()); }
  std::int32_t tet_count() const { return static_cast<std::int32_t>(tets_.size()); }
  std::int32_t edge_count() const { return static_cast<std::int32_t>(edge_vertices_.size()); }

  const Vec3& vertex(std::int32_t v) const { return vertices_[v]; }
  const std::array<std::int32_t, 4>& tet(std::int32_t t) const { return tets_[t]; }
  std::int32_t material(std::int32_t t) const { return materials_[t]; }
  const std::vector<Vec3>& vertices() const { return vertices_; }
  const std::vector<std::array<std::int32_t, 4>>& tets() const { return tets_; }
  const std::vector<std::int32_t>& materials() const { return materials_; }

  // Absolute tolerance (mm) of every geometric test; stated once, see docs/decisions.md.
  double tolerance() const { return tolerance_; }

  const Plane& face_plane(std::int32_t t, int face) const { return planes_[t].face[face]; }
  // Asks the cache for what a walk reads on entering tet t (its planes, its
  // neighbours, its material), so a walk that knows its next tet one step
  // ahead waits for one memory access, not for four in a row.
  void prefetch_tet(std::int32_t t) const {
    __builtin_prefetch(&planes_[t].face[0]);
    __builtin_prefetch(&planes_[t].face[2]);
    __builtin_prefetch(&neighbours_[4 * static_cast<std::size_t>(t)]);
    __builtin_prefetch(&materials_[t]);
  }
  std::int32_t neighbour(std::int32_t t, int face) const { return neighbours_[4 * t + face]; }
  int neighbour_face(std::int32_t t, int face) const { return neighbour_faces_[4 * t + face]; }
  std::int32_t edge_of(std::int32_t t, int local_edge) const {
    return tet_edges_[6 * t + local_edge];
  }

  const std::array<std::int32_t, 2>& edge_vertices(std::int32_t e) const {
    return edge_vertices_[e];
  }
  // Unit direction from edge_vertices(e)[0] to [1]: the inward direction at
  // end 0; its negation is the inward direction at end 1 (eq. 10).
  const Vec3& edge_direction(std::int32_t e) const { return edge_directions_[e]; }
  std::span<const EdgeFanEntry> edge_fan(std::int32_t e) const {
    return {edge_fan_.data() + edge_fan_start_[e], edge_fan_.data() + edge_fan_start_[e + 1]};
  }
  // edge_fan(edge_of(t, local_edge)), from a range stored with the tet: an EDGE
  // step waits for two lookups in a row before the fan's planes, not three (the
  // slide of a proxy over a bone crosses an edge per surface triangle).
  std::span<const EdgeFanEntry> edge_fan_of(std::int32_t t, int local_edge) const {
    const auto& range = tet_edge_fans_[6 * t + local_edge];
    return {edge_fan_.data() + range[0], edge_fan_.data() + range[1]};
  }
  // Asks the cache for the fan ranges of tet t's six edges (48 bytes, up to two
  // lines): a slide that goes on over a face of t next ends on one of its edges.
  void prefetch_fan_ranges(std::int32_t t) const {
    __builtin_prefetch(&tet_edge_fans_[6 * static_cast<std::size_t>(t)]);
    __builtin_prefetch(&tet_edge_fans_[6 * static_cast<std::size_t>(t) + 5]);
  }
  std::span<const VertexFanEntry> vertex_fan(std::int32_t v) const {
    return {vertex_fan_.data() + vertex_fan_start_[v],
            vertex_fan_.data() + vertex_fan_start_[v + 1]};
  }
  bool is_boundary_edge(std::int32_t e) const { return boundary_edge_[e] != 0; }
  bool is_boundary_vertex(std::int32_t v) const { return boundary_vertex_[v] != 0; }

  const std::vector<FaceRef>& boundary_faces() const { return boundary_faces_; }
  // The outward plane of boundary_faces()[k], stored contiguously for OUTSIDE's scan.
  const Plane& boundary_plane(std::size_t k) const { return boundary_planes_[k]; }
  // The three side planes of boundary_faces()[k] (its tet's other faces, in
  // kOtherFaces order), side by side: OUTSIDE's triangle test reads them in a row.
  const Plane* boundary_side_planes(std::size_t k) const { return &boundary_side_planes_[3 * k]; }
  // The same planes as separate coordinate arrays (normal x, y, z, offset), so
  // a scan over all of them vectorizes.
  const std::array<std::vector<double>, 4>& boundary_plane_columns() const {
    return boundary_plane_columns_;
  }
  const AabbTree& boundary_tree() const { return boundary_tree_; }
  const AabbTree& tet_tree() const { return tet_tree_; }

  // The tet containing p (within the tolerance), or kNoTet.
  std::int32_t locate(const Vec3& p) const;
  // Largest signed distance of p to the planes of tet t (<= 0 inside).
  double outside_distance(std::int32_t t, const Vec3& p) const;

  double signed_volume(std::int32_t t) const;
  const MeshStats& stats() const { return stats_; }
  std::size_t memory_bytes() const;

 private:
  void validate_and_orient();
  void reject_duplicate_tets() const;
  void reject_overlapping_tets() const;
  void build_faces();
  void build_edges();
  void build_vertex_fans();
  void build_trees();
  void compute_stats();

  std::vector<Vec3> vertices_;
  std::vector<std::array<std::int32_t, 4>> tets_;
  std::vector<std::int32_t> materials_;
  double tolerance_ = 0.0;

  // A tet's four face planes, 128 bytes on a cache-line boundary: two lines,
  // never three (a plain vector of Plane starts where malloc puts it).
  struct alignas(64) TetPlanes {
    std::array<Plane, 4> face;
  };
  static_assert(sizeof(TetPlanes) == 128, "a tet's planes fill two cache lines exactly");
  std::vector<TetPlanes> planes_;             // One per tet.
  std::vector<std::int32_t> neighbours_;      // 4 per tet.
  std::vector<std::int8_t> neighbour_faces_;  // 4 per tet.
  std::vector<std::int32_t> tet_edges_;       // 6 per tet.
  // 6 per tet: the edge_fan_ range of edge_of(t, e), a copy of edge_fan_start_'s (edge_fan_of).
  std::vector<std::array<std::int32_t, 2>> tet_edge_fans_;
  std::vector<std::array<std::int32_t, 2>> edge_vertices_;
  std::vector<Vec3> edge_directions_;
  std::vector<std::int32_t> edge_fan_start_;
  std::vector<EdgeFanEntry> edge_fan_;
  std::vector<std::int32_t> vertex_fan_start_;
  std::vector<VertexFanEntry> vertex_fan_;
  std::vector<std::uint8_t> boundary_edge_;
  std::vector<std::uint8_t> boundary_vertex_;
  std::vector<FaceRef> boundary_faces_;
  std::vector<Plane> boundary_planes_;
  std::vector<Plane> boundary_side_planes_;  // 3 per boundary face.
  std::array<std::vector<double>, 4> boundary_plane_columns_;
  AabbTree boundary_tree_;
  AabbTree tet_tree_;
  MeshStats stats_;
};

// ---- Mesh queries of the OUTSIDE state ----------------------------------------

// Euclidean distance from x to tet t (0 inside or on it).
double distance_to_tet(const TetMesh& mesh, std::int32_t t, const Vec3& x);

// Whether x lies in the mesh farther than margin from its boundary: within
// margin of some tet and of no boundary triangle. An OUTSIDE proxy must never
// be there (the OUTSIDE safety net and Proxy::check_invariants). Exact
// distances, so a point on an interior face or vertex counts as inside and a
// point near a sharp outer corner does not.
bool lies_in_mesh_interior(const TetMesh& mesh, const Vec3& x, double margin);

// The box of the mesh's vertices grown by pad on every side.
Aabb mesh_box(const TetMesh& mesh, double pad);

// Where the straight move x -> b leaves tet t first: the face and the fraction
// of the move (docs/method.md, repair 1: only a plane it strictly exits, by
// more than eps, counts; the fraction is 0 when x already lies on it). face is
// -1 when b lies in t.
struct TetExit {
  int face = -1;
  double fraction = 0.0;
};
inline TetExit first_exit(const TetMesh& mesh, std::int32_t t, const Vec3& x, const Vec3& b,
                          double eps) {
  const Plane* planes = &mesh.face_plane(t, 0);
  TetExit exit;
  double least = std::numeric_limits<double>::infinity();
  for (int f = 0; f < 4; ++f) {
    const double d0 = planes[f].signed_distance(x);
    const double d1 = planes[f].signed_distance(b);
    if (!(d1 > eps && d1 > d0)) continue;
    const double h = d0 >= 0.0 ? 0.0 : d0 / (d0 - d1);
    if (h < least) {
      least = h;
      exit = {f, h};
    }
  }
  return exit;
}

}  // namespace hapticut
