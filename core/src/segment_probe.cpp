#include "hapticut/segment_probe.h"

#include <algorithm>
#include <limits>

#include "hapticut/tet_mesh.h"

namespace hapticut {

namespace {

// The first boundary face the segment x -> b enters through (the mirror of
// the exit rule: x on or outside the face's plane, b strictly inside), as a
// parameter on x -> b; returns false when it enters nowhere.
bool first_entry(const TetMesh& mesh, const Vec3& x, const Vec3& b, double eps, double& h_out,
                 std::size_t& face_out) {
  double best = std::numeric_limits<double>::infinity();
  std::size_t best_face = 0;
  mesh.boundary_tree().for_each_on_segment(x, b, eps, [&](std::int32_t k) {
    const auto face = static_cast<std::size_t>(k);
    const Plane& plane = mesh.boundary_plane(face);
    const double d0 = plane.signed_distance(x);
    const double d1 = plane.signed_distance(b);
    if (!(d1 < -eps && d0 > d1 && d0 >= -eps)) return;
    const double h = d0 <= 0.0 ? 0.0 : d0 / (d0 - d1);
    const Vec3 c = x + (b - x) * h;
    const Plane* sides = mesh.boundary_side_planes(face);
    for (int s = 0; s < 3; ++s) {
      if (strictly_beyond(sides[s].signed_distance(c), eps)) return;
    }
    if (h < best || (h == best && face < best_face)) {
      best = h;
      best_face = face;
    }
  });
  if (best == std::numeric_limits<double>::infinity()) return false;
  h_out = best;
  face_out = best_face;
  return true;
}

bool is_wall(const Space& space, std::int32_t t, ProbeWalls walls, const CutState* cuts) {
  const MaterialModel model = space.tet_model(t, cuts);
  return model == MaterialModel::Rigid ||
         (walls == ProbeWalls::RigidAndMembrane && model == MaterialModel::Membrane);
}

}  // namespace

SegmentProbe probe_segment(const Space& space, std::int32_t start_tet, const Vec3& a, const Vec3& b,
                           ProbeWalls walls, const CutState* cuts) {
  const TetMesh& mesh = space.mesh();
  const double eps = space.tolerance();
  SegmentProbe result;
  std::int32_t t = start_tet;
  Vec3 x = a;
  double s = 0.0;  // x = a + s (b - a), kept for the fraction reported.
  for (int step = 0; step < kSegmentProbeMaxSteps; ++step) {
    if (t == kNoTet) {
      double h = 0.0;
      std::size_t face = 0;
      if (!first_entry(mesh, x, b, eps, h, face)) {
        result.end_tet = kNoTet;
        return result;
      }
      s += (1.0 - s) * h;
      x = x + (b - x) * h;
      const std::int32_t u = mesh.boundary_faces()[face].tet;
      if (is_wall(space, u, walls, cuts)) {
        result.hit = true;
        result.fraction = s;
        result.contact = mesh.boundary_plane(face);  // Outward: out of the rigid tet.
        result.wall_tet = u;
        return result;
      }
      t = u;
      continue;
    }
    // The face the segment leaves t through first (the hit is at 0 when x
    // already lies on it).
    const TetExit exit = first_exit(mesh, t, x, b, eps);
    if (exit.face < 0) {
      result.end_tet = t;
      return result;
    }
    s += (1.0 - s) * exit.fraction;
    x = x + (b - x) * exit.fraction;
    const std::int32_t u = mesh.neighbour(t, exit.face);
    if (u != kNoTet && is_wall(space, u, walls, cuts)) {
      result.hit = true;
      result.fraction = s;
      const Plane& face = mesh.face_plane(t, exit.face);
      result.contact = Plane{face.normal * -1.0, -face.offset};
      result.wall_tet = u;
      result.owner_tet = t;
      result.owner_face = static_cast<std::int8_t>(exit.face);
      return result;
    }
    t = u;
  }
  result.hit = true;
  result.exhausted = true;
  result.fraction = s;
  return result;
}

std::int32_t locate_for_probe(const Space& space, const Vec3& p, bool& inside_rigid) {
  const TetMesh& mesh = space.mesh();
  const double eps = space.tolerance();
  std::int32_t best = kNoTet;
  double best_distance = eps;
  bool any_rigid = false;
  mesh.tet_tree().for_each_containing(p, eps, [&](std::int32_t t) {
    const double d = mesh.outside_distance(t, p);
    if (d > eps) return;
    if (space.tet_is_rigid(t)) {
      any_rigid = any_rigid || d < -eps;
      return;
    }
    // The tet that holds p deepest; the lowest index on a tie, whatever the tree's order.
    if (best == kNoTet || d < best_distance || (d == best_distance && t < best)) {
      best_distance = d;
      best = t;
    }
  });
  inside_rigid = best == kNoTet && any_rigid;
  return best;
}

}  // namespace hapticut
