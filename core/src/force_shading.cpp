#include "hapticut/force_shading.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "hapticut/aabb_tree.h"
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

// The smoothing (docs/decisions.md, "Force shading: nearest source and
// smoothed normals"): a normal is fitted to the oriented points within
// kSmoothingReach x the vertex's reach, its reach being its longest edge on
// the rigid surface (with a source surface, at least the distance to the
// nearest source triangle's corners). The linear interpolation of the FACE
// path cannot show detail finer than the facets it spans, so the fit
// averages out detail of that size and keeps what is larger. Points whose
// normal is 45 degrees or more off (ForceShading::kCreaseCosine) the normal being fitted lie beyond
// a crease (or on the other side of a thin part) and are left out, so a crease sharper than that
// stays sharp instead of bending the facets beside it.
constexpr double kSmoothingReach = 1.5;

// What the tet mesh itself says about its rigid surface.
struct OneRing {
  std::vector<Vec3> normals;  // Angle-weighted unit normal per mesh vertex; zero off the surface.
  std::vector<std::uint8_t> surface_edge;  // Per mesh edge: on the rigid surface.
  std::vector<double> reach_mm;            // Per mesh vertex: its longest surface edge.
};

OneRing one_ring_normals(const Space& space) {
  const TetMesh& mesh = space.mesh();
  OneRing ring;
  ring.normals.assign(mesh.vertex_count(), Vec3{});
  ring.surface_edge.assign(mesh.edge_count(), 0);
  ring.reach_mm.assign(mesh.vertex_count(), 0.0);
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
        ring.normals[mesh.tet(t)[local[k]]] += n * angle;
      }
      for (int e = 0; e < 6; ++e) {
        if (kEdgeVertices[e][0] == f || kEdgeVertices[e][1] == f) continue;
        const std::int32_t edge = mesh.edge_of(t, e);
        ring.surface_edge[edge] = 1;
        const auto& ends = mesh.edge_vertices(edge);
        const double length = norm(mesh.vertex(ends[1]) - mesh.vertex(ends[0]));
        for (const std::int32_t v : ends) ring.reach_mm[v] = std::max(ring.reach_mm[v], length);
      }
    }
  }
  for (Vec3& n : ring.normals) n = normalized_or_zero(n);
  return ring;
}

// Weighted points with unit normals, and the normal of a sphere fitted to
// those near a position (algebraic point set surfaces, Guennebaud and Gross
// 2007): the fit reproduces a sphere or a plane exactly, whatever the points'
// spacing and weights, and averages out bumps smaller than its reach.
class OrientedPoints {
 public:
  OrientedPoints(std::vector<Vec3> points, std::vector<Vec3> normals, std::vector<double> weights)
      : points_(std::move(points)), normals_(std::move(normals)), weights_(std::move(weights)) {
    std::vector<Aabb> boxes(points_.size());
    for (std::size_t i = 0; i < points_.size(); ++i) boxes[i].grow(points_[i]);
    tree_ = AabbTree(boxes);
  }

  // The gradient at x of the algebraic sphere u0 + u.x + u4 |x|^2 fitted in
  // the least-squares sense to the points within `radius` of x whose normals
  // lie within the crease angle of `facing` (a surface beyond a crease, or
  // the other side of a thin part, is not the surface being fitted),
  // weighted by their weight x (1 - (d / radius)^2)^4: its direction is the
  // smoothed normal, its length about 1 near the points. Zero when no point
  // qualifies or the fit turns away from `facing`.
  Vec3 fitted_normal(const Vec3& x, const Vec3& facing, double radius) const {
    if (!(radius > 0.0)) return {};
    double total = 0.0;
    Vec3 mean_point;  // Relative to x.
    Vec3 mean_normal;
    auto each = [&](auto&& use) {
      tree_.for_each_containing(x, radius, [&](std::int32_t i) {
        const Vec3 r = points_[i] - x;
        const double t = squared_norm(r) / (radius * radius);
        if (t >= 1.0 || !(dot(normals_[i], facing) > ForceShading::kCreaseCosine)) return;
        use(i, r, weights_[i] * (1.0 - t) * (1.0 - t) * (1.0 - t) * (1.0 - t));
      });
    };
    each([&](std::int32_t i, const Vec3& r, double w) {
      total += w;
      mean_point += r * w;
      mean_normal += normals_[i] * w;
    });
    if (!(total > 0.0)) return {};
    mean_point = mean_point / total;
    mean_normal = mean_normal / total;
    // Second pass about the means: the spread of the points and how the
    // normals turn with them, both translation invariant.
    double spread = 0.0;
    double turn = 0.0;
    each([&](std::int32_t i, const Vec3& r, double w) {
      const Vec3 d = r - mean_point;
      spread += w * squared_norm(d);
      turn += w * dot(d, normals_[i]);
    });
    // Points (nearly) on one spot fix no curvature: fit a plane (u4 = 0).
    const double u4 = spread > 1e-12 * radius * radius * total ? 0.5 * turn / spread : 0.0;
    // grad = u + 2 u4 x with u = mean_normal - 2 u4 mean_point, at x (0 here).
    const Vec3 gradient = mean_normal - mean_point * (2.0 * u4);
    if (!(dot(gradient, facing) > 0.0) || !std::isfinite(squared_norm(gradient))) return {};
    return gradient;
  }

