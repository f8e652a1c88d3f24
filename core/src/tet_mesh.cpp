#include "hapticut/tet_mesh.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "hapticut/parameter_range.h"

namespace hapticut {

namespace {

struct KeyedItem {
  std::array<std::int32_t, 3> key;
  std::int32_t tet;
  std::int8_t local;
  bool operator<(const KeyedItem& o) const { return key < o.key; }
};

std::array<std::int32_t, 3> sorted3(std::int32_t a, std::int32_t b, std::int32_t c) {
  std::array<std::int32_t, 3> k{a, b, c};
  std::sort(k.begin(), k.end());
  return k;
}

std::array<int, 3> face_local_vertices(int face) {
  std::array<int, 3> out{};
  int n = 0;
  for (int v = 0; v < 4; ++v) {
    if (v != face) out[n++] = v;
  }
  return out;
}

}  // namespace

TetMesh::TetMesh(std::vector<Vec3> vertices_mm, std::vector<std::array<std::int32_t, 4>> tets,
                 std::vector<std::int32_t> tet_materials, double tolerance_mm)
    : vertices_(std::move(vertices_mm)),
      tets_(std::move(tets)),
      materials_(std::move(tet_materials)) {
  check_in_range(setting_range::kTolerance, tolerance_mm, "tolerance_mm");
  validate_and_orient();
  reject_duplicate_tets();
  Aabb box;
  for (const Vec3& v : vertices_) box.grow(v);
  tolerance_ = tolerance_mm > 0.0 ? tolerance_mm : kRelativeTolerance * norm(box.hi - box.lo);
  build_faces();
  build_edges();
  build_vertex_fans();
  build_trees();
  reject_overlapping_tets();
  compute_stats();
}

double TetMesh::signed_volume(std::int32_t t) const {
  const auto& tv = tets_[t];
  const Vec3& a = vertices_[tv[0]];
  return signed_tet_volume(a, vertices_[tv[1]], vertices_[tv[2]], vertices_[tv[3]]);
}

void TetMesh::validate_and_orient() {
  if (tets_.empty()) throw MeshError("mesh has no tets", -1);
  if (materials_.size() != tets_.size()) {
    throw MeshError("tet_materials has " + std::to_string(materials_.size()) + " entries for " +
                        std::to_string(tets_.size()) + " tets",
                    -1);
  }
  for (std::size_t v = 0; v < vertices_.size(); ++v) {
    if (!is_finite(vertices_[v])) {
      throw MeshError("vertex " + std::to_string(v) + " has a NaN or infinite coordinate",
                      static_cast<std::int64_t>(v));
    }
  }
  const auto vertex_count = static_cast<std::int64_t>(vertices_.size());
  for (std::size_t t = 0; t < tets_.size(); ++t) {
    const auto index = static_cast<std::int64_t>(t);
    auto& tv = tets_[t];
    for (int k = 0; k < 4; ++k) {
      if (tv[k] < 0 || tv[k] >= vertex_count) {
        throw MeshError("tet " + std::to_string(t) + " refers to vertex " + std::to_string(tv[k]) +
                            ", out of range (" + std::to_string(vertex_count) + " vertices)",
                        index);
      }
      for (int j = 0; j < k; ++j) {
        if (tv[j] == tv[k]) {
          throw MeshError("tet " + std::to_string(t) + " repeats vertex " + std::to_string(tv[k]),
                          index);
        }
      }
    }
    if (materials_[t] < 0) {
      throw MeshError("tet " + std::to_string(t) + " has negative material index", index);
    }
    const double volume6 = 6.0 * signed_volume(static_cast<std::int32_t>(t));
    if (tet_has_no_volume({vertices_[tv[0]], vertices_[tv[1]], vertices_[tv[2]], vertices_[tv[3]]},
                          volume6)) {
      throw MeshError("tet " + std::to_string(t) + " has zero volume", index);
    }
    if (volume6 < 0.0) {
      std::swap(tv[2], tv[3]);
      ++stats_.reoriented_tets;
    }
  }
}

// A tet listed twice leaves the body without boundary faces: the proxy would
// pass through it with zero force.
void TetMesh::reject_duplicate_tets() const {
  std::vector<std::pair<std::array<std::int32_t, 4>, std::int32_t>> sorted(tets_.size());
  for (std::size_t t = 0; t < tets_.size(); ++t) {
    auto key = tets_[t];
    std::sort(key.begin(), key.end());
    sorted[t] = {key, static_cast<std::int32_t>(t)};
  }
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t k = 1; k < sorted.size(); ++k) {
    if (sorted[k].first != sorted[k - 1].first) continue;
    const auto& v = sorted[k].first;
    throw MeshError("tets " + std::to_string(sorted[k - 1].second) + " and " +
                        std::to_string(sorted[k].second) + " are the same tet (vertices " +
                        std::to_string(v[0]) + ", " + std::to_string(v[1]) + ", " +
                        std::to_string(v[2]) + ", " + std::to_string(v[3]) + ")",
                    sorted[k].second);
  }
}

