#include "hapticut/cut_state.h"

#include <algorithm>
#include <array>
#include <stdexcept>
#include <string>

#include "hapticut/proxy_place.h"
#include "hapticut/scene.h"
#include "hapticut/space.h"
#include "hapticut/tet_mesh.h"

namespace hapticut {

CutState::CutState(std::shared_ptr<const Space> space) : space_(std::move(space)) {
  if (!space_) throw std::invalid_argument("a CutState needs a Space");
  cut_.assign(static_cast<std::size_t>(space_->mesh().tet_count()), 0);
  order_.assign(cut_.size(), 0);
}

void CutState::mark(std::int32_t t) {
  cut_[t] = 1;
  order_[static_cast<std::size_t>(cut_count_)] = t;
  ++cut_count_;
}

bool CutState::cut_if_inside(std::int32_t t, const Vec3& x) {
  if (cut_[t] != 0) return false;
  // The tet's own material decides: a tet of flesh whose cut variant is free
  // is still flesh that the blade cut.
  if (!is_cuttable(space_->own_model(t))) return false;
  // Inside by more than the tolerance: a point resting on a membrane's outer
  // face (a rigid blade's ideal point, seated in the membrane's tet) touches
  // the skin without opening it.
  if (!(space_->mesh().outside_distance(t, x) < -space_->tolerance())) return false;
  mark(t);
  return true;
}

namespace {

// The walk of segment_probe.cpp's probe_segment, without walls: from
// `start_tet` (whose closure holds a), in each tet the face the segment a -> b
// leaves by first (only a plane it strictly exits counts), at most `most`
// tets. visit(t, middle, holds_b) for each: `middle` is the middle of the
// segment's piece in t, inside t exactly when the piece crosses t's inside
// (a tet is convex: a piece along a face crosses neither side); the last,
// b's own tet, has holds_b set.
template <typename Visit>
void walk_segment(const TetMesh& mesh, double eps, std::int32_t start_tet, const Vec3& a,
                  const Vec3& b, int most, Visit&& visit) {
  std::int32_t t = start_tet;
  Vec3 x = a;
  for (int step = 0; t >= 0 && t < mesh.tet_count() && step < most; ++step) {
    const TetExit exit = first_exit(mesh, t, x, b, eps);
    const Vec3 leave = exit.face < 0 ? b : x + (b - x) * exit.fraction;
    visit(t, (x + leave) * 0.5, exit.face < 0);
    if (exit.face < 0) return;
    x = leave;
    t = mesh.neighbour(t, exit.face);
  }
}

}  // namespace

int CutState::cut_along(std::int32_t start_tet, const Vec3& a, const Vec3& b) {
  const TetMesh& mesh = space_->mesh();
  const double eps = space_->tolerance();
  int newly_cut = 0;
  // b's own tet: the point has not left it.
  walk_segment(mesh, eps, start_tet, a, b, kMaxChordTets,
               [&](std::int32_t t, const Vec3& middle, bool holds_b) {
                 if (!holds_b && mesh.outside_distance(t, b) > eps && cut_if_inside(t, middle)) {
                   ++newly_cut;
                 }
               });
  return newly_cut;
}

int CutState::tets_crossed(std::int32_t start_tet, const Vec3& a, const Vec3& b,
                           std::array<std::int32_t, kMaxEdgeTets>& out) const {
  const TetMesh& mesh = space_->mesh();
  const double eps = space_->tolerance();
  int count = 0;
  walk_segment(mesh, eps, start_tet, a, b, kMaxChordTets,
               [&](std::int32_t t, const Vec3& middle, bool) {
                 if (count < kMaxEdgeTets && mesh.outside_distance(t, middle) < -eps) {
                   out[count++] = t;
                 }
               });
  return count;
}

int CutState::cut_left_by_edge(const ProxyPlace& a0, const ProxyPlace& b0, const ProxyPlace& a1,
                               const ProxyPlace& b1) {
  if (a0.state == ProxyState::Outside || a0.tet == b0.tet) return 0;
  std::array<std::int32_t, kMaxEdgeTets> before{};
  std::array<std::int32_t, kMaxEdgeTets> now{};
  const int crossed = tets_crossed(a0.tet, a0.q, b0.q, before);
  const int still = a1.state == ProxyState::Outside ? 0 : tets_crossed(a1.tet, a1.q, b1.q, now);
  int newly_cut = 0;
  for (int k = 0; k < crossed; ++k) {
    const std::int32_t t = before[k];
    const MaterialModel model = space_->own_model(t);
    if (cut_[t] != 0 || t == a0.tet || t == b0.tet || t == a1.tet || t == b1.tet) continue;
    if (model != MaterialModel::Drag && model != MaterialModel::Viscous) continue;
    if (std::find(now.begin(), now.begin() + still, t) != now.begin() + still) continue;
    mark(t);
    ++newly_cut;
  }
  return newly_cut;
}

int CutState::cut_left_behind(const ProxyPlace& place, const Vec3& now) {
  if (place.state == ProxyState::Outside) return 0;
  const std::int32_t owner = place.tet;
  if (owner < 0 || owner >= static_cast<std::int32_t>(cut_.size())) return 0;
  const MaterialModel owner_model = space_->own_model(owner);
  if (!is_cuttable(owner_model)) return 0;
  const TetMesh& mesh = space_->mesh();
  const double eps = space_->tolerance();
  int newly_cut = 0;
  // A membrane only from inside: a point held on a face, edge or vertex of
  // its own tet went in (the walk enters a membrane only by breaking it);
  // a TET point on the membrane tet's face (a rigid blade's point seated on
  // the skin it rests on) has not broken it.
  const bool owner_cut = owner_model != MaterialModel::Membrane || place.state != ProxyState::Tet ||
                         mesh.outside_distance(owner, place.q) < -eps;
  if (cut_[owner] == 0 && owner_cut && mesh.outside_distance(owner, now) > eps) {
    mark(owner);
    ++newly_cut;
  }
  const auto touched = [&](std::int32_t t) {
    if (t == kNoTet || cut_[t] != 0) return;
    const MaterialModel model = space_->own_model(t);
    if ((model == MaterialModel::Drag || model == MaterialModel::Viscous) &&
        mesh.outside_distance(t, now) > eps) {
      mark(t);
      ++newly_cut;
    }
  };
  switch (place.state) {
    case ProxyState::Face:
      touched(mesh.neighbour(owner, place.local));
      break;
    case ProxyState::Edge:
      for (const EdgeFanEntry& entry : mesh.edge_fan_of(owner, place.local)) touched(entry.tet);
      break;
    case ProxyState::Vertex:
      for (const VertexFanEntry& entry : mesh.vertex_fan(mesh.tet(owner)[place.local])) {
        touched(entry.tet);
      }
      break;
    case ProxyState::Tet:
    case ProxyState::Outside:
      break;
  }
  return newly_cut;
}

void CutState::reset_cuts() {
  std::fill(cut_.begin(), cut_.end(), std::uint8_t{0});
  cut_count_ = 0;
  ++generation_;
}

void CutState::set_cuts(std::span<const std::int32_t> tets) {
  std::vector<std::uint8_t> given(cut_.size(), 0);
  for (std::size_t i = 0; i < tets.size(); ++i) {
    const std::int32_t t = tets[i];
    std::string problem;
    if (t < 0 || t >= static_cast<std::int32_t>(cut_.size())) {
      problem = "tet " + std::to_string(t) + " is not one of the scene's " +
                std::to_string(cut_.size()) + " tets";
    } else if (given[t] != 0) {
      problem = "tet " + std::to_string(t) + " is given twice";
    } else if (!is_cuttable(space_->own_model(t))) {
      problem = "tet " + std::to_string(t) + " is of a material that is never cut (" +
                std::string(material_model_name(space_->own_model(t))) + ")";
    }
    if (!problem.empty()) {
      throw std::invalid_argument("cut tets/" + std::to_string(i) + ": " + problem);
    }
    given[t] = 1;
  }
  reset_cuts();
  for (const std::int32_t t : tets) mark(t);
}

std::vector<std::int32_t> CutState::cut_tets() const {
  std::vector<std::int32_t> tets;
  tets.reserve(static_cast<std::size_t>(cut_count_));
  for (std::size_t t = 0; t < cut_.size(); ++t) {
    if (cut_[t] != 0) tets.push_back(static_cast<std::int32_t>(t));
  }
  return tets;
}

}  // namespace hapticut
