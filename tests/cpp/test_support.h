// Shared helpers of the C++ tests: a Space from reference geometry.
#pragma once

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "hapticut/reference_meshes.h"
#include "hapticut/space.h"

namespace hapticut::testing {

inline Material free_material() { return {"air", MaterialModel::Free}; }
inline Material drag_material(double d_mm) {
  Material m{"flesh", MaterialModel::Drag};
  m.drag_distance_mm = d_mm;
  return m;
}
inline Material rigid_material() { return {"bone", MaterialModel::Rigid}; }
// Bone with friction at rigid contacts (static, dynamic).
inline Material rigid_material(double static_friction, double dynamic_friction) {
  Material m = rigid_material();
  m.static_friction = static_friction;
  m.dynamic_friction = dynamic_friction;
  return m;
}

// Materials: 0 air (free), 1 flesh (drag 1 mm), 2 bone (rigid).
inline std::vector<Material> paper_materials() {
  return {free_material(), drag_material(1.0), rigid_material()};
}

inline std::shared_ptr<const Space> make_space(const MeshData& data,
                                               std::vector<std::int32_t> tet_materials,
                                               std::vector<Material> materials = paper_materials(),
                                               EngineSettings settings = {}) {
  return Space::create(TetMesh(data.vertices_mm, data.tets, std::move(tet_materials)),
                       std::move(materials), settings);
}

inline std::shared_ptr<const Space> make_space(const MeshData& data, std::int32_t material) {
  return make_space(data, std::vector<std::int32_t>(data.tets.size(), material));
}

// Grid lines from..to at step, with `extra` lines added (lines within 0.05 mm
// of one of them dropped): a grid with planes where a thin feature's faces lie.
inline std::vector<double> axis(double from, double to, double step,
                                const std::vector<double>& extra = {}) {
  std::vector<double> v;
  for (double x = from; x <= to + 1e-9; x += step) v.push_back(x);
  for (double e : extra) {
    v.erase(std::remove_if(v.begin(), v.end(), [e](double x) { return std::abs(x - e) < 0.05; }),
            v.end());
    v.push_back(e);
  }
  std::sort(v.begin(), v.end());
  return v;
}

// Each tet bone (material 2) where in_bone(its centroid), air (0) elsewhere.
template <class InBone>
std::shared_ptr<const Space> labelled_space(const MeshData& mesh, InBone in_bone,
                                            std::vector<Material> materials = paper_materials()) {
  std::vector<std::int32_t> labels(mesh.tets.size());
  for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
    Vec3 c;
    for (std::int32_t v : mesh.tets[t]) c += mesh.vertices_mm[v] * 0.25;
    labels[t] = in_bone(c) ? 2 : 0;
  }
  return make_space(mesh, labels, std::move(materials));
}

// Whether x lies inside rigid material by more than depth_mm.
inline bool inside_rigid(const Space& space, const Vec3& x, double depth_mm = 1e-6) {
  bool inside = false;
  space.mesh().tet_tree().for_each_containing(x, 0.0, [&](std::int32_t t) {
    inside = inside || (space.tet_is_rigid(t) && space.mesh().outside_distance(t, x) < -depth_mm);
  });
  return inside;
}

// A V-groove of bone running along x: a grid of the given lines with every
// vertex lifted by slope |y|, bone (material 2 of paper_materials) below the
// lifted z = 0, the groove's bottom line the x axis. Its angle is
// 2 atan(1 / slope).
inline std::shared_ptr<const Space> v_groove(const std::vector<double>& xs,
                                             const std::vector<double>& ys,
                                             const std::vector<double>& zs, double slope) {
  MeshData mesh = grid_mesh(xs, ys, zs);
  std::vector<std::int32_t> labels(mesh.tets.size());
  for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
    double z = 0.0;
    for (std::int32_t v : mesh.tets[t]) z += mesh.vertices_mm[v].z * 0.25;
    labels[t] = z < 0.0 ? 2 : 0;
  }
  for (Vec3& v : mesh.vertices_mm) v.z += slope * std::abs(v.y);
  return make_space(mesh, labels);
}

// n fractions evenly spaced over [0, 1], both ends included (n >= 2).
inline std::vector<double> evenly_spaced(int n) {
  std::vector<double> f(n);
  for (int i = 0; i < n; ++i) f[i] = double(i) / (n - 1);
  return f;
}

// Bone below z = 0 inside a free 40 mm box (material 2 of paper_materials).
inline std::shared_ptr<const Space> bone_floor(EngineSettings settings = {}) {
  const MeshData mesh = grid_mesh({-20, 0, 20}, {-20, 0, 20}, {-20, 0, 20});
  std::vector<std::int32_t> m(mesh.tets.size(), 0);
  for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
    double z = 0;
    for (std::int32_t v : mesh.tets[t]) z += mesh.vertices_mm[v].z * 0.25;
    if (z < 0) m[t] = 2;
  }
  return make_space(mesh, m, paper_materials(), settings);
}

}  // namespace hapticut::testing