// Interiors must be disjoint. Tets across a face are separated by its plane
// (build_faces rejects folds); for the rest, five points well inside each tet
// (its centroid and the midpoints from there to its vertices) must lie in no
// other tet by more than the tolerance. A sampled test: it finds every
// duplicate-like or substantial overlap, not a sliver-thin one (decisions.md).
void TetMesh::reject_overlapping_tets() const {
  for (std::size_t t = 0; t < tets_.size(); ++t) {
    const auto& tv = tets_[t];
    const Vec3 centroid =
        (vertices_[tv[0]] + vertices_[tv[1]] + vertices_[tv[2]] + vertices_[tv[3]]) * 0.25;
    std::array<Vec3, 5> samples{centroid};
    for (int k = 0; k < 4; ++k) samples[k + 1] = (centroid + vertices_[tv[k]]) * 0.5;
    const auto self = static_cast<std::int32_t>(t);
    for (const Vec3& sample : samples) {
      tet_tree_.for_each_containing(sample, 0.0, [&](std::int32_t other) {
        if (other == self || outside_distance(other, sample) >= -tolerance_) return;
        throw MeshError("tets " + std::to_string(std::min(self, other)) + " and " +
                            std::to_string(std::max(self, other)) +
                            " overlap (a point well inside tet " + std::to_string(self) +
                            " is inside tet " + std::to_string(other) + ")",
                        std::max(self, other));
      });
    }
  }
}

