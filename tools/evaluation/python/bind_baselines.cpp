// hapticut_evaluation._baselines: the baseline methods (voxel proxy, surface
// god-object), the tet proxy with and without force shading, and one interface
// for all methods so
// the same paths run through each of them in C++ (no Python loop per tick):
// reset(P), step(P, dt_s), run(path, dt_s) -> q, force_N and ns per point update.
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include <chrono>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "arrays.h"
#include "hapticut/baselines/god_object.h"
#include "hapticut/baselines/voxel_proxy.h"
#include "hapticut/force_shading.h"
#include "hapticut/proxy.h"

namespace nb = nanobind;

namespace hapticut::python {

namespace {

using Clock = std::chrono::steady_clock;
using PathIn = nb::ndarray<const double, nb::shape<-1, -1, 3>, nb::c_contig, nb::device::cpu>;
using Vec3In = nb::ndarray<const double, nb::shape<3>, nb::device::cpu>;

// The tetrahedral proxy, with force shading when `shading` is set.
struct TetMethod {
  TetMethod(const Space& space, const ForceShading* shading_) : proxy(space), shading(shading_) {}
  void reset(const Vec3& p) { proxy.reset(p); }
  void step(const Vec3& p, double dt_s) {
    const TickResult r = proxy.step(p, dt_s);
    capped += r.capped ? 1 : 0;
  }
  const Vec3& q() const { return proxy.q(); }
  Vec3 force_N() const {
    return shading != nullptr ? shading->shade(proxy.place(), proxy.force_N()) : proxy.force_N();
  }
  std::string problem() const { return proxy.check_invariants(); }

  Proxy proxy;
  const ForceShading* shading;
  std::uint64_t capped = 0;
};

struct VoxelMethod {
  VoxelMethod(const baselines::VoxelGrid& grid, double k) : proxy(grid, k), grid_(&grid) {}
  void reset(const Vec3& p) { proxy.reset(p); }
  void step(const Vec3& p, double /*dt_s*/) { proxy.step(p); }
  const Vec3& q() const { return proxy.q(); }
  Vec3 force_N() const { return proxy.force_N(); }
  std::string problem() const {
    const auto& c = proxy.cell();
    return grid_->is_solid(c[0], c[1], c[2]) ? "proxy cell is solid" : "";
  }
  baselines::VoxelProxy proxy;
  const baselines::VoxelGrid* grid_;
  std::uint64_t capped = 0;
};

struct GodObjectMethod {
  GodObjectMethod(const baselines::TriangleSurface& surface, double k) : proxy(surface, k) {}
  void reset(const Vec3& p) { proxy.reset(p); }
  void step(const Vec3& p, double /*dt_s*/) { proxy.step(p); }
  const Vec3& q() const { return proxy.q(); }
  Vec3 force_N() const { return proxy.force_N(); }
  std::string problem() const { return ""; }
  baselines::SurfaceGodObject proxy;
  std::uint64_t capped = 0;
};

template <class Method>
struct MethodSet {
  std::vector<Method> items;
  std::size_t memory_bytes = 0;
  std::shared_ptr<const baselines::TriangleSurface> surface;  // Owned here for GodObjectSet.
  // Timed passes whose force sum was not finite: read back, so the timed
  // passes must compute every force (see best_timed_pass).
  mutable std::uint64_t nonfinite_forces = 0;

