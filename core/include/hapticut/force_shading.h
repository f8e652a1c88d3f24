// Force shading on the surface of rigid material (Morgenbesser and
// Srinivasan, beyond the paper): the proxy still slides over flat facets, but
// the force direction is the normal interpolated from per-vertex normals, so
// a faceted sphere feels round. Built once per Space; pure lookups per tick.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "hapticut/proxy_place.h"
#include "hapticut/space.h"

namespace hapticut {

// The surface of the rigid region: every tet face with a rigid tet on one side
// and a non-rigid tet or the mesh's outside on the other. #T by 3 triangles
// into `vertices_mm`, wound counter-clockwise seen from outside the rigid region.
struct RigidSurface {
  std::vector<Vec3> vertices_mm;
  std::vector<std::array<std::int32_t, 3>> triangles;
  std::vector<std::int32_t> mesh_vertex;  // Surface vertex -> TetMesh vertex.
};

RigidSurface extract_rigid_surface(const Space& space);

class ForceShading {
 public:
  // Surfaces meeting at a sharper angle than 45 degrees (their normals this
  // cosine apart) are a crease the shading keeps; gentler turns it smooths.
  static constexpr double kCreaseCosine = 0.70710678118654752;

  // Both constructors smooth the normals they interpolate at the scale of the
  // rigid surface's own facets (docs/decisions.md, "Force shading: nearest
  // source and smoothed normals"): a surface vertex takes the normal of a
  // sphere fitted to the oriented points within 1.5 x its longest surface
  // edge, leaving out points more than 45 degrees off (beyond a crease). The
  // fit keeps a sphere or a plane exact and averages out bumps (a scanned
  // surface) that a facet-wise interpolation would only alias. The FACE path
  // fits each face's corners against that face's own normal, so a face
  // beside a crease is not bent by the surface across it; EDGE and VERTEX use
  // the vertex's normal fitted against its one-ring normal.
  //
  // Normals from the rigid surface of the tet mesh itself (what a servo has on
  // an exported scene): the points are its facets (centroid, normal, area).
  explicit ForceShading(const Space& space);
  // Normals from the surface the scene was built from (#T by 3 triangles
  // wound outward, vertices finite; anything else throws std::invalid_argument
  // naming it): the points are the source's vertices with their angle-weighted
  // normals, fitted within at least the reach of the triangle holding the
  // exact nearest source point. Tetrahedralization splits the source's
  // facets; the FACE path interpolates the fitted values unnormalised (on a
  // sphere or plane they are the source's linear field, so split pieces
  // reproduce it exactly); EDGE and VERTEX use them normalised. The source is
  // not kept.
  ForceShading(const Space& space, const std::vector<Vec3>& source_vertices_mm,
               const std::vector<std::array<std::int32_t, 3>>& source_triangles);

  // The shaded force for a proxy at `place` whose raw force is k (q - p), eq. (15).
  // FACE on the rigid surface: the normal component keeps its size and takes
  // the direction interpolated (barycentric) from the face's vertex values
  // at the shaded contact point;
  // the tangential component is kept. EDGE or VERTEX on the rigid surface:
  // the whole force (which lies in the feature's normal cone) takes the
  // interpolated direction; so does a FACE or EDGE not on the surface whose
  // q sits on a surface edge or vertex (within 100 x the mesh tolerance).
  // Anywhere else, or a force pulling into the surface: the raw force.
  Vec3 shade(const ProxyPlace& place, const Vec3& raw_force_N) const;

  // The shaded unit normal for a body whose device point p presses on the
  // rigid surface's edge e (a rigid blade resting on a ridge): of the surface
  // faces through e, the FACE path's normal (its contact point found from p)
  // of those whose line from p along that normal leaves the material through
  // them; where none or all do, the faces' mean; the EDGE path's normal where
  // no face through e is shaded.
  Vec3 edge_contact_normal(std::int32_t e, const Vec3& p) const;

  // Smoothed unit normal of a mesh vertex out of the rigid region, zero for a
  // vertex not on the rigid surface.
  const Vec3& vertex_normal(std::int32_t v) const { return vertex_normals_[v]; }
  std::int32_t vertex_count() const { return static_cast<std::int32_t>(vertex_normals_.size()); }
  bool is_surface_edge(std::int32_t e) const { return surface_edge_[e] != 0; }
  // The EDGE path's unit normal at x on mesh edge e (its ends' normals
  // interpolated), zero when e is not on the rigid surface.
  Vec3 surface_edge_normal(std::int32_t e, const Vec3& x) const {
    return is_surface_edge(e) ? edge_normal(e, x) : Vec3{};
  }
  // What the FACE path interpolates at the corners of face f of tet t (the
  // tet's vertices other than f, in order): zeros unless t is not rigid and
  // the face is on the rigid surface. For tests and inspection.
  std::array<Vec3, 3> face_corner_normals(std::int32_t t, int f) const;
  std::size_t memory_bytes() const;

 private:
  // A face of the rigid surface as seen from its non-rigid owner, ready for
  // the FACE path of shade(): the interpolated normal is affine in x,
  // n(x) = n0 + A (x - origin) (barycentric weights from signed areas are
  // affine in x, exactly, also off the face's plane), so one matrix-vector
  // product replaces three cross products per evaluation.
  struct ShadedFace {
    Vec3 origin;               // The face's first corner.
    Vec3 origin_normal;        // n0: the corner value there.
    std::array<Vec3, 3> rows;  // A, by rows: sum over corners of n_k (grad w_k)^T.
    Vec3 normal;               // Unit normal out of the rigid region (into the owner).
  };

  // The FACE path's unit normal on `face` for a proxy at q whose device
  // point p lies p_height over the face's plane (Morgenbesser and
  // Srinivasan's contact point); zero when there is none.
  Vec3 contact_normal(const ShadedFace& face, const Vec3& q, const Vec3& p, double p_height) const;
  // Faces of the rigid surface through one edge that edge_contact_normal weighs.
  static constexpr int kMaxEdgeFaces = 8;
  Vec3 edge_normal(std::int32_t e, const Vec3& q) const;
  Vec3 touching_normal(const ProxyPlace& place) const;
  // What the FACE path interpolates at a corner of a face: a function of
  // the mesh vertex and the face's unit normal out of the rigid region.
  using CornerNormal = std::function<Vec3(std::int32_t vertex, const Vec3& face_normal)>;
  // Fills shaded_faces_ and face_record_.
  void build_shaded_faces(const CornerNormal& corner_normal);

  std::shared_ptr<const Space> space_;  // Shared ownership (space.h, "Who owns a Space").
  std::vector<Vec3> vertex_normals_;
  std::vector<std::uint8_t> surface_edge_;
  std::vector<ShadedFace> shaded_faces_;
  // Per tet face (4 t + f): its index in shaded_faces_ when the face lies on the
  // rigid surface with t its non-rigid owner, else kNotShaded.
  static constexpr std::int32_t kNotShaded = -1;
  std::vector<std::int32_t> face_record_;
};

}  // namespace hapticut