void TetMesh::build_faces() {
  const std::size_t n = tets_.size();
  planes_.resize(n);
  neighbours_.assign(4 * n, kNoTet);
  neighbour_faces_.assign(4 * n, 0);
  std::vector<KeyedItem> faces;
  faces.reserve(4 * n);
  for (std::size_t t = 0; t < n; ++t) {
    const auto& tv = tets_[t];
    for (int f = 0; f < 4; ++f) {
      const auto lv = face_local_vertices(f);
      faces.push_back({sorted3(tv[lv[0]], tv[lv[1]], tv[lv[2]]), static_cast<std::int32_t>(t),
                       static_cast<std::int8_t>(f)});
    }
  }
  std::sort(faces.begin(), faces.end());
  for (std::size_t k = 0; k < faces.size();) {
    std::size_t end = k + 1;
    while (end < faces.size() && faces[end].key == faces[k].key) ++end;
    if (end - k > 2) {
      throw MeshError("a face (vertices " + std::to_string(faces[k].key[0]) + ", " +
                          std::to_string(faces[k].key[1]) + ", " + std::to_string(faces[k].key[2]) +
                          ") is shared by more than two tets, " + "among them tet " +
                          std::to_string(faces[k + 2].tet),
                      faces[k + 2].tet);
    }
    // The plane comes from the sorted vertex triple, so the two tets sharing
    // a face get exactly opposite planes: no gap or overlap from rounding.
    const auto& key = faces[k].key;
    const Vec3& a = vertices_[key[0]];
    Vec3 normal = cross(vertices_[key[1]] - a, vertices_[key[2]] - a);
    normal = normal / norm(normal);
    const double offset = dot(normal, a);
    std::array<bool, 2> flipped{};
    for (std::size_t j = k; j < end; ++j) {
      const auto& item = faces[j];
      const Vec3& opposite = vertices_[tets_[item.tet][item.local]];
      const bool flip = dot(normal, opposite) - offset > 0.0;
      flipped[j - k] = flip;
      planes_[item.tet].face[item.local] = flip ? Plane{-normal, -offset} : Plane{normal, offset};
    }
    // Two tets on the same side of their shared face overlap and would get
    // the same plane: the walk could not leave one for the other.
    if (end - k == 2 && flipped[0] == flipped[1]) {
      throw MeshError("tets " + std::to_string(faces[k].tet) + " and " +
                          std::to_string(faces[k + 1].tet) +
                          " lie on the same side of their shared face (vertices " +
                          std::to_string(key[0]) + ", " + std::to_string(key[1]) + ", " +
                          std::to_string(key[2]) + "): the mesh is folded",
                      std::max(faces[k].tet, faces[k + 1].tet));
    }
    if (end - k == 2) {
      const auto& f0 = faces[k];
      const auto& f1 = faces[k + 1];
      neighbours_[4 * f0.tet + f0.local] = f1.tet;
      neighbour_faces_[4 * f0.tet + f0.local] = f1.local;
      neighbours_[4 * f1.tet + f1.local] = f0.tet;
      neighbour_faces_[4 * f1.tet + f1.local] = f0.local;
    } else {
      boundary_faces_.push_back({faces[k].tet, faces[k].local});
    }
    k = end;
  }
  std::sort(boundary_faces_.begin(), boundary_faces_.end(), [](const FaceRef& x, const FaceRef& y) {
    return x.tet != y.tet ? x.tet < y.tet : x.face < y.face;
  });
}

void TetMesh::build_edges() {
  const std::size_t n = tets_.size();
  std::vector<KeyedItem> edges;
  edges.reserve(6 * n);
  for (std::size_t t = 0; t < n; ++t) {
    const auto& tv = tets_[t];
    for (int e = 0; e < 6; ++e) {
      const std::int32_t a = tv[kEdgeVertices[e][0]];
      const std::int32_t b = tv[kEdgeVertices[e][1]];
      edges.push_back({{std::min(a, b), std::max(a, b), 0},
                       static_cast<std::int32_t>(t),
                       static_cast<std::int8_t>(e)});
    }
  }
  std::sort(edges.begin(), edges.end());
  tet_edges_.assign(6 * n, -1);
  tet_edge_fans_.assign(6 * n, {0, 0});
  edge_fan_.reserve(edges.size());
  for (std::size_t k = 0; k < edges.size();) {
    std::size_t end = k + 1;
    while (end < edges.size() && edges[end].key == edges[k].key) ++end;
    const auto id = static_cast<std::int32_t>(edge_vertices_.size());
    const std::int32_t v0 = edges[k].key[0];
    const std::int32_t v1 = edges[k].key[1];
    edge_vertices_.push_back({v0, v1});
    const Vec3 d = vertices_[v1] - vertices_[v0];
    edge_directions_.push_back(d / norm(d));
    const auto fan_begin = static_cast<std::int32_t>(edge_fan_.size());
    const auto fan_end = static_cast<std::int32_t>(fan_begin + (end - k));
    edge_fan_start_.push_back(fan_begin);
    for (std::size_t j = k; j < end; ++j) {
      const int e = edges[j].local;
      tet_edges_[6 * edges[j].tet + e] = id;
      tet_edge_fans_[6 * edges[j].tet + e] = {fan_begin, fan_end};
      edge_fan_.push_back({edges[j].tet,
                           static_cast<std::int8_t>(e),
                           {static_cast<std::int8_t>(kEdgeFaces[e][0]),
                            static_cast<std::int8_t>(kEdgeFaces[e][1])}});
    }
    k = end;
  }
  edge_fan_start_.push_back(static_cast<std::int32_t>(edge_fan_.size()));

  boundary_edge_.assign(edge_vertices_.size(), 0);
  boundary_vertex_.assign(vertices_.size(), 0);
  for (const FaceRef& f : boundary_faces_) {
    for (int other = 0; other < 4; ++other) {
      if (other == f.face) continue;
      boundary_edge_[edge_of(f.tet, kEdgeOfFaces[f.face][other])] = 1;
      boundary_vertex_[tets_[f.tet][other]] = 1;
    }
  }
}

