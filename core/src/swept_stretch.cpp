#include "hapticut/swept_stretch.h"

#include <algorithm>
#include <cmath>
#include <tuple>
#include <utility>

namespace hapticut {

RigidSurfaceEdges::RigidSurfaceEdges(const Space& space) : space_(&space) {
  const TetMesh& mesh = space.mesh();
  std::vector<Aabb> boxes;
  for (std::int32_t e = 0; e < mesh.edge_count(); ++e) {
    bool rigid = false;
    bool other = mesh.is_boundary_edge(e);
    for (const EdgeFanEntry& entry : mesh.edge_fan(e)) {
      if (space.tet_is_rigid(entry.tet)) {
        rigid = true;
      } else {
        other = true;
      }
    }
    if (!rigid || !other) continue;
    const auto& v = mesh.edge_vertices(e);
    // Ends in coordinate order, not index order: the same edge of a scene
    // stored in another order gives the same numbers.
    Vec3 a = mesh.vertex(v[0]);
    Vec3 b = mesh.vertex(v[1]);
    if (std::tie(b.x, b.y, b.z) < std::tie(a.x, a.y, a.z)) std::swap(a, b);
    segments_.push_back({a, b});
    mesh_edges_.push_back(e);
    Aabb box;
    box.grow(mesh.vertex(v[0]));
    box.grow(mesh.vertex(v[1]));
    boxes.push_back(box);
  }
  tree_ = AabbTree(boxes);
}

int RigidSurfaceEdges::material_side(std::int32_t k, const Vec3& normal, double tolerance_mm,
                                     std::int32_t& rigid_tet) const {
  const TetMesh& mesh = space_->mesh();
  const Vec3& origin = segments_[k][0];
  double least = 0.0;
  double most = 0.0;
  for (const EdgeFanEntry& entry : mesh.edge_fan(mesh_edges_[k])) {
    if (!space_->tet_is_rigid(entry.tet)) continue;
    rigid_tet = entry.tet;
    for (std::int32_t v : mesh.tet(entry.tet)) {
      const double d = dot(normal, mesh.vertex(v) - origin);
      least = std::min(least, d);
      most = std::max(most, d);
    }
  }
  const bool above = most > tolerance_mm;
  const bool below = least < -tolerance_mm;
  if (above == below) return 0;
  return above ? 1 : -1;
}

namespace {

// Where segment p -> q crosses triangle v0 v1 v2 (Moller and Trumbore): the
// barycentric weights of v1 and v2. False when it does not, or lies in the
// triangle's plane (a patch that does not move sweeps no area).
bool segment_crosses_triangle(const Vec3& p, const Vec3& q, const Vec3& v0, const Vec3& v1,
                              const Vec3& v2, double& u, double& v) {
  const Vec3 e1 = v1 - v0;
  const Vec3 e2 = v2 - v0;
  const Vec3 dir = q - p;
  const Vec3 h = cross(dir, e2);
  const double det = dot(e1, h);
  const double scale = norm(e1) * norm(e2) * norm(dir);
  if (!(std::abs(det) > 1e-14 * scale)) return false;
  const Vec3 s = p - v0;
  u = dot(s, h) / det;
  if (u < 0.0 || u > 1.0) return false;
  const Vec3 r = cross(s, e1);
  v = dot(dir, r) / det;
  if (v < 0.0 || u + v > 1.0) return false;
  const double t = dot(e2, r) / det;
  return t >= 0.0 && t <= 1.0;
}

}  // namespace

SweptHit sweep_stretch(const RigidSurfaceEdges& edges, const Vec3& a0, const Vec3& b0,
                       const Vec3& a1, const Vec3& b1, double motion_from, double motion_to,
                       double tolerance_mm) {
  SweptHit best;
  Aabb box;
  box.grow(a0);
  box.grow(b0);
  box.grow(a1);
  box.grow(b1);
  const Vec3 pad{tolerance_mm, tolerance_mm, tolerance_mm};
  box.lo = box.lo - pad;
  box.hi = box.hi + pad;
  edges.tree().for_each_overlapping(box, [&](std::int32_t k) {
    const auto& seg = edges.segment(k);
    // The patch's (along, motion) at a crossing: triangle a0 b0 b1 holds
    // (0,0), (1,0), (1,1); triangle a0 b1 a1 holds (0,0), (1,1), (0,1).
    double u = 0.0;
    double v = 0.0;
    double along = 0.0;
    double motion = 0.0;
    if (segment_crosses_triangle(seg[0], seg[1], a0, b0, b1, u, v)) {
      along = u + v;
      motion = v;
    } else if (segment_crosses_triangle(seg[0], seg[1], a0, b1, a1, u, v)) {
      along = u;
      motion = u + v;
    } else {
      return;
    }
    // The earliest crossing; of crossings at one motion, the one nearest the
    // stretch's start. Ties (edges meeting at a vertex) are settled after the
    // plane is known, not by the tree's order, which follows the tets'.
    if (best.hit && (motion > best.motion || (motion == best.motion && along > best.along))) {
      return;
    }
    // The stretch's sample there, at the start and as it moves.
    const Vec3 start = a0 + (b0 - a0) * along;
    const Vec3 moved = (a1 + (b1 - a1) * along) - start;
    const Vec3 edge = seg[1] - seg[0];
    const Vec3 stretch = (b0 - a0) + ((b1 - a1) - (b0 - a0)) * motion;
    Vec3 normal = cross(edge, stretch);
    double size = norm(normal);
    if (!(size > 1e-9 * norm(edge) * norm(stretch))) {
      // The rigid edge runs along the stretch: the plane through it across the motion.
      const double edge_size2 = squared_norm(edge);
      normal = moved - edge * (dot(moved, edge) / (edge_size2 > 0.0 ? edge_size2 : 1.0));
      size = norm(normal);
      if (!(size > 0.0)) return;
    }
    normal = normal / size;
    std::int32_t rigid_tet = kNoTet;
    const int side = edges.material_side(k, normal, tolerance_mm, rigid_tet);
    if (side == 0) return;
    if (side > 0) normal = -normal;
    const Plane plane{normal, dot(normal, seg[0])};
    // Only a stretch that goes into the material's side is stopped.
    if (plane.signed_distance(start + moved) > -tolerance_mm) return;
    if (best.hit && motion == best.motion && along == best.along &&
        !plane_before(plane, best.contact)) {
      return;
    }
    best.hit = true;
    best.motion = motion;
    best.along = along;
    best.contact = plane;
    best.wall_tet = rigid_tet;
  });
  if (best.hit) best.motion = motion_from + (motion_to - motion_from) * best.motion;
  return best;
}

int swept_pieces(double turn_rad, double length_mm, double deviation_mm) {
  if (!(turn_rad > 0.0) || !(length_mm > 0.0)) return 1;
  // r theta^2 / 8 <= deviation for each piece's theta = turn / pieces.
  const double most_turn = std::sqrt(8.0 * deviation_mm / length_mm);
  const double pieces = std::ceil(turn_rad / most_turn);
  return static_cast<int>(std::clamp(pieces, 1.0, double(kMaxSweptPieces)));
}

}  // namespace hapticut