  void check_count(std::size_t n) const {
    if (n != items.size()) {
      throw std::invalid_argument("expected " + std::to_string(items.size()) + " points, got " +
                                  std::to_string(n));
    }
  }
};

// ns per point update of the best of `repeats` passes along the path, each
// on copies of the methods (which keep their state): the update (step and
// force) alone, without writing outputs. 0 when there is nothing to time.
template <class Method>
double best_timed_pass(const MethodSet<Method>& s, const PathIn& path, double dt_s, int repeats) {
  const std::size_t ticks = path.shape(0);
  const std::size_t n = s.items.size();
  if (ticks * n == 0 || repeats <= 0) return 0.0;
  double best = 0.0;
  Vec3 sink;
  for (int r = 0; r < repeats; ++r) {
    std::vector<Method> copies = s.items;
    const double* point = path.data();  // C-contiguous (ticks, n, 3).
    const auto t0 = Clock::now();
    for (std::size_t k = 0; k < ticks; ++k) {
      for (Method& m : copies) {
        m.step({point[0], point[1], point[2]}, dt_s);
        sink += m.force_N();
        point += 3;
      }
    }
    const double pass = std::chrono::duration<double, std::nano>(Clock::now() - t0).count();
    if (r == 0 || pass < best) best = pass;
  }
  // Uses the forces, so the compiler cannot drop their computation.
  if (!is_finite(sink)) ++s.nonfinite_forces;
  return best / static_cast<double>(ticks * n);
}

template <class Method>
void bind_method_set(nb::class_<MethodSet<Method>>& cls) {
  using Set = MethodSet<Method>;
  cls.def("__len__", [](const Set& s) { return s.items.size(); })
      .def(
          "reset",
          [](Set& s, const PointsIn& points) {
            s.check_count(points.shape(0));
            for (std::size_t i = 0; i < s.items.size(); ++i) {
              s.items[i].reset({points(i, 0), points(i, 1), points(i, 2)});
            }
          },
          nb::arg("points"), "Place each proxy for its device point (N, 3).")
      .def(
          "step",
          [](Set& s, const PointsIn& points, double dt_s) {
            s.check_count(points.shape(0));
            for (std::size_t i = 0; i < s.items.size(); ++i) {
              s.items[i].step({points(i, 0), points(i, 1), points(i, 2)}, dt_s);
            }
          },
          nb::arg("points"), nb::arg("dt_s") = 0.001, "One servo tick for every proxy.")
      .def(
          "time",
          [](Set& s, const PathIn& path, double dt_s, int repeats) {
            s.check_count(path.shape(1));
            return best_timed_pass(s, path, dt_s, repeats);
          },
          nb::arg("path"), nb::arg("dt_s") = 0.001, nb::arg("repeats") = 1,
          "ns per point update along a (ticks, N, 3) path: the best of `repeats` passes "
          "over copies of the methods (their state is left as it was).")
      .def(
          "run",
          [](Set& s, const PathIn& path, double dt_s, bool check, int timing_repeats) {
            s.check_count(path.shape(1));
            const std::size_t ticks = path.shape(0);
            const std::size_t n = s.items.size();
            const double ns = best_timed_pass(s, path, dt_s, timing_repeats);
            // The recorded pass, on the methods themselves.
            auto q = new_array<double>({ticks, n, 3});
            auto force = new_array<double>({ticks, n, 3});
            std::uint64_t problems = 0;
            std::string first_problem;
            std::uint64_t capped_before = 0;
            for (const Method& m : s.items) capped_before += m.capped;
            for (std::size_t k = 0; k < ticks; ++k) {
              for (std::size_t i = 0; i < n; ++i) {
                Method& m = s.items[i];
                m.step({path(k, i, 0), path(k, i, 1), path(k, i, 2)}, dt_s);
                const Vec3& qi = m.q();
                const Vec3 fi = m.force_N();
                double* out_q = q.data() + (k * n + i) * 3;
                double* out_f = force.data() + (k * n + i) * 3;
                out_q[0] = qi.x;
                out_q[1] = qi.y;
                out_q[2] = qi.z;
                out_f[0] = fi.x;
                out_f[1] = fi.y;
                out_f[2] = fi.z;
                if (check) {
                  const std::string why = m.problem();
                  if (!why.empty()) {
                    if (problems == 0) first_problem = why;
                    ++problems;
                  }
                }
              }
            }
            std::uint64_t capped_after = 0;
            for (const Method& m : s.items) capped_after += m.capped;
            nb::dict d;
            d["q"] = q;
            d["force_N"] = force;
            d["ns_per_update"] = ns;
            d["invariant_failures"] = problems;
            d["first_failure"] = first_problem;
            d["capped_ticks"] = capped_after - capped_before;
            return d;
          },
          nb::arg("path"), nb::arg("dt_s") = 0.001, nb::arg("check") = false,
          nb::arg("timing_repeats") = 3,
          "Step through a (ticks, N, 3) path in C++. Returns q and force_N (ticks, N, 3), "
          "ns_per_update (the best of timing_repeats passes over copies of the methods, "
          "steps and forces only, wall clock / (ticks x N); 0 when timing_repeats is 0), "
          "invariant_failures (with check=True, per tick), first_failure and capped_ticks.")
      .def_prop_ro(
          "q",
          [](const Set& s) {
            std::vector<Vec3> points(s.items.size());
            for (std::size_t i = 0; i < points.size(); ++i) points[i] = s.items[i].q();
            return from_points(points);
          },
          nb::rv_policy::move)
      .def_prop_ro(
          "force_N",
          [](const Set& s) {
            std::vector<Vec3> points(s.items.size());
            for (std::size_t i = 0; i < points.size(); ++i) points[i] = s.items[i].force_N();
            return from_points(points);
          },
          nb::rv_policy::move)
      .def_prop_ro(
          "timed_nonfinite_passes", [](const Set& s) { return s.nonfinite_forces; },
          "Timed passes whose summed force was not finite (0 unless a method broke).",
          nb::rv_policy::move)
      .def_prop_ro(
          "memory_bytes", [](const Set& s) { return s.memory_bytes; },
          "Bytes of the method's shared model (mesh, grid or surface with its tree).",
          nb::rv_policy::move)
      .def(
          "problems",
          [](const Set& s) {
            std::vector<std::string> out;
            for (const Method& m : s.items) out.push_back(m.problem());
            return out;
          },
          "Per proxy: '' when its invariants hold, else why.");
}

// Solid flags of a grid from the rigid tets of a Space: a cell is solid when
// its centre lies in a rigid tet (each rigid tet rasterised over its box).
baselines::VoxelGrid voxelize_space(const Space& space, const Vec3& origin, double cell_mm,
                                    std::array<std::int32_t, 3> dims) {
  const TetMesh& mesh = space.mesh();
  std::vector<std::uint8_t> solid(static_cast<std::size_t>(dims[0]) * dims[1] * dims[2], 0);
  for (std::int32_t t = 0; t < mesh.tet_count(); ++t) {
    if (!space.tet_is_rigid(t)) continue;
    Aabb box;
    for (std::int32_t v : mesh.tet(t)) box.grow(mesh.vertex(v));
    std::array<std::int32_t, 3> lo{};
    std::array<std::int32_t, 3> hi{};
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::max(
          0, static_cast<std::int32_t>(std::floor((box.lo[a] - origin[a]) / cell_mm - 0.5)));
      hi[a] =
          std::min(dims[a] - 1,
                   static_cast<std::int32_t>(std::ceil((box.hi[a] - origin[a]) / cell_mm - 0.5)));
    }
    for (std::int32_t k = lo[2]; k <= hi[2]; ++k) {
      for (std::int32_t j = lo[1]; j <= hi[1]; ++j) {
        for (std::int32_t i = lo[0]; i <= hi[0]; ++i) {
          const Vec3 centre = origin + Vec3{i + 0.5, j + 0.5, k + 0.5} * cell_mm;
          if (mesh.outside_distance(t, centre) <= 0.0) {
            solid[(static_cast<std::size_t>(k) * dims[1] + j) * dims[0] + i] = 1;
          }
        }
      }
    }
  }
  return {origin, cell_mm, dims, std::move(solid)};
}

}  // namespace