void TetMesh::build_vertex_fans() {
  vertex_fan_start_.assign(vertices_.size() + 1, 0);
  for (const auto& tv : tets_) {
    for (std::int32_t v : tv) ++vertex_fan_start_[v + 1];
  }
  for (std::size_t v = 0; v < vertices_.size(); ++v)
    vertex_fan_start_[v + 1] += vertex_fan_start_[v];
  vertex_fan_.resize(4 * tets_.size());
  std::vector<std::int32_t> cursor(vertex_fan_start_.begin(), vertex_fan_start_.end() - 1);
  for (std::size_t t = 0; t < tets_.size(); ++t) {
    for (int k = 0; k < 4; ++k) {
      vertex_fan_[cursor[tets_[t][k]]++] = {static_cast<std::int32_t>(t),
                                            static_cast<std::int8_t>(k)};
    }
  }
}

void TetMesh::build_trees() {
  boundary_planes_.clear();
  boundary_side_planes_.clear();
  for (const FaceRef& f : boundary_faces_) {
    const Plane& plane = face_plane(f.tet, f.face);
    boundary_planes_.push_back(plane);
    for (const int side : kOtherFaces[f.face])
      boundary_side_planes_.push_back(face_plane(f.tet, side));
    boundary_plane_columns_[0].push_back(plane.normal.x);
    boundary_plane_columns_[1].push_back(plane.normal.y);
    boundary_plane_columns_[2].push_back(plane.normal.z);
    boundary_plane_columns_[3].push_back(plane.offset);
  }
  std::vector<Aabb> boxes(boundary_faces_.size());
  for (std::size_t k = 0; k < boundary_faces_.size(); ++k) {
    const FaceRef& f = boundary_faces_[k];
    for (int v : face_local_vertices(f.face)) boxes[k].grow(vertices_[tets_[f.tet][v]]);
  }
  boundary_tree_ = AabbTree(boxes);
  boxes.assign(tets_.size(), Aabb{});
  for (std::size_t t = 0; t < tets_.size(); ++t) {
    for (std::int32_t v : tets_[t]) boxes[t].grow(vertices_[v]);
  }
  tet_tree_ = AabbTree(boxes);
}

void TetMesh::compute_stats() {
  stats_.boundary_faces = static_cast<std::int64_t>(boundary_faces_.size());
  for (std::size_t e = 0; e + 1 < edge_fan_start_.size(); ++e) {
    stats_.max_tets_per_edge =
        std::max(stats_.max_tets_per_edge, edge_fan_start_[e + 1] - edge_fan_start_[e]);
  }
  stats_.mean_tets_per_edge =
      edge_vertices_.empty() ? 0.0 : double(edge_fan_.size()) / double(edge_vertices_.size());
  std::int64_t used_vertices = 0;
  for (std::size_t v = 0; v + 1 < vertex_fan_start_.size(); ++v) {
    const int count = vertex_fan_start_[v + 1] - vertex_fan_start_[v];
    stats_.max_tets_per_vertex = std::max(stats_.max_tets_per_vertex, count);
    used_vertices += count > 0 ? 1 : 0;
  }
  stats_.mean_tets_per_vertex =
      used_vertices == 0 ? 0.0 : double(vertex_fan_.size()) / double(used_vertices);
  double min_angle = std::numbers::pi;
  for (std::size_t t = 0; t < tets_.size(); ++t) {
    for (int i = 0; i < 4; ++i) {
      for (int j = i + 1; j < 4; ++j) {
        const double c =
            std::clamp(dot(planes_[t].face[i].normal, planes_[t].face[j].normal), -1.0, 1.0);
        min_angle = std::min(min_angle, std::numbers::pi - std::acos(c));
      }
    }
  }
  stats_.min_dihedral_deg = min_angle * 180.0 / std::numbers::pi;
}

