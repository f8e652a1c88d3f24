#include "hapticut/baselines/voxel_proxy.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace hapticut::baselines {

namespace {

double coordinate(const Vec3& v, int axis) { return axis == 0 ? v.x : (axis == 1 ? v.y : v.z); }

void set_coordinate(Vec3& v, int axis, double value) {
  (axis == 0 ? v.x : (axis == 1 ? v.y : v.z)) = value;
}

}  // namespace

VoxelGrid::VoxelGrid(const Vec3& origin_mm, double cell_mm, std::array<std::int32_t, 3> dims,
                     std::vector<std::uint8_t> solid)
    : origin_(origin_mm), cell_mm_(cell_mm), dims_(dims), solid_(std::move(solid)) {
  if (!(cell_mm > 0.0)) throw std::invalid_argument("voxel cell size must be positive");
  const std::int64_t count = static_cast<std::int64_t>(dims[0]) * dims[1] * dims[2];
  if (dims[0] < 1 || dims[1] < 1 || dims[2] < 1 ||
      static_cast<std::int64_t>(solid_.size()) != count) {
    throw std::invalid_argument("voxel grid: solid flags do not match the dimensions");
  }
}

bool VoxelGrid::is_solid(std::int32_t i, std::int32_t j, std::int32_t k) const {
  if (i < 0 || j < 0 || k < 0 || i >= dims_[0] || j >= dims_[1] || k >= dims_[2]) return false;
  return solid_[(static_cast<std::size_t>(k) * dims_[1] + j) * dims_[0] + i] != 0;
}

std::array<std::int32_t, 3> VoxelGrid::cell_of(const Vec3& x) const {
  std::array<std::int32_t, 3> c{};
  for (int a = 0; a < 3; ++a) {
    const double s = std::floor((coordinate(x, a) - coordinate(origin_, a)) / cell_mm_);
    c[a] = static_cast<std::int32_t>(std::clamp(s, -1e9, 1e9));
  }
  return c;
}

bool VoxelGrid::is_solid_at(const Vec3& x) const {
  const auto c = cell_of(x);
  return is_solid(c[0], c[1], c[2]);
}

std::int64_t VoxelGrid::solid_count() const {
  std::int64_t n = 0;
  for (std::uint8_t s : solid_) n += s != 0;
  return n;
}

VoxelProxy::VoxelProxy(const VoxelGrid& grid, double stiffness_N_per_mm)
    : grid_(&grid), stiffness_N_per_mm_(stiffness_N_per_mm) {}

void VoxelProxy::reset(const Vec3& p) {
  last_p_ = p;
  cell_ = grid_->cell_of(p);
  q_ = p;
  active_constraints_ = 0;
  while (grid_->is_solid(cell_[0], cell_[1], cell_[2])) {
    ++cell_[2];
    q_ = grid_->origin() +
         Vec3{(cell_[0] + 0.5), (cell_[1] + 0.5), (cell_[2] + 0.5)} * grid_->cell_mm();
  }
}

int VoxelProxy::step(const Vec3& p) {
  last_p_ = p;
  Vec3 target = p;
  // Each constraint fixes one axis at a cell-face coordinate; a second hit on
  // the same axis cannot happen (the target no longer moves along it).
  active_constraints_ = 0;
  int walked = 0;
  const double h = grid_->cell_mm();
  for (int pass = 0; pass <= kMaxConstraints; ++pass) {
    const Vec3 d = target - q_;
    if (d == Vec3{}) break;
    // DDA set-up from the current (free) cell.
    std::array<int, 3> step{};
    std::array<double, 3> t_max{};
    std::array<double, 3> t_delta{};
    for (int a = 0; a < 3; ++a) {
      const double da = coordinate(d, a);
      if (da > 0.0) {
        step[a] = 1;
        const double boundary = coordinate(grid_->origin(), a) + (cell_[a] + 1) * h;
        t_max[a] = (boundary - coordinate(q_, a)) / da;
        t_delta[a] = h / da;
      } else if (da < 0.0) {
        step[a] = -1;
        const double boundary = coordinate(grid_->origin(), a) + cell_[a] * h;
        t_max[a] = (boundary - coordinate(q_, a)) / da;
        t_delta[a] = -h / da;
      } else {
        step[a] = 0;
        t_max[a] = std::numeric_limits<double>::infinity();
        t_delta[a] = std::numeric_limits<double>::infinity();
      }
      if (t_max[a] < 0.0) t_max[a] = 0.0;
    }
    int blocked_axis = -1;
    double blocked_t = 1.0;
    for (;;) {
      int a = 0;
      if (t_max[1] < t_max[a]) a = 1;
      if (t_max[2] < t_max[a]) a = 2;
      if (t_max[a] > 1.0) break;  // The target lies in the current cell.
      std::array<std::int32_t, 3> next = cell_;
      next[a] += step[a];
      ++walked;
      if (grid_->is_solid(next[0], next[1], next[2])) {
        blocked_axis = a;
        blocked_t = t_max[a];
        break;
      }
      cell_ = next;
      t_max[a] += t_delta[a];
    }
    if (blocked_axis < 0) {
      q_ = target;
      break;
    }
    // Stop on the blocked face, exactly on its coordinate (no rounding into the solid cell).
    const double face =
        coordinate(grid_->origin(), blocked_axis) +
        (step[blocked_axis] > 0 ? cell_[blocked_axis] + 1 : cell_[blocked_axis]) * h;
    Vec3 hit = q_ + d * blocked_t;
    set_coordinate(hit, blocked_axis, face);
    // Keep the hit inside the current cell's closed box on the other axes.
    for (int a = 0; a < 3; ++a) {
      if (a == blocked_axis) continue;
      const double lo = coordinate(grid_->origin(), a) + cell_[a] * h;
      set_coordinate(hit, a, std::clamp(coordinate(hit, a), lo, lo + h));
    }
    q_ = hit;
    ++active_constraints_;
    // Eq. (6) for an axis-aligned plane: the target keeps its other coordinates.
    set_coordinate(target, blocked_axis, face);
    if (active_constraints_ == kMaxConstraints) break;
  }
  return walked;
}

}  // namespace hapticut::baselines
