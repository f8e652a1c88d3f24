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

namespace {

// One stretch's motion tested edge by edge; keeps the earliest crossing.
class StretchSweep {
 public:
  StretchSweep(const RigidSurfaceEdges& edges, const Vec3& a0, const Vec3& b0, const Vec3& a1,
               const Vec3& b1, double tolerance_mm)
      : edges_(edges),
        a0_(a0),
        b0_(b0),
        a1_(a1),
        b1_(b1),
        tolerance_(tolerance_mm),
        // Each triangle's plane, once: an edge with both ends strictly on one
        // side of it cannot cross it (most edges near a patch that slides
        // over the surface lie under it).
        n1_(cross(b0 - a0, b1 - a0)),
        n2_(cross(b1 - a0, a1 - a0)) {}

  Aabb box() const { return motion_box(a0_, b0_, a1_, b1_, tolerance_); }

  void consider(std::int32_t k) {
    const auto& seg = edges_.segment(k);
    const bool off1 = one_side(n1_, seg[0], seg[1]);
    const bool off2 = one_side(n2_, seg[0], seg[1]);
    if (off1 && off2) return;
    // The patch's (along, motion) at a crossing: triangle a0 b0 b1 holds
    // (0,0), (1,0), (1,1); triangle a0 b1 a1 holds (0,0), (1,1), (0,1).
    double u = 0.0;
    double v = 0.0;
    double along = 0.0;
    double motion = 0.0;
    if (!off1 && segment_crosses_triangle(seg[0], seg[1], a0_, b0_, b1_, u, v)) {
      along = u + v;
      motion = v;
    } else if (!off2 && segment_crosses_triangle(seg[0], seg[1], a0_, b1_, a1_, u, v)) {
      along = u;
      motion = u + v;
    } else {
      return;
    }
    // The stretch's sample there, at the start and as it moves.
    const Vec3 start = a0_ + (b0_ - a0_) * along;
    const Vec3 moved = (a1_ + (b1_ - a1_) * along) - start;
    const Vec3 edge = seg[1] - seg[0];
    const Vec3 stretch = (b0_ - a0_) + ((b1_ - a1_) - (b0_ - a0_)) * motion;
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
    const int side = edges_.material_side(k, normal, tolerance_, rigid_tet);
    if (side == 0) return;
    if (side > 0) normal = -normal;
    const Plane plane{normal, dot(normal, seg[0])};
    // Only a stretch that goes into the material's side is stopped.
    const double from_plane = plane.signed_distance(start);
    const double to_plane = plane.signed_distance(start + moved);
    if (to_plane > -tolerance_) return;
    // The sample moves on a straight line, so it reaches the plane (where it
    // meets the edge) at one motion: the patch's triangles only approximate
    // where, and badly near an end that hardly moves (a turn about it).
    motion = from_plane <= 0.0 ? 0.0 : std::min(motion, from_plane / (from_plane - to_plane));
    // The earliest crossing; of crossings at one motion, the one nearest the
    // stretch's start, then the plane first in plane_before's order (not the
    // tree's order, which follows the tets').
    if (best_.hit && (motion > best_.motion || (motion == best_.motion && along > best_.along))) {
      return;
    }
    if (best_.hit && motion == best_.motion && along == best_.along &&
        !plane_before(plane, best_.contact)) {
      return;
    }
    best_.hit = true;
    best_.motion = motion;
    best_.along = along;
    best_.contact = plane;
    best_.wall_tet = rigid_tet;
    best_.mesh_edge = edges_.mesh_edge(k);
  }

  SweptHit result(double motion_from, double motion_to) const {
    SweptHit out = best_;
    if (out.hit) out.motion = motion_from + (motion_to - motion_from) * out.motion;
    return out;
  }

 private:
  bool one_side(const Vec3& normal, const Vec3& p, const Vec3& q) const {
    const double dp = dot(normal, p - a0_);
    const double dq = dot(normal, q - a0_);
    return (dp > 0.0 && dq > 0.0) || (dp < 0.0 && dq < 0.0);
  }

  const RigidSurfaceEdges& edges_;
  Vec3 a0_;
  Vec3 b0_;
  Vec3 a1_;
  Vec3 b1_;
  double tolerance_;
  Vec3 n1_;
  Vec3 n2_;
  SweptHit best_;
};

}  // namespace

SweptHit sweep_stretch(const RigidSurfaceEdges& edges, const Vec3& a0, const Vec3& b0,
                       const Vec3& a1, const Vec3& b1, double motion_from, double motion_to,
                       double tolerance_mm) {
  StretchSweep sweep(edges, a0, b0, a1, b1, tolerance_mm);
  edges.tree().for_each_overlapping(sweep.box(), [&](std::int32_t k) { sweep.consider(k); });
  return sweep.result(motion_from, motion_to);
}

SweptHit sweep_stretch_among(const RigidSurfaceEdges& edges,
                             std::span<const std::int32_t> candidates, const Vec3& a0,
                             const Vec3& b0, const Vec3& a1, const Vec3& b1, double motion_from,
                             double motion_to, double tolerance_mm) {
  StretchSweep sweep(edges, a0, b0, a1, b1, tolerance_mm);
  const Aabb box = sweep.box();
  for (const std::int32_t k : candidates) {
    Aabb edge;
    edge.grow(edges.segment(k)[0]);
    edge.grow(edges.segment(k)[1]);
    if (edge.overlaps(box)) sweep.consider(k);
  }
  return sweep.result(motion_from, motion_to);
}

int swept_pieces(double turn_rad, double length_mm, double deviation_mm) {
  if (!(turn_rad > 0.0) || !(length_mm > 0.0)) return 1;
  // r theta^2 / 8 <= deviation for each piece's theta = turn / pieces.
  const double most_turn = std::sqrt(8.0 * deviation_mm / length_mm);
  const double pieces = std::ceil(turn_rad / most_turn);
  return static_cast<int>(std::clamp(pieces, 1.0, double(kMaxSweptPieces)));
}

}  // namespace hapticut