 private:
  std::vector<Vec3> points_;
  std::vector<Vec3> normals_;
  std::vector<double> weights_;
  AabbTree tree_;
};

// The exact nearest point of a triangle soup to a position.
class NearestTriangle {
 public:
  struct Hit {
    std::int32_t triangle = -1;
    std::array<double, 3> weights{};  // Barycentric weights of the nearest point.
  };

  NearestTriangle(const std::vector<Vec3>& vertices,
                  const std::vector<std::array<std::int32_t, 3>>& triangles,
                  const std::vector<Aabb>& boxes)
      : vertices_(vertices), triangles_(triangles), tree_(boxes) {
    Aabb all;
    for (const Aabb& box : boxes) all.grow(box);
    diagonal_ = norm(all.hi - all.lo);
  }

  // Boxes within a growing pad until one holds a triangle, then once more
  // with the best distance as the pad: a triangle nearer than the best has
  // its box within that distance, wherever the first pad stopped.
  Hit find(const Vec3& x) const {
    Hit hit;
    double best = std::numeric_limits<double>::infinity();
    auto visit = [&](std::int32_t t) {
      const auto& tri = triangles_[t];
      const Vec3& a = vertices_[tri[0]];
      const Vec3& b = vertices_[tri[1]];
      const Vec3& c = vertices_[tri[2]];
      const Vec3 y = closest_point_on_triangle(x, a, b, c);
      const double d = norm(y - x);
      if (d >= best) return;
      best = d;
      hit.triangle = t;
      const Vec3 n = cross(b - a, c - a);
      const double area = dot(n, n);
      if (!(area > 0.0)) {
        hit.weights = {1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0};
        return;
      }
      hit.weights[0] = dot(cross(b - y, c - y), n) / area;
      hit.weights[1] = dot(cross(c - y, a - y), n) / area;
      hit.weights[2] = 1.0 - hit.weights[0] - hit.weights[1];
    };
    // Triangle 0's box is within this distance: the pad never needs more.
    const double enough = norm(x - vertices_[triangles_[0][0]]);
    for (double pad = 1e-4 * (diagonal_ + enough);; pad *= 4.0) {
      const double clamped = std::min(pad, enough);
      tree_.for_each_containing(x, clamped, visit);
      if (hit.triangle >= 0 || clamped >= enough) break;
    }
    if (std::isfinite(best)) tree_.for_each_containing(x, best, visit);
    return hit;
  }

 private:
  const std::vector<Vec3>& vertices_;
  const std::vector<std::array<std::int32_t, 3>>& triangles_;
  AabbTree tree_;
  double diagonal_ = 0.0;
};

// A source surface the constructor can use: finite vertices, triangles that
// index them.
void check_source(const std::vector<Vec3>& vertices,
                  const std::vector<std::array<std::int32_t, 3>>& triangles) {
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    const Vec3& x = vertices[i];
    if (!std::isfinite(x.x) || !std::isfinite(x.y) || !std::isfinite(x.z)) {
      throw std::invalid_argument("ForceShading: source vertex " + std::to_string(i) +
                                  " is not finite");
    }
  }
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    for (const std::int32_t v : triangles[t]) {
      if (v < 0 || static_cast<std::size_t>(v) >= vertices.size()) {
        throw std::invalid_argument("ForceShading: source triangle " + std::to_string(t) +
                                    " uses vertex " + std::to_string(v) + ", outside [0, " +
                                    std::to_string(vertices.size()) + ")");
      }
    }
  }
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
  const OneRing ring = one_ring_normals(space);
  surface_edge_ = ring.surface_edge;
  vertex_normals_ = ring.normals;
  // The facets themselves are the points: centroid, unit normal, area.
  const RigidSurface surface = extract_rigid_surface(space);
  std::vector<Vec3> points;
  std::vector<Vec3> normals;
  std::vector<double> areas;
  for (const auto& tri : surface.triangles) {
    const Vec3& a = surface.vertices_mm[tri[0]];
    const Vec3& b = surface.vertices_mm[tri[1]];
    const Vec3& c = surface.vertices_mm[tri[2]];
    const Vec3 n = cross(b - a, c - a);
    if (!(norm(n) > 0.0)) continue;
    points.push_back((a + b + c) / 3.0);
    normals.push_back(n / norm(n));
    areas.push_back(0.5 * norm(n));
  }
  const OrientedPoints cloud(points, normals, areas);
  const TetMesh& mesh = space.mesh();
  for (std::int32_t v = 0; v < mesh.vertex_count(); ++v) {
    if (ring.normals[v] == Vec3{}) continue;
    const Vec3 fitted = normalized_or_zero(
        cloud.fitted_normal(mesh.vertex(v), ring.normals[v], kSmoothingReach * ring.reach_mm[v]));
    if (fitted != Vec3{}) vertex_normals_[v] = fitted;
  }
  build_shaded_faces([&](std::int32_t v, const Vec3& face_normal) {
    const Vec3 fitted = normalized_or_zero(
        cloud.fitted_normal(mesh.vertex(v), face_normal, kSmoothingReach * ring.reach_mm[v]));
    return fitted != Vec3{} ? fitted : face_normal;
  });
}