void bind_baselines(nb::module_& m) {
  using Solid =
      nb::ndarray<const std::uint8_t, nb::shape<-1, -1, -1>, nb::c_contig, nb::device::cpu>;

  m.def(
      "rigid_surface",
      [](const Space& space) {
        const RigidSurface s = extract_rigid_surface(space);
        auto triangles = new_array<std::int32_t>({s.triangles.size(), 3});
        for (std::size_t t = 0; t < s.triangles.size(); ++t) {
          for (int k = 0; k < 3; ++k) triangles.data()[3 * t + k] = s.triangles[t][k];
        }
        return nb::make_tuple(from_points(s.vertices_mm), triangles);
      },
      nb::arg("space"),
      "The surface of the rigid region (faces between rigid and non-rigid tets or the outside): "
      "(vertices (V, 3), triangles (T, 3)) wound counter-clockwise seen from outside.");

  m.def(
      "rigid_depth",
      [](const Space& space, const PointsIn& points) {
        auto out = new_array<double>({points.shape(0)});
        for (std::size_t i = 0; i < points.shape(0); ++i) {
          const Vec3 x{points(i, 0), points(i, 1), points(i, 2)};
          const std::int32_t t = space.mesh().locate(x);
          out.data()[i] = t != kNoTet && space.tet_is_rigid(t)
                              ? std::max(0.0, -space.mesh().outside_distance(t, x))
                              : 0.0;
        }
        return out;
      },
      nb::arg("space"), nb::arg("points"),
      "How deep each point lies inside rigid material: the distance to the nearest face of "
      "the rigid tet holding it (a lower bound of the depth in the rigid region), 0 elsewhere.");

  nb::class_<baselines::VoxelGrid>(m, "VoxelGrid", "A regular grid of free and solid cells.")
      .def(
          "__init__",
          [](baselines::VoxelGrid* self, const Vec3In& origin, double cell_mm, const Solid& solid) {
            const std::array<std::int32_t, 3> dims{static_cast<std::int32_t>(solid.shape(2)),
                                                   static_cast<std::int32_t>(solid.shape(1)),
                                                   static_cast<std::int32_t>(solid.shape(0))};
            std::vector<std::uint8_t> flags(solid.data(), solid.data() + solid.size());
            new (self) baselines::VoxelGrid({origin(0), origin(1), origin(2)}, cell_mm, dims,
                                            std::move(flags));
          },
          nb::arg("origin_mm"), nb::arg("cell_mm"), nb::arg("solid"),
          "solid: uint8 array of shape (nz, ny, nx); cell (i, j, k) spans origin + [i, i+1] x "
          "cell_mm along x, and so on.")
      .def_static(
          "from_space",
          [](const Space& space, const Vec3In& origin, double cell_mm,
             const std::vector<std::int32_t>& dims) {
            if (dims.size() != 3) throw std::invalid_argument("dims needs 3 numbers (nx, ny, nz)");
            return voxelize_space(space, {origin(0), origin(1), origin(2)}, cell_mm,
                                  {dims[0], dims[1], dims[2]});
          },
          nb::arg("space"), nb::arg("origin_mm"), nb::arg("cell_mm"), nb::arg("dims"),
          "Voxelise a Space: a cell is solid when its centre lies in a rigid tet.")
      .def_prop_ro("cell_mm", &baselines::VoxelGrid::cell_mm, nb::rv_policy::move)
      .def_prop_ro(
          "dims",
          [](const baselines::VoxelGrid& g) {
            return std::vector<std::int32_t>(g.dims().begin(), g.dims().end());
          },
          nb::rv_policy::move)
      .def_prop_ro("solid_count", &baselines::VoxelGrid::solid_count, nb::rv_policy::move)
      .def_prop_ro("memory_bytes", &baselines::VoxelGrid::memory_bytes, nb::rv_policy::move)
      .def(
          "is_solid_at",
          [](const baselines::VoxelGrid& g, const PointsIn& points) {
            auto out = new_array<bool>({points.shape(0)});
            for (std::size_t i = 0; i < points.shape(0); ++i) {
              out.data()[i] = g.is_solid_at({points(i, 0), points(i, 1), points(i, 2)});
            }
            return out;
          },
          nb::arg("points"));

  using TetSet = MethodSet<TetMethod>;
  nb::class_<TetSet> tet_set(m, "TetMethodSet",
                             "N tetrahedral proxies, optionally with force shading on the rigid "
                             "surface; the evaluation's common method interface.");
  tet_set.def(
      "__init__",
      [](TetSet* self, const Space& space, std::size_t count, const ForceShading* shading) {
        new (self) TetSet();
        for (std::size_t i = 0; i < count; ++i) self->items.emplace_back(space, shading);
        self->memory_bytes =
            space.mesh().memory_bytes() + (shading != nullptr ? shading->memory_bytes() : 0);
      },
      nb::arg("space"), nb::arg("count"), nb::arg("shading").none() = nb::none(),
      nb::keep_alive<1, 2>(), nb::keep_alive<1, 4>());
  bind_method_set(tet_set);

  using VoxelSet = MethodSet<VoxelMethod>;
  nb::class_<VoxelSet> voxel_set(m, "VoxelProxySet", "N voxel god-objects on one VoxelGrid.");
  voxel_set.def(
      "__init__",
      [](VoxelSet* self, const baselines::VoxelGrid& grid, std::size_t count, double k) {
        new (self) VoxelSet();
        for (std::size_t i = 0; i < count; ++i) self->items.emplace_back(grid, k);
        self->memory_bytes = grid.memory_bytes();
      },
      nb::arg("grid"), nb::arg("count"), nb::arg("stiffness_N_per_mm") = 0.1,
      nb::keep_alive<1, 2>());
  bind_method_set(voxel_set);

  using GodSet = MethodSet<GodObjectMethod>;
  nb::class_<GodSet> god_set(m, "GodObjectSet",
                             "N surface god-objects (Zilles and Salisbury) on one closed "
                             "triangle surface.");
  god_set.def(
      "__init__",
      [](GodSet* self, const PointsIn& vertices, const TrianglesIn& triangles, std::size_t count,
         double k, bool use_tree, double tolerance_mm) {
        new (self) GodSet();
        self->surface = std::make_shared<const baselines::TriangleSurface>(
            to_points(vertices), to_triangles(triangles), use_tree, tolerance_mm);
        for (std::size_t i = 0; i < count; ++i) self->items.emplace_back(*self->surface, k);
        self->memory_bytes = self->surface->memory_bytes();
      },
      nb::arg("vertices"), nb::arg("triangles"), nb::arg("count"),
      nb::arg("stiffness_N_per_mm") = 0.1, nb::arg("use_tree") = true,
      nb::arg("tolerance_mm") = 0.0);
  bind_method_set(god_set);
}

}  // namespace hapticut::python

NB_MODULE(_baselines, m) {
  m.doc() = "Hapticut's evaluation: baseline methods and the timing harness (C++).";
  // Space and ForceShading come from hapticut._core (nanobind shares its types across modules).
  nb::module_::import_("hapticut._core");
  hapticut::python::bind_baselines(m);
}