double TetMesh::outside_distance(std::int32_t t, const Vec3& p) const {
  double worst = -1e300;
  for (int f = 0; f < 4; ++f) worst = std::max(worst, face_plane(t, f).signed_distance(p));
  return worst;
}

std::int32_t TetMesh::locate(const Vec3& p) const {
  std::int32_t best = kNoTet;
  double best_distance = tolerance_;
  tet_tree_.for_each_containing(p, tolerance_, [&](std::int32_t t) {
    const double d = outside_distance(t, p);
    if (d <= best_distance) {
      best_distance = d;
      best = t;
    }
  });
  return best;
}

std::size_t TetMesh::memory_bytes() const {
  return vertices_.capacity() * sizeof(Vec3) + tets_.capacity() * sizeof(tets_[0]) +
         materials_.capacity() * 4 + planes_.capacity() * sizeof(TetPlanes) +
         neighbours_.capacity() * 4 + neighbour_faces_.capacity() + tet_edges_.capacity() * 4 +
         tet_edge_fans_.capacity() * sizeof(tet_edge_fans_[0]) + edge_vertices_.capacity() * 8 +
         edge_directions_.capacity() * sizeof(Vec3) + edge_fan_start_.capacity() * 4 +
         edge_fan_.capacity() * sizeof(EdgeFanEntry) + vertex_fan_start_.capacity() * 4 +
         vertex_fan_.capacity() * sizeof(VertexFanEntry) + boundary_edge_.capacity() +
         boundary_vertex_.capacity() + boundary_faces_.capacity() * sizeof(FaceRef) +
         boundary_planes_.capacity() * sizeof(Plane) +
         boundary_side_planes_.capacity() * sizeof(Plane) + boundary_tree_.memory_bytes() +
         tet_tree_.memory_bytes();
}

double distance_to_tet(const TetMesh& mesh, std::int32_t t, const Vec3& x) {
  if (mesh.outside_distance(t, x) <= 0.0) return 0.0;
  const auto& tet = mesh.tet(t);
  double best = std::numeric_limits<double>::infinity();
  for (int f = 0; f < 4; ++f) {
    std::array<Vec3, 3> corner;
    for (int v = 0, n = 0; v < 4; ++v) {
      if (v != f) corner[n++] = mesh.vertex(tet[v]);
    }
    best = std::min(best, norm(closest_point_on_triangle(x, corner[0], corner[1], corner[2]) - x));
  }
  return best;
}

bool lies_in_mesh_interior(const TetMesh& mesh, const Vec3& x, double margin) {
  bool near_tet = false;
  bool near_boundary = false;
  mesh.tet_tree().for_each_containing(x, margin, [&](std::int32_t t) {
    // A plane distance never exceeds the Euclidean one: past margin, t is too far.
    if (near_boundary || mesh.outside_distance(t, x) > margin) return;
    const auto& tet = mesh.tet(t);
    for (int f = 0; f < 4 && !near_boundary; ++f) {
      if (mesh.neighbour(t, f) != kNoTet) continue;
      std::array<Vec3, 3> corner;
      for (int v = 0, n = 0; v < 4; ++v) {
        if (v != f) corner[n++] = mesh.vertex(tet[v]);
      }
      near_boundary =
          norm(closest_point_on_triangle(x, corner[0], corner[1], corner[2]) - x) <= margin;
    }
    near_tet = near_tet || distance_to_tet(mesh, t, x) <= margin;
  });
  return near_tet && !near_boundary;
}

Aabb mesh_box(const TetMesh& mesh, double pad) {
  Aabb box;
  for (const Vec3& v : mesh.vertices()) box.grow(v);
  return grown(box, pad);
}

}  // namespace hapticut