ForceShading::ForceShading(const Space& space, const std::vector<Vec3>& source_vertices_mm,
                           const std::vector<std::array<std::int32_t, 3>>& source_triangles)
    : space_(owner_of(space)) {
  check_source(source_vertices_mm, source_triangles);
  const OneRing ring = one_ring_normals(space);
  surface_edge_ = ring.surface_edge;
  vertex_normals_ = ring.normals;
  // Angle-weighted vertex normals of the source.
  std::vector<Vec3> source_normals(source_vertices_mm.size());
  std::vector<Aabb> boxes;
  for (const auto& tri : source_triangles) {
    const std::array<Vec3, 3> x{source_vertices_mm[tri[0]], source_vertices_mm[tri[1]],
                                source_vertices_mm[tri[2]]};
    const Vec3 n = normalized_or_zero(cross(x[1] - x[0], x[2] - x[0]));
    Aabb box;
    for (int k = 0; k < 3; ++k) {
      const Vec3 e1 = normalized_or_zero(x[(k + 1) % 3] - x[k]);
      const Vec3 e2 = normalized_or_zero(x[(k + 2) % 3] - x[k]);
      source_normals[tri[k]] += n * std::acos(std::clamp(dot(e1, e2), -1.0, 1.0));
      box.grow(x[k]);
    }
    boxes.push_back(box);
  }
  for (Vec3& n : source_normals) n = normalized_or_zero(n);
  // Only the source's vertices that some triangle uses carry a normal.
  std::vector<Vec3> points;
  std::vector<Vec3> normals;
  for (std::size_t i = 0; i < source_vertices_mm.size(); ++i) {
    if (source_normals[i] == Vec3{}) continue;
    points.push_back(source_vertices_mm[i]);
    normals.push_back(source_normals[i]);
  }
  const OrientedPoints cloud(points, normals, std::vector<double>(points.size(), 1.0));
  // Per surface vertex: the source's own field at its nearest source point
  // (unsmoothed) and the fit's radius.
  std::vector<Vec3> field(vertex_count());
  std::vector<double> radius(vertex_count(), 0.0);
  if (!boxes.empty()) {
    const NearestTriangle nearest(source_vertices_mm, source_triangles, boxes);
    for (std::int32_t v = 0; v < vertex_count(); ++v) {
      if (ring.normals[v] == Vec3{}) continue;
      const Vec3& x = space.mesh().vertex(v);
      const NearestTriangle::Hit hit = nearest.find(x);
      const auto& tri = source_triangles[hit.triangle];
      field[v] = source_normals[tri[0]] * hit.weights[0] + source_normals[tri[1]] * hit.weights[1] +
                 source_normals[tri[2]] * hit.weights[2];
      if (normalized_or_zero(field[v]) == Vec3{}) continue;
      // The smoothing reaches at least the nearest source triangle's corners,
      // so that a source coarser than the tet surface is fitted through its
      // own vertices rather than left unsmoothed.
      double reach = ring.reach_mm[v];
      for (int k = 0; k < 3; ++k) reach = std::max(reach, norm(source_vertices_mm[tri[k]] - x));
      radius[v] = kSmoothingReach * reach;
      const Vec3 fitted = normalized_or_zero(cloud.fitted_normal(x, field[v], radius[v]));
      vertex_normals_[v] = fitted != Vec3{} ? fitted : normalized_or_zero(field[v]);
    }
  }
  // Unnormalised: on a sphere (or plane) the fit's gradient is the linear
  // field of the source's exact vertex normals, so pieces of a split source
  // triangle interpolating these values reproduce it.
  build_shaded_faces([&](std::int32_t v, const Vec3& face_normal) {
    const Vec3 fitted = cloud.fitted_normal(space.mesh().vertex(v), face_normal, radius[v]);
    if (fitted != Vec3{}) return fitted;
    return dot(field[v], face_normal) > 0.0 ? field[v] : face_normal;
  });
}

