#include "hapticut/force_shading.h"

#include <algorithm>
#include <cmath>

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

ForceShading::ForceShading(const Space& space) : space_(&space) {
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
}

Vec3 ForceShading::shade(const ProxyPlace& place, const Vec3& raw_force_N) const {
  const TetMesh& mesh = space_->mesh();
  const std::int32_t t = place.tet;
  if (t == kNoTet) return raw_force_N;
  Vec3 shaded_normal;
  switch (place.state) {
    case ProxyState::Face: {
      const int f = place.local;
      const std::int32_t u = mesh.neighbour(t, f);
      if (u == kNoTet || !space_->tet_is_rigid(u) || space_->tet_is_rigid(t)) return raw_force_N;
      // Out of the rigid region = into the owner.
      const Vec3 face_normal = -mesh.face_plane(t, f).normal;
      const double normal_part = dot(raw_force_N, face_normal);
      if (normal_part <= 0.0) return raw_force_N;
      std::array<Vec3, 3> corner;
      std::array<std::int32_t, 3> vertex{};
      int count = 0;
      for (int v = 0; v < 4; ++v) {
        if (v == f) continue;
        vertex[count] = mesh.tet(t)[v];
        corner[count++] = mesh.vertex(mesh.tet(t)[v]);
      }
      // Barycentric weights from sub-triangle areas along the face normal.
      const Vec3& q = place.q;
      std::array<double, 3> weight{};
      double total = 0.0;
      for (int k = 0; k < 3; ++k) {
        const Vec3& b = corner[(k + 1) % 3];
        const Vec3& c = corner[(k + 2) % 3];
        weight[k] = std::max(0.0, dot(cross(b - q, c - q), face_normal));
        total += weight[k];
      }
      if (!(total > 0.0)) return raw_force_N;
      for (int k = 0; k < 3; ++k) shaded_normal += vertex_normals_[vertex[k]] * (weight[k] / total);
      shaded_normal = normalized_or_zero(shaded_normal);
      if (shaded_normal == Vec3{}) return raw_force_N;
      return raw_force_N - face_normal * normal_part + shaded_normal * normal_part;
    }
    case ProxyState::Edge: {
      const std::int32_t e = mesh.edge_of(t, place.local);
      if (!is_surface_edge(e)) return raw_force_N;
      const auto& ends = mesh.edge_vertices(e);
      const Vec3& a = mesh.vertex(ends[0]);
      const Vec3& b = mesh.vertex(ends[1]);
      const double length = norm(b - a);
      const double s =
          length > 0.0 ? std::clamp(dot(place.q - a, b - a) / (length * length), 0.0, 1.0) : 0.5;
      shaded_normal =
          normalized_or_zero(vertex_normals_[ends[0]] * (1.0 - s) + vertex_normals_[ends[1]] * s);
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
  return vertex_normals_.capacity() * sizeof(Vec3) + surface_edge_.capacity();
}

}  // namespace hapticut
