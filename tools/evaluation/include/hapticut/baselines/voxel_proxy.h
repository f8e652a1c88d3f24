// Baseline: the voxel method the tetrahedral proxy replaces. Space is a
// regular grid of cells, each free or solid; the proxy is a god-object kept in
// free cells. Each tick it walks the segment q -> target cell by cell (3D
// DDA, Amanatides and Woo); where the walk would enter a solid cell the proxy
// stops on that cell's face, the face becomes a constraint plane (always
// axis-aligned) and the target is projected onto it; up to three constraints.
// Its staircase artefacts (force normals along the axes only) are the point.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "hapticut/vec3.h"

namespace hapticut::baselines {

class VoxelGrid {
 public:
  // solid: nx*ny*nz flags, x fastest. Cells outside the grid count as free.
  VoxelGrid(const Vec3& origin_mm, double cell_mm, std::array<std::int32_t, 3> dims,
            std::vector<std::uint8_t> solid);

  const Vec3& origin() const { return origin_; }
  double cell_mm() const { return cell_mm_; }
  const std::array<std::int32_t, 3>& dims() const { return dims_; }
  bool is_solid(std::int32_t i, std::int32_t j, std::int32_t k) const;
  bool is_solid_at(const Vec3& x) const;
  std::array<std::int32_t, 3> cell_of(const Vec3& x) const;
  std::int64_t solid_count() const;
  std::size_t memory_bytes() const { return solid_.capacity(); }

 private:
  Vec3 origin_;
  double cell_mm_;
  std::array<std::int32_t, 3> dims_;
  std::vector<std::uint8_t> solid_;
};

class VoxelProxy {
 public:
  static constexpr int kMaxConstraints = 3;

  VoxelProxy(const VoxelGrid& grid, double stiffness_N_per_mm);

  // Start at p when its cell is free; else at the centre of the nearest free
  // cell along +z (a start inside solid is pushed out upward).
  void reset(const Vec3& p);
  // One tick; returns the number of cells walked.
  int step(const Vec3& p);

  const Vec3& q() const { return q_; }
  const std::array<std::int32_t, 3>& cell() const { return cell_; }
  Vec3 force_N() const { return (q_ - last_p_) * stiffness_N_per_mm_; }
  int active_constraints() const { return active_constraints_; }

 private:
  const VoxelGrid* grid_;
  double stiffness_N_per_mm_;
  Vec3 q_;
  Vec3 last_p_;
  std::array<std::int32_t, 3> cell_{};
  int active_constraints_ = 0;
};

}  // namespace hapticut::baselines