void ForceShading::build_shaded_faces(const CornerNormal& corner_normal) {
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
        normal[count] = corner_normal(mesh.tet(t)[v], face_normal);
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

Vec3 ForceShading::contact_normal(const ShadedFace& face, const Vec3& q, const Vec3& p,
                                  double p_height) const {
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
  // normal is normalised.
  Vec3 n = normal_at(q);
  for (int iteration = 0; iteration < kContactIterations; ++iteration) {
    const double along = dot(n, face.normal);
    // along / |n| > 0.5: the normal leans less than 60 degrees off the facet.
    if (!(along > 0.0 && 4.0 * along * along > squared_norm(n))) break;
    const Vec3 next = normal_at(p - n * (p_height / along));
    if (next == Vec3{}) break;
    n = next;
  }
  const double length = norm(n);
  if (!(length > 0.0)) return {};
  return n * (1.0 / length);
}

Vec3 ForceShading::edge_contact_normal(std::int32_t e, const Vec3& p) const {
  // The surface's faces through the edge, each as its non-rigid owner sees it.
  const TetMesh& mesh = space_->mesh();
  std::array<const ShadedFace*, kMaxEdgeFaces> faces{};
  int count = 0;
  for (const EdgeFanEntry& entry : mesh.edge_fan(e)) {
    if (space_->tet_is_rigid(entry.tet)) continue;
    for (const std::int8_t f : entry.faces) {
      const std::int32_t record =
          face_record_[4 * static_cast<std::size_t>(entry.tet) + static_cast<std::size_t>(f)];
      if (record != kNotShaded && count < kMaxEdgeFaces) faces[count++] = &shaded_faces_[record];
    }
  }
  // Each face's contact normal for p; the faces whose line from p lands on
  // the surface (under every other face's plane: a convex edge's material
  // lies under both) are the ones p presses on.
  std::array<Vec3, kMaxEdgeFaces> normals{};
  std::array<bool, kMaxEdgeFaces> lands{};
  const double eps = space_->tolerance();
  for (int k = 0; k < count; ++k) {
    const ShadedFace& face = *faces[k];
    const double height = dot(p - face.origin, face.normal);
    normals[k] = contact_normal(face, p - face.normal * height, p, height);
    const double along = dot(normals[k], face.normal);
    if (normals[k] == Vec3{} || !(along > 0.0)) continue;
    const Vec3 landing = p - normals[k] * (height / along);
    lands[k] = true;
    for (int j = 0; j < count; ++j) {
      if (j != k && dot(landing - faces[j]->origin, faces[j]->normal) > eps) lands[k] = false;
    }
  }
  Vec3 landed;
  Vec3 all;
  for (int k = 0; k < count; ++k) {
    all += normals[k];
    if (lands[k]) landed += normals[k];
  }
  // Neither or each: p presses on the edge itself, between the faces.
  const Vec3 chosen = landed != Vec3{} ? landed : all;
  const double length = norm(chosen);
  if (length > 0.0) return chosen / length;
  return surface_edge_normal(e, p);
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
      // p - q = -raw / k, so p's height over the plane is -normal_part / k.
      const double compliance_mm_per_N = 1.0 / space_->settings().stiffness_N_per_mm;
      shaded_normal = contact_normal(face, place.q, place.q - raw_force_N * compliance_mm_per_N,
                                     -normal_part * compliance_mm_per_N);
      if (shaded_normal == Vec3{}) return raw_force_N;
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

std::array<Vec3, 3> ForceShading::face_corner_normals(std::int32_t t, int f) const {
  const std::int32_t record =
      face_record_.at(4 * static_cast<std::size_t>(t) + static_cast<std::size_t>(f));
  if (record == kNotShaded) return {};
  const ShadedFace& face = shaded_faces_[record];
  std::array<Vec3, 3> out;
  int count = 0;
  for (int v = 0; v < 4; ++v) {
    if (v == f) continue;
    const Vec3 r = space_->mesh().vertex(space_->mesh().tet(t)[v]) - face.origin;
    out[count++] =
        face.origin_normal + Vec3{dot(face.rows[0], r), dot(face.rows[1], r), dot(face.rows[2], r)};
  }
  return out;
}

std::size_t ForceShading::memory_bytes() const {
  return vertex_normals_.capacity() * sizeof(Vec3) + surface_edge_.capacity() +
         shaded_faces_.capacity() * sizeof(ShadedFace) +
         face_record_.capacity() * sizeof(std::int32_t);
}

}  // namespace hapticut
