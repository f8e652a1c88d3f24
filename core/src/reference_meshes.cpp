#include "hapticut/reference_meshes.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>

namespace hapticut {

namespace {

double signed_volume6(const MeshData& mesh, const std::array<std::int32_t, 4>& t) {
  const Vec3& a = mesh.vertices_mm[t[0]];
  return dot(mesh.vertices_mm[t[1]] - a,
             cross(mesh.vertices_mm[t[2]] - a, mesh.vertices_mm[t[3]] - a));
}

void orient_positive(MeshData& mesh) {
  for (auto& t : mesh.tets) {
    if (signed_volume6(mesh, t) < 0.0) std::swap(t[2], t[3]);
  }
}

}  // namespace

MeshData two_tets_mesh(double size_mm) {
  MeshData mesh;
  const double s = size_mm;
  mesh.vertices_mm = {{0, 0, 0}, {s, 0, 0}, {0, s, 0}, {s / 4, s / 4, -s}, {s / 4, s / 4, s}};
  mesh.tets = {{0, 1, 2, 3}, {0, 1, 2, 4}};
  orient_positive(mesh);
  return mesh;
}

MeshData edge_fan_mesh(int fan_size, double radius_mm, double half_height_mm) {
  MeshData mesh;
  mesh.vertices_mm = {{0, 0, -half_height_mm}, {0, 0, half_height_mm}};
  for (int i = 0; i < fan_size; ++i) {
    const double angle = 2.0 * std::numbers::pi * i / fan_size;
    mesh.vertices_mm.push_back({radius_mm * std::cos(angle), radius_mm * std::sin(angle), 0.0});
  }
  for (int i = 0; i < fan_size; ++i) {
    mesh.tets.push_back({0, 1, 2 + i, 2 + (i + 1) % fan_size});
  }
  orient_positive(mesh);
  return mesh;
}

MeshData icosahedron_mesh(double radius_mm) {
  const double g = (1.0 + std::sqrt(5.0)) / 2.0;
  const double scale = radius_mm / std::sqrt(1.0 + g * g);
  MeshData mesh;
  mesh.vertices_mm = {{0, 0, 0}};
  const std::array<Vec3, 12> corners{{{-1, g, 0},
                                      {1, g, 0},
                                      {-1, -g, 0},
                                      {1, -g, 0},
                                      {0, -1, g},
                                      {0, 1, g},
                                      {0, -1, -g},
                                      {0, 1, -g},
                                      {g, 0, -1},
                                      {g, 0, 1},
                                      {-g, 0, -1},
                                      {-g, 0, 1}}};
  for (const Vec3& c : corners) mesh.vertices_mm.push_back(c * scale);
  const std::array<std::array<int, 3>, 20> faces{
      {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
       {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
       {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}}};
  for (const auto& f : faces) mesh.tets.push_back({0, f[0] + 1, f[1] + 1, f[2] + 1});
  orient_positive(mesh);
  return mesh;
}

MeshData vertex_fan_mesh(int subdivisions, double radius_mm) {
  if (subdivisions < 0 || subdivisions > 5) {
    throw std::invalid_argument("vertex_fan_mesh: subdivisions must be 0 to 5, got " +
                                std::to_string(subdivisions));
  }
  MeshData mesh = icosahedron_mesh(radius_mm);
  // The shell's triangles: each tet is (centre, a, b, c) after orientation.
  std::vector<std::array<std::int32_t, 3>> shell;
  for (const auto& t : mesh.tets) shell.push_back({t[1], t[2], t[3]});
  for (int level = 0; level < subdivisions; ++level) {
    std::map<std::pair<std::int32_t, std::int32_t>, std::int32_t> midpoints;
    auto middle = [&](std::int32_t a, std::int32_t b) {
      const std::pair<std::int32_t, std::int32_t> key{std::min(a, b), std::max(a, b)};
      const auto [it, added] =
          midpoints.try_emplace(key, static_cast<std::int32_t>(mesh.vertices_mm.size()));
      if (added) {
        const Vec3 m = mesh.vertices_mm[a] + mesh.vertices_mm[b];
        mesh.vertices_mm.push_back(m * (radius_mm / norm(m)));
      }
      return it->second;
    };
    std::vector<std::array<std::int32_t, 3>> finer;
    for (const auto& [a, b, c] : shell) {
      const std::int32_t ab = middle(a, b);
      const std::int32_t bc = middle(b, c);
      const std::int32_t ca = middle(c, a);
      finer.insert(finer.end(), {{a, ab, ca}, {b, bc, ab}, {c, ca, bc}, {ab, bc, ca}});
    }
    shell = std::move(finer);
  }
  mesh.tets.clear();
  for (const auto& [a, b, c] : shell) mesh.tets.push_back({0, a, b, c});
  orient_positive(mesh);
  return mesh;
}

MeshData double_cone_mesh(int ring_size, double radius_mm, double half_height_mm) {
  if (ring_size < 3) {
    throw std::invalid_argument("double_cone_mesh: ring_size must be at least 3, got " +
                                std::to_string(ring_size));
  }
  MeshData mesh;
  mesh.vertices_mm = {{0, 0, 0}, {0, 0, -half_height_mm}, {0, 0, half_height_mm}};
  for (int i = 0; i < ring_size; ++i) {
    const double angle = 2.0 * std::numbers::pi * i / ring_size;
    mesh.vertices_mm.push_back({radius_mm * std::cos(angle), radius_mm * std::sin(angle), 0.0});
  }
  for (int apex = 1; apex <= 2; ++apex) {
    for (int i = 0; i < ring_size; ++i) {
      mesh.tets.push_back({0, apex, 3 + i, 3 + (i + 1) % ring_size});
    }
  }
  orient_positive(mesh);
  return mesh;
}

MeshData cube_mesh(double size_mm) { return grid_mesh({0, size_mm}, {0, size_mm}, {0, size_mm}); }

MeshData grid_mesh(const std::vector<double>& xs, const std::vector<double>& ys,
                   const std::vector<double>& zs, double jitter, std::uint64_t seed) {
  MeshData mesh;
  const int nx = static_cast<int>(xs.size());
  const int ny = static_cast<int>(ys.size());
  const int nz = static_cast<int>(zs.size());
  auto id = [&](int i, int j, int k) { return static_cast<std::int32_t>((k * ny + j) * nx + i); };
  for (int k = 0; k < nz; ++k) {
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) mesh.vertices_mm.push_back({xs[i], ys[j], zs[k]});
    }
  }
  // Kuhn split: the 6 paths from corner 0 to corner 7 of each cell.
  static constexpr std::array<std::array<int, 3>, 6> kPaths{
      {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}}};
  for (int k = 0; k + 1 < nz; ++k) {
    for (int j = 0; j + 1 < ny; ++j) {
      for (int i = 0; i + 1 < nx; ++i) {
        for (const auto& path : kPaths) {
          std::array<int, 3> c{i, j, k};
          std::array<std::int32_t, 4> tet{};
          tet[0] = id(c[0], c[1], c[2]);
          for (int step = 0; step < 3; ++step) {
            ++c[path[step]];
            tet[step + 1] = id(c[0], c[1], c[2]);
          }
          mesh.tets.push_back(tet);
        }
      }
    }
  }
  orient_positive(mesh);
  if (jitter > 0.0) {
    // Move interior vertices one at a time; halve a move until every tet
    // around it keeps at least 0.1% of its volume: slivers wanted, inversions not.
    std::vector<std::vector<std::int32_t>> around(mesh.vertices_mm.size());
    for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
      for (std::int32_t v : mesh.tets[t]) around[v].push_back(static_cast<std::int32_t>(t));
    }
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    for (int k = 1; k + 1 < nz; ++k) {
      for (int j = 1; j + 1 < ny; ++j) {
        for (int i = 1; i + 1 < nx; ++i) {
          const std::int32_t v = id(i, j, k);
          const Vec3 spacing{std::min(xs[i] - xs[i - 1], xs[i + 1] - xs[i]),
                             std::min(ys[j] - ys[j - 1], ys[j + 1] - ys[j]),
                             std::min(zs[k] - zs[k - 1], zs[k + 1] - zs[k])};
          Vec3 shift{unit(rng) * spacing.x * jitter, unit(rng) * spacing.y * jitter,
                     unit(rng) * spacing.z * jitter};
          const Vec3 home = mesh.vertices_mm[v];
          std::vector<double> before;
          for (std::int32_t t : around[v]) before.push_back(signed_volume6(mesh, mesh.tets[t]));
          for (int attempt = 0; attempt < 20; ++attempt, shift = shift * 0.5) {
            mesh.vertices_mm[v] = home + shift;
            bool ok = true;
            for (std::size_t n = 0; n < around[v].size() && ok; ++n) {
              ok = signed_volume6(mesh, mesh.tets[around[v][n]]) > 1e-3 * before[n];
            }
            if (ok) break;
            mesh.vertices_mm[v] = home;
          }
        }
      }
    }
  }
  return mesh;
}

}  // namespace hapticut
