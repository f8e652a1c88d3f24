#include "hapticut/force_shading.h"

#include <algorithm>
#include <cmath>

#include "hapticut/geometry.h"

namespace hapticut {

namespace {

// The three local vertices of face f of a tet, in the order that makes
// (b - a) x (c - a) point out of the tet (tets are stored positively oriented).
std::array<int, 3> face_vertices_outward(int f) {
  static constexpr std::array<std::array<int, 3>, 4> kFaces{
      {{1, 3, 2}, {0, 2, 3}, {0, 3, 1}, {0, 1, 2}}};
  return kFaces[f];
}

// Is the tet face (t, f) on the rigid surface, with t the rigid side?
bool is_rigid_surface_face(const Space& space, std::int32_t t, int f) {
  if (!space.tet_is_rigid(t)) return false;
  const std::int32_t u = space.mesh().neighbour(t, f);
  return u == kNoTet || !space.tet_is_rigid(u);
}

// Fixed-point iterations locating the shaded contact point on a face.
constexpr int kContactIterations = 2;

Vec3 normalized_or_zero(const Vec3& v) {
  const double n = norm(v);
  return n > 0.0 ? v / n : Vec3{};
}

}  // namespace

RigidSurface extract_rigid_surface(const Space& space) {
  const TetMesh& mesh = space.mesh();
  RigidSurface surface;
  std::vector<std::int32_t> compact(mesh.vertex_count(), -1);
  for (std::int32_t t = 0; t < mesh.tet_count(); ++t) {
    for (int f = 0; f < 4; ++f) {
      if (!is_rigid_surface_face(space, t, f)) continue;
      std::array<std::int32_t, 3> triangle{};
      const std::array<int, 3> local = face_vertices_outward(f);
      for (int k = 0; k < 3; ++k) {
        const std::int32_t v = mesh.tet(t)[local[k]];
        if (compact[v] < 0) {
          compact[v] = static_cast<std::int32_t>(surface.vertices_mm.size());
          surface.vertices_mm.push_back(mesh.vertex(v));
          surface.mesh_vertex.push_back(v);
        }
        triangle[k] = compact[v];
      }
      // Make the winding agree with the stored outward plane whatever the
      // table above assumed about orientation.
      const Vec3& a = surface.vertices_mm[triangle[0]];
      const Vec3 n =
          cross(surface.vertices_mm[triangle[1]] - a, surface.vertices_mm[triangle[2]] - a);
      if (dot(n, mesh.face_plane(t, f).normal) < 0.0) std::swap(triangle[1], triangle[2]);
      surface.triangles.push_back(triangle);
    }
  }
  return surface;
}

ForceShading::ForceShading(const Space& space) : space_(owner_of(space)) {
  const TetMesh& mesh = space.mesh();
  vertex_normals_.assign(mesh.vertex_count(), Vec3{});
  surface_edge_.assign(mesh.edge_count(), 0);
  for (std::int32_t t = 0; t < mesh.tet_count(); ++t) {
    for (int f = 0; f < 4; ++f) {
      if (!is_rigid_surface_face(space, t, f)) continue;
      // Out of the rigid tet: its own outward face normal.
      const Vec3 n = mesh.face_plane(t, f).normal;
      std::array<int, 3> local{};
      int count = 0;
      for (int v = 0; v < 4; ++v) {
        if (v != f) local[count++] = v;
      }
      for (int k = 0; k < 3; ++k) {
        // Angle weights (Thuermer and Wuethrich): independent of how the
        // surface around a vertex happens to be split into triangles.
        const Vec3& x = mesh.vertex(mesh.tet(t)[local[k]]);
        const Vec3 e1 = normalized_or_zero(mesh.vertex(mesh.tet(t)[local[(k + 1) % 3]]) - x);
        const Vec3 e2 = normalized_or_zero(mesh.vertex(mesh.tet(t)[local[(k + 2) % 3]]) - x);
        const double angle = std::acos(std::clamp(dot(e1, e2), -1.0, 1.0));
        vertex_normals_[mesh.tet(t)[local[k]]] += n * angle;
      }
      for (int e = 0; e < 6; ++e) {
        if (kEdgeVertices[e][0] != f && kEdgeVertices[e][1] != f) {
          surface_edge_[mesh.edge_of(t, e)] = 1;
        }
      }
    }
  }
  for (Vec3& n : vertex_normals_) n = normalized_or_zero(n);
  face_normals_ = vertex_normals_;
  build_shaded_faces();
}

ForceShading::ForceShading(const Space& space, const std::vector<Vec3>& source_vertices_mm,
                           const std::vector<std::array<std::int32_t, 3>>& source_triangles)
    : ForceShading(space) {
  // Angle-weighted vertex normals of the source.
  std::vector<Vec3> source_normals(source_vertices_mm.size());
  std::vector<Aabb> boxes;
  Aabb all;
  for (const auto& tri : source_triangles) {
    const std::array<Vec3, 3> x{source_vertices_mm.at(tri[0]), source_vertices_mm.at(tri[1]),
                                source_vertices_mm.at(tri[2])};
    const Vec3 n = normalized_or_zero(cross(x[1] - x[0], x[2] - x[0]));
    Aabb box;
    for (int k = 0; k < 3; ++k) {
      const Vec3 e1 = normalized_or_zero(x[(k + 1) % 3] - x[k]);
      const Vec3 e2 = normalized_or_zero(x[(k + 2) % 3] - x[k]);
      source_normals[tri[k]] += n * std::acos(std::clamp(dot(e1, e2), -1.0, 1.0));
      box.grow(x[k]);
    }
    boxes.push_back(box);
    all.grow(box);
  }
  if (boxes.empty()) return;
  for (Vec3& n : source_normals) n = normalized_or_zero(n);
  const AabbTree tree(boxes);
  const double diagonal = norm(all.hi - all.lo);
  for (std::int32_t v = 0; v < vertex_count(); ++v) {
    if (vertex_normals_[v] == Vec3{}) continue;
    const Vec3& x = space.mesh().vertex(v);
    // Nearest source triangle: search boxes within a growing pad.
    double best = 1e300;
    Vec3 best_normal;
    for (double pad = 1e-4 * diagonal; best == 1e300 && pad < 4.0 * diagonal; pad *= 4.0) {
      tree.for_each_containing(x, pad, [&](std::int32_t t) {
        const auto& tri = source_triangles[t];
        const Vec3& a = source_vertices_mm[tri[0]];
        const Vec3& b = source_vertices_mm[tri[1]];
        const Vec3& c = source_vertices_mm[tri[2]];
        const Vec3 y = closest_point_on_triangle(x, a, b, c);
        const double d = norm(y - x);
        if (d >= best) return;
        best = d;
        // Barycentric weights of y in abc.
        const Vec3 n = cross(b - a, c - a);
        const double area = dot(n, n);
        const double wa = dot(cross(b - y, c - y), n) / area;
        const double wb = dot(cross(c - y, a - y), n) / area;
        const double wc = 1.0 - wa - wb;
        best_normal =
            source_normals[tri[0]] * wa + source_normals[tri[1]] * wb + source_normals[tri[2]] * wc;
      });
    }
    const Vec3 n = normalized_or_zero(best_normal);
    if (n == Vec3{}) continue;
    vertex_normals_[v] = n;
    // Unnormalised: the source's field is linear over each source triangle,
    // so pieces of a split triangle interpolating these values reproduce it.
    face_normals_[v] = best_normal;
  }
  build_shaded_faces();
}

void ForceShading::build_shaded_faces() {
  const TetMesh& mesh = space_->mesh();
  shaded_faces_.clear();
  face_record_.assign(4 * static_cast<std::size_t>(mesh.tet_count()), kNotShaded);
  for (std::int32_t t = 0; t < mesh.tet_count(); ++t) {
    if (space_->tet_is_rigid(t)) continue;
    for (int f = 0; f < 4; ++f) {
      const std::int32_t u = mesh.neighbour(t, f);
      if (u == kNoTet || !space_->tet_is_rigid(u)) continue;
      // Out of the rigid region = into the owner.
      const Vec3 face_normal = -mesh.face_plane(t, f).normal;
      std::array<Vec3, 3> corner;
      std::array<Vec3, 3> normal;
      int count = 0;
      for (int v = 0; v < 4; ++v) {
        if (v == f) continue;
        normal[count] = face_normals_[mesh.tet(t)[v]];
        corner[count++] = mesh.vertex(mesh.tet(t)[v]);
      }
      const double area = dot(cross(corner[1] - corner[0], corner[2] - corner[0]), face_normal);
      if (area == 0.0 || !std::isfinite(area)) continue;
      // w_k(x) = face_normal . ((c_{k+1} - x) x (c_{k+2} - x)) / area, whose
      // gradient is ((c_{k+1} - c_{k+2}) x face_normal) / area; w_k(c_0) = [k == 0].
      ShadedFace face;
      face.origin = corner[0];
      face.origin_normal = normal[0];
      face.normal = face_normal;
      for (int k = 0; k < 3; ++k) {
        const Vec3 gradient = cross(corner[(k + 1) % 3] - corner[(k + 2) % 3], face_normal) / area;
        face.rows[0] += gradient * normal[k].x;
        face.rows[1] += gradient * normal[k].y;
        face.rows[2] += gradient * normal[k].z;
      }
      face_record_[4 * static_cast<std::size_t>(t) + f] =
          static_cast<std::int32_t>(shaded_faces_.size());
      shaded_faces_.push_back(face);
    }
  }
}

Vec3 ForceShading::edge_normal(std::int32_t e, const Vec3& q) const {
  const TetMesh& mesh = space_->mesh();
  const auto& ends = mesh.edge_vertices(e);
  const Vec3& a = mesh.vertex(ends[0]);
  const Vec3& b = mesh.vertex(ends[1]);
  const double length2 = squared_norm(b - a);
  const double s = length2 > 0.0 ? std::clamp(dot(q - a, b - a) / length2, 0.0, 1.0) : 0.5;
  return normalized_or_zero(vertex_normals_[ends[0]] * (1.0 - s) + vertex_normals_[ends[1]] * s);
}

// The shading normal where the proxy touches the rigid surface at a feature
// its state does not name: a FACE or EDGE whose own plane or line is not on
// the surface, with q on one of its surface edges or vertices (a proxy held
// on a surface edge may be owned by any face through that edge). Zero when q
// touches no surface edge or vertex of the element.
Vec3 ForceShading::touching_normal(const ProxyPlace& place) const {
  const TetMesh& mesh = space_->mesh();
  const std::int32_t t = place.tet;
  const double near = 100.0 * space_->tolerance();
  std::array<int, 3> vertices{};
  int vertex_count = 0;
  if (place.state == ProxyState::Face) {
    for (int v = 0; v < 4; ++v) {
      if (v != place.local) vertices[vertex_count++] = v;
    }
  } else {
    vertices[0] = kEdgeVertices[place.local][0];
    vertices[1] = kEdgeVertices[place.local][1];
    vertex_count = 2;
  }
  for (int i = 0; i < vertex_count; ++i) {
    const std::int32_t v = mesh.tet(t)[vertices[i]];
    if (vertex_normals_[v] != Vec3{} && squared_norm(place.q - mesh.vertex(v)) <= near * near) {
      return vertex_normals_[v];
    }
  }
  if (place.state != ProxyState::Face) return {};
  for (int i = 0; i < 3; ++i) {
    const int e = kEdgeOfVertices[vertices[i]][vertices[(i + 1) % 3]];
    const std::int32_t edge = mesh.edge_of(t, e);
    if (!is_surface_edge(edge)) continue;
    const auto& ends = mesh.edge_vertices(edge);
    const Vec3& a = mesh.vertex(ends[0]);
    const Vec3& b = mesh.vertex(ends[1]);
    const double s = std::clamp(dot(place.q - a, b - a) / squared_norm(b - a), 0.0, 1.0);
    if (squared_norm(place.q - (a + (b - a) * s)) <= near * near) return edge_normal(edge, place.q);
  }
  return {};
}

Vec3 ForceShading::shade(const ProxyPlace& place, const Vec3& raw_force_N) const {
  const TetMesh& mesh = space_->mesh();
  const std::int32_t t = place.tet;
  if (t == kNoTet || space_->tet_is_rigid(t)) return raw_force_N;
  Vec3 shaded_normal;
  switch (place.state) {
    case ProxyState::Face: {
      const std::int32_t record =
          face_record_[4 * static_cast<std::size_t>(t) + static_cast<std::size_t>(place.local)];
      if (record == kNotShaded) {
        shaded_normal = touching_normal(place);
        break;
      }
      const ShadedFace& face = shaded_faces_[record];
      const double normal_part = dot(raw_force_N, face.normal);
      if (normal_part <= 0.0) return raw_force_N;
      // The shaded normal at a point x, unnormalised: barycentric weights
      // from signed sub-triangle areas (linear, so it extrapolates a little
      // past the face's edges), vertex normals interpolated.
      auto normal_at = [&face](const Vec3& x) {
        const Vec3 r = x - face.origin;
        return face.origin_normal +
               Vec3{dot(face.rows[0], r), dot(face.rows[1], r), dot(face.rows[2], r)};
      };
      // The contact point of the smooth surface the normals describe: where
      // the line from p along the shaded normal meets the face plane (q is
      // where the line along the facet normal meets it). A fixed point,
      // two iterations from q (Morgenbesser and Srinivasan's second pass).
      // The point does not depend on the normal's length, so only the last
      // normal is normalised. p - q = -raw / k, so p's height over the plane
      // is -normal_part / k.
      const double compliance_mm_per_N = 1.0 / space_->settings().stiffness_N_per_mm;
      const double p_height = -normal_part * compliance_mm_per_N;
      const Vec3 p = place.q - raw_force_N * compliance_mm_per_N;
      Vec3 n = normal_at(place.q);
      for (int iteration = 0; iteration < kContactIterations; ++iteration) {
        const double along = dot(n, face.normal);
        // along / |n| > 0.5: the normal leans less than 60 degrees off the facet.
        if (!(along > 0.0 && 4.0 * along * along > squared_norm(n))) break;
        const Vec3 next = normal_at(p - n * (p_height / along));
        if (next == Vec3{}) break;
        n = next;
      }
      const double length = norm(n);
      if (!(length > 0.0)) return raw_force_N;
      shaded_normal = n * (1.0 / length);
      return raw_force_N - face.normal * normal_part + shaded_normal * normal_part;
    }
    case ProxyState::Edge: {
      const std::int32_t e = mesh.edge_of(t, place.local);
      shaded_normal = is_surface_edge(e) ? edge_normal(e, place.q) : touching_normal(place);
      break;
    }
    case ProxyState::Vertex:
      shaded_normal = vertex_normals_[mesh.tet(t)[place.local]];
      break;
    default:
      return raw_force_N;
  }
  if (shaded_normal == Vec3{} || dot(raw_force_N, shaded_normal) <= 0.0) return raw_force_N;
  return shaded_normal * norm(raw_force_N);
}

std::size_t ForceShading::memory_bytes() const {
  return (vertex_normals_.capacity() + face_normals_.capacity()) * sizeof(Vec3) +
         surface_edge_.capacity() + shaded_faces_.capacity() * sizeof(ShadedFace) +
         face_record_.capacity() * sizeof(std::int32_t);
}

}  // namespace hapticut
