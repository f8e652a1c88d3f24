// Bindings: many proxies stepped at once from an (N, 3) array (one call per
// tick, no Python loop per point), and the blade.
#include <nanobind/stl/shared_ptr.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include "arrays.h"
#include "hapticut/blade.h"
#include "hapticut/force_shading.h"
#include "hapticut/parameter_range.h"
#include "hapticut/proxy.h"

namespace hapticut::python {

namespace {

// The force shading of a Space, built when first asked for (it allocates;
// Python is never on the servo's real-time path).
std::shared_ptr<const ForceShading> shading_for(const std::shared_ptr<const Space>& space,
                                                const RuntimeSettings& settings) {
  return settings.force_shading ? std::make_shared<const ForceShading>(*space) : nullptr;
}

// The bindings release the GIL while they step, so two Python threads could
// reach one ProxySet or Blade at once: each call claims the object first and
// raises RuntimeError if another thread is using it, never racing.
template <class Owner>
std::unique_lock<std::mutex> claim(const Owner& owner) {
  std::unique_lock<std::mutex> lock(owner.busy, std::try_to_lock);
  if (!lock.owns_lock()) throw std::runtime_error("in use by another thread");
  return lock;
}

// N proxies in one Space, which they keep alive (shared ownership), with the
// settings every step uses and, when those ask for it, a force shading.
struct ProxySet {
  ProxySet(std::shared_ptr<const Space> space_, std::size_t count)
      : space(std::move(space_)),
        proxies(count, Proxy(space)),
        last(count),
        settings(space->runtime_settings()),
        shading(shading_for(space, settings)) {}

  void check_count(std::size_t n) const {
    if (n != proxies.size()) {
      throw std::invalid_argument("expected " + std::to_string(proxies.size()) + " points, got " +
                                  std::to_string(n));
    }
  }
  void set_settings(const RuntimeSettings& s) {
    s.validate();
    if (s.force_shading && !shading) shading = shading_for(space, s);
    settings = s;
  }
  TickResult step_one(std::size_t i, const Vec3& p, double dt_s) {
    return proxies[i].step(p, dt_s, settings, shading.get());
  }

  std::shared_ptr<const Space> space;
  std::vector<Proxy> proxies;
  std::vector<TickResult> last;
  RuntimeSettings settings;
  std::shared_ptr<const ForceShading> shading;
  mutable std::mutex busy;
};

// A Blade with the settings its steps use (the C++ Blade takes them per tick).
struct PyBlade {
  PyBlade(std::shared_ptr<const Space> space, const BladeSpec& spec)
      : settings(space->runtime_settings()), blade(std::move(space), spec) {}
  RuntimeSettings settings;
  Blade blade;
  mutable std::mutex busy;
};

nb::dict counters_dict(const std::vector<Proxy>& proxies) {
  const std::size_t n = proxies.size();
  auto transitions = new_array<std::uint64_t>({n, kProxyStateCount, kProxyStateCount, 2});
  auto ticks = new_array<std::uint64_t>({n});
  auto capped = new_array<std::uint64_t>({n});
  auto rejected = new_array<std::uint64_t>({n});
  auto far = new_array<std::uint64_t>({n});
  auto deferred = new_array<std::uint64_t>({n});
  auto max_in_tick = new_array<std::uint32_t>({n});
  auto total = new_array<std::uint64_t>({n});
  for (std::size_t i = 0; i < n; ++i) {
    const ProxyCounters& c = proxies[i].counters();
    std::uint64_t* out = transitions.data() + i * kProxyStateCount * kProxyStateCount * 2;
    for (int a = 0; a < kProxyStateCount; ++a) {
      for (int b = 0; b < kProxyStateCount; ++b) {
        out[(a * kProxyStateCount + b) * 2] = c.transitions[a][b][0];
        out[(a * kProxyStateCount + b) * 2 + 1] = c.transitions[a][b][1];
      }
    }
    ticks.data()[i] = c.ticks;
    capped.data()[i] = c.capped_ticks;
    rejected.data()[i] = c.rejected_inputs;
    far.data()[i] = c.out_of_workspace_inputs;
    deferred.data()[i] = c.deferred_ticks;
    max_in_tick.data()[i] = c.max_transitions_in_tick;
    total.data()[i] = c.total_transitions;
  }
  nb::dict d;
  d["transitions"] = transitions;  // [proxy, from, to, to_neighbour]
  d["ticks"] = ticks;
  d["capped_ticks"] = capped;
  d["rejected_inputs"] = rejected;
  d["out_of_workspace_inputs"] = far;
  d["deferred_ticks"] = deferred;
  d["max_transitions_in_tick"] = max_in_tick;
  d["total_transitions"] = total;
  return d;
}

template <class Get>
nb::ndarray<nb::numpy, double> gather_points(const std::vector<Proxy>& proxies, Get get) {
  std::vector<Vec3> points(proxies.size());
  for (std::size_t i = 0; i < proxies.size(); ++i) points[i] = get(proxies[i]);
  return from_points(points);
}

Pose pose_from(const nb::ndarray<const double, nb::shape<7>, nb::device::cpu>& a) {
  return {{a(0), a(1), a(2)}, {a(3), a(4), a(5), a(6)}};
}

nb::dict tick_dict(const BladeTick& t) {
  nb::dict d;
  d["force_N"] = from_vec3(t.force_N);
  d["torque_N_mm"] = from_vec3(t.torque_N_mm);
  d["capped_points"] = t.capped_points;
  d["deferred_points"] = t.deferred_points;
  d["max_transitions"] = t.max_transitions;
  d["transitions"] = t.transitions;
  d["rejected"] = t.rejected;
  d["rigid_rounds"] = t.rigid_rounds;
  d["contacts"] = t.contacts;
  d["unresolved"] = t.unresolved;
  d["unseated"] = t.unseated;
  return d;
}

nb::dict blade_counters_dict(const BladeCounters& c) {
  nb::dict d;
  d["ticks"] = c.ticks;
  d["rejected_ticks"] = c.rejected_ticks;
  d["out_of_workspace_ticks"] = c.out_of_workspace_ticks;
  d["unfinished_ticks"] = c.unfinished_ticks;
  d["capped_points"] = c.capped_points;
  d["deferred_points"] = c.deferred_points;
  d["total_transitions"] = c.total_transitions;
  d["max_transitions_in_tick"] = c.max_transitions_in_tick;
  d["rigid_rounds"] = c.rigid_rounds;
  d["max_rigid_rounds_in_tick"] = c.max_rigid_rounds_in_tick;
  d["unresolved_ticks"] = c.unresolved_ticks;
  d["unseated_ticks"] = c.unseated_ticks;
  return d;
}

BladeCoupling coupling_from(const std::string& name) {
  if (const auto coupling = hapticut::blade_coupling_from_name(name)) return *coupling;
  throw std::invalid_argument("coupling must be \"rigid\" or \"independent\", got \"" + name +
                              "\"");
}

BladeOrientation orientation_from(const std::string& name) {
  if (const auto orientation = hapticut::blade_orientation_from_name(name)) return *orientation;
  throw std::invalid_argument("orientation must be \"free\" or \"locked\", got \"" + name + "\"");
}

template <class T, class Get>
nb::ndarray<nb::numpy, T> per_proxy(std::size_t n, Get get) {
  auto out = new_array<T>({n});
  for (std::size_t i = 0; i < n; ++i) out.data()[i] = get(i);
  return out;
}

void bind_settings(nb::module_& m) {
  nb::class_<RuntimeSettings>(
      m, "RuntimeSettings",
      "Settings per tick (space.h): what a servo may change between ticks without "
      "rebuilding the Space. blade_transition_budget 0: 16 transitions per blade point.")
      .def(
          "__init__",
          [](RuntimeSettings* self, double stiffness_N_per_mm, int max_transitions_per_tick,
             double capped_tick_force_N, bool force_shading, int blade_transition_budget) {
            RuntimeSettings s;
            s.stiffness_N_per_mm = stiffness_N_per_mm;
            s.max_transitions_per_tick = max_transitions_per_tick;
            s.capped_tick_force_N = capped_tick_force_N;
            s.force_shading = force_shading;
            s.blade_transition_budget = blade_transition_budget;
            s.validate();
            new (self) RuntimeSettings(s);
          },
          nb::arg("stiffness_N_per_mm") = 0.1, nb::arg("max_transitions_per_tick") = 64,
          nb::arg("capped_tick_force_N") = 1.0, nb::arg("force_shading") = false,
          nb::arg("blade_transition_budget") = 0)
      .def_rw("stiffness_N_per_mm", &RuntimeSettings::stiffness_N_per_mm)
      .def_rw("max_transitions_per_tick", &RuntimeSettings::max_transitions_per_tick)
      .def_rw("capped_tick_force_N", &RuntimeSettings::capped_tick_force_N)
      .def_rw("force_shading", &RuntimeSettings::force_shading)
      .def_rw("blade_transition_budget", &RuntimeSettings::blade_transition_budget)
      .def("validate", &RuntimeSettings::validate,
           "Raises ValueError naming the first field out of range.")
      .def("__copy__", [](const RuntimeSettings& s) { return s; });
  m.def(
      "runtime_settings", [](const Space& space) { return space.runtime_settings(); },
      nb::arg("space"), "The scene's own settings per tick of a Space.");
  m.attr("BLADE_MAX_POINTS") = Blade::kMaxPoints;
  m.attr("BLADE_MAX_RIGID_ROUNDS") = Blade::kMaxRigidRounds;
  m.attr("WORKSPACE_MARGIN") = Space::kWorkspaceMargin;
}

}  // namespace

void bind_proxy(nb::module_& m) {
  bind_settings(m);
  nb::enum_<ProxyState>(m, "ProxyState", nb::is_arithmetic())
      .value("TET", ProxyState::Tet)
      .value("FACE", ProxyState::Face)
      .value("EDGE", ProxyState::Edge)
      .value("VERTEX", ProxyState::Vertex)
      .value("OUTSIDE", ProxyState::Outside);
  m.attr("STATE_NAMES") = nb::make_tuple("TET", "FACE", "EDGE", "VERTEX", "OUTSIDE");

  nb::class_<ProxySet>(m, "ProxySet",
                       "N proxies in one Space (which they keep alive), stepped together.")
      .def(nb::init<std::shared_ptr<const Space>, std::size_t>(), nb::arg("space"),
           nb::arg("count"))
      .def("__len__",
           [](const ProxySet& s) {
             const auto busy = claim(s);
             return s.proxies.size();
           })
      .def_prop_rw(
          "settings",
          [](const ProxySet& s) {
            const auto busy = claim(s);
            return s.settings;
          },
          [](ProxySet& s, const RuntimeSettings& settings) {
            const auto busy = claim(s);
            s.set_settings(settings);
          },
          "Settings of every step (a copy; assign a RuntimeSettings to change them).")
      .def(
          "reset",
          [](ProxySet& s, const PointsIn& points) {
            const auto busy = claim(s);
            s.check_count(points.shape(0));
            auto kinds = new_array<std::uint8_t>({points.shape(0)});
            for (std::size_t i = 0; i < s.proxies.size(); ++i) {
              kinds.data()[i] = static_cast<std::uint8_t>(
                  s.proxies[i].reset({points(i, 0), points(i, 1), points(i, 2)}));
            }
            return kinds;
          },
          nb::arg("points"),
          "Place each proxy for its device point; returns the start kind per proxy "
          "(0 inside a tet, 1 outside, 2 pushed out of rigid material). Raises ValueError "
          "for a point not finite or outside the scene's workspace.")
      .def(
          "step",
          [](ProxySet& s, const PointsIn& points, double dt_s) {
            const auto busy = claim(s);
            s.check_count(points.shape(0));
            const nb::gil_scoped_release released;
            for (std::size_t i = 0; i < s.proxies.size(); ++i) {
              s.last[i] = s.step_one(i, {points(i, 0), points(i, 1), points(i, 2)}, dt_s);
            }
          },
          nb::arg("points"), nb::arg("dt_s") = 0.001,
          "One servo tick for every proxy (the GIL is released meanwhile).")
      .def(
          "run",
          [](ProxySet& s,
             const nb::ndarray<const double, nb::shape<-1, -1, 3>, nb::c_contig, nb::device::cpu>&
                 path,
             double dt_s) {
            const auto busy = claim(s);
            s.check_count(path.shape(1));
            const std::size_t ticks = path.shape(0);
            auto q = new_array<double>({ticks, s.proxies.size(), 3});
            double* out = q.data();
            {
              const nb::gil_scoped_release released;
              for (std::size_t k = 0; k < ticks; ++k) {
                for (std::size_t i = 0; i < s.proxies.size(); ++i) {
                  s.last[i] = s.step_one(i, {path(k, i, 0), path(k, i, 1), path(k, i, 2)}, dt_s);
                  const Vec3& qi = s.proxies[i].q();
                  double* o = out + (k * s.proxies.size() + i) * 3;
                  o[0] = qi.x;
                  o[1] = qi.y;
                  o[2] = qi.z;
                }
              }
            }
            return q;
          },
          nb::arg("path"), nb::arg("dt_s") = 0.001,
          "Step through a (ticks, N, 3) path; returns q for every tick, shape (ticks, N, 3). "
          "The GIL is released meanwhile.")
      .def_prop_ro(
          "q",
          [](const ProxySet& s) {
            const auto busy = claim(s);
            return gather_points(s.proxies, [](const Proxy& p) { return p.q(); });
          },
          nb::rv_policy::move)
      .def_prop_ro(
          "force_N",
          [](const ProxySet& s) {
            const auto busy = claim(s);
            return gather_points(s.proxies, [](const Proxy& p) { return p.force_N(); });
          },
          "Each proxy's force, shaded when settings.force_shading is on.", nb::rv_policy::move)
      .def_prop_ro(
          "state",
          [](const ProxySet& s) {
            const auto busy = claim(s);
            return per_proxy<std::uint8_t>(s.proxies.size(), [&](std::size_t i) {
              return static_cast<std::uint8_t>(s.proxies[i].place().state);
            });
          },
          nb::rv_policy::move)
      .def_prop_ro(
          "tet",
          [](const ProxySet& s) {
            const auto busy = claim(s);
            return per_proxy<std::int32_t>(s.proxies.size(),
                                           [&](std::size_t i) { return s.proxies[i].place().tet; });
          },
          "The tet that owns each proxy's state (-1 when OUTSIDE).", nb::rv_policy::move)
      .def_prop_ro(
          "local",
          [](const ProxySet& s) {
            const auto busy = claim(s);
            return per_proxy<std::int8_t>(
                s.proxies.size(), [&](std::size_t i) { return s.proxies[i].place().local; });
          },
          "The owner's local face (0-3), edge (0-5) or vertex (0-3) of the state.",
          nb::rv_policy::move)
      .def_prop_ro(
          "last_transitions",
          [](const ProxySet& s) {
            const auto busy = claim(s);
            return per_proxy<std::int32_t>(s.proxies.size(),
                                           [&](std::size_t i) { return s.last[i].transitions; });
          },
          nb::rv_policy::move)
      .def_prop_ro(
          "last_capped",
          [](const ProxySet& s) {
            const auto busy = claim(s);
            return per_proxy<bool>(s.proxies.size(),
                                   [&](std::size_t i) { return s.last[i].capped; });
          },
          nb::rv_policy::move)
      .def_prop_ro(
          "last_rejected",
          [](const ProxySet& s) {
            const auto busy = claim(s);
            return per_proxy<bool>(s.proxies.size(),
                                   [&](std::size_t i) { return s.last[i].rejected; });
          },
          nb::rv_policy::move)
      .def_prop_ro(
          "counters",
          [](const ProxySet& s) {
            const auto busy = claim(s);
            return counters_dict(s.proxies);
          },
          nb::rv_policy::move)
      .def("clear_counters",
           [](ProxySet& s) {
             const auto busy = claim(s);
             for (Proxy& p : s.proxies) p.clear_counters();
           })
      .def(
          "check_invariants",
          [](const ProxySet& s, double factor) {
            const auto busy = claim(s);
            std::vector<std::string> problems;
            for (const Proxy& p : s.proxies) problems.push_back(p.check_invariants(factor));
            return problems;
          },
          nb::arg("tolerance_factor") = 100.0,
          "Per proxy: '' when its state agrees with q and q is outside rigid tets, else why.")
      .def(
          "set_place",
          [](ProxySet& s, std::int64_t i, int state, std::int64_t tet, int local,
             const nb::ndarray<const double, nb::shape<3>, nb::device::cpu>& q) {
            const auto busy = claim(s);
            if (i < 0 || i >= static_cast<std::int64_t>(s.proxies.size())) {
              throw nb::index_error(("proxy index " + std::to_string(i) + " out of range 0.." +
                                     std::to_string(s.proxies.size() - 1))
                                        .c_str());
            }
            if (state < 0 || state >= kProxyStateCount || tet < kNoTet || tet > INT32_MAX ||
                local < INT8_MIN || local > INT8_MAX) {
              throw std::invalid_argument("set_place: state " + std::to_string(state) + ", tet " +
                                          std::to_string(tet) + ", local " + std::to_string(local) +
                                          " out of range");
            }
            s.proxies[static_cast<std::size_t>(i)].set_place({static_cast<ProxyState>(state),
                                                              static_cast<std::int32_t>(tet),
                                                              static_cast<std::int8_t>(local),
                                                              {q(0), q(1), q(2)}});
          },
          nb::arg("index"), nb::arg("state"), nb::arg("tet"), nb::arg("local"), nb::arg("q"),
          "Put proxy i in a given state (tests and benchmarks of single transitions); "
          "IndexError or ValueError naming the value when out of range.");

  nb::class_<PyBlade>(m, "Blade",
                      "N points on a segment in the tool frame, one proxy each; keeps its Space "
                      "alive.")
      .def(
          "__init__",
          [](PyBlade* self, std::shared_ptr<const Space> space, const std::vector<double>& start_mm,
             const std::vector<double>& end_mm, std::int64_t points, const std::string& coupling,
             const std::string& orientation) {
            if (start_mm.size() != 3 || end_mm.size() != 3) {
              throw std::invalid_argument("start_mm and end_mm need 3 coordinates");
            }
            if (points < 1 || points > Blade::kMaxPoints) {
              throw std::invalid_argument("a blade has 1.." + std::to_string(Blade::kMaxPoints) +
                                          " points, got " + std::to_string(points));
            }
            BladeSpec spec{"blade",
                           {start_mm[0], start_mm[1], start_mm[2]},
                           {end_mm[0], end_mm[1], end_mm[2]},
                           static_cast<int>(points)};
            spec.coupling = coupling_from(coupling);
            spec.orientation = orientation_from(orientation);
            new (self) PyBlade(std::move(space), spec);
          },
          nb::arg("space"), nb::arg("start_mm"), nb::arg("end_mm"), nb::arg("points") = 50,
          nb::arg("coupling") = "rigid", nb::arg("orientation") = "free",
          "coupling: \"rigid\" (the default: one ideal pose for the whole edge) or "
          "\"independent\" (the paper's points, each on its own); orientation of a rigid "
          "blade: \"free\" (the default) or \"locked\" to the device's.")
      .def_prop_ro("coupling",
                   [](const PyBlade& b) {
                     return std::string(hapticut::blade_coupling_name(b.blade.coupling()));
                   })
      .def_prop_rw(
          "orientation",
          [](const PyBlade& b) {
            const auto busy = claim(b);
            return std::string(hapticut::blade_orientation_name(b.blade.orientation()));
          },
          [](PyBlade& b, const std::string& orientation) {
            const auto busy = claim(b);
            b.blade.set_orientation(orientation_from(orientation),
                                    hapticut::setting_range::kRampTime.default_value);
          },
          "A rigid blade's orientation, \"free\" or \"locked\"; from the next step on, turned in "
          "over the default ramp time (0.5 s) so the force does not jump.")
      .def_prop_ro(
          "ideal_pose",
          [](const PyBlade& b) {
            const auto busy = claim(b);
            const Pose& pose = b.blade.ideal_pose();
            auto out = new_array<double>({7});
            double* d = out.data();
            d[0] = pose.position_mm.x;
            d[1] = pose.position_mm.y;
            d[2] = pose.position_mm.z;
            d[3] = pose.rotation.w;
            d[4] = pose.rotation.x;
            d[5] = pose.rotation.y;
            d[6] = pose.rotation.z;
            return out;
          },
          "(x, y, z, qw, qx, qy, qz) of the rigid blade's ideal tool pose (its points are q); "
          "for independent points, the last device pose.",
          nb::rv_policy::move)
      .def_prop_ro(
          "point_count",
          [](const PyBlade& b) {
            const auto busy = claim(b);
            return b.blade.point_count();
          },
          nb::rv_policy::move)
      .def_prop_rw(
          "settings",
          [](const PyBlade& b) {
            const auto busy = claim(b);
            return b.settings;
          },
          [](PyBlade& b, const RuntimeSettings& settings) {
            const auto busy = claim(b);
            settings.validate();
            b.settings = settings;
          },
          "Settings of every step (a copy; assign a RuntimeSettings to change them).")
      .def(
          "reset",
          [](PyBlade& b, const nb::ndarray<const double, nb::shape<7>, nb::device::cpu>& pose) {
            const auto busy = claim(b);
            b.blade.reset(pose_from(pose));
          },
          nb::arg("pose"),
          "pose: (x, y, z, qw, qx, qy, qz), position in mm. Raises ValueError for a pose "
          "not finite, a zero quaternion or a point outside the scene's workspace.")
      .def_prop_ro(
          "cut_tets",
          [](const PyBlade& b) {
            const auto busy = claim(b);
            const std::vector<std::int32_t> tets = b.blade.cuts().cut_tets();
            auto out = new_array<std::int32_t>({tets.size()});
            std::copy(tets.begin(), tets.end(), out.data());
            return out;
          },
          "(k,) int32, increasing: the tets the blade has cut (docs/decisions.md, \"Cut "
          "memory\"); a cut tet of a material with a cut_to acts as that material.",
          nb::rv_policy::move)
      .def(
          "reset_cuts",
          [](PyBlade& b) {
            const auto busy = claim(b);
            b.blade.reset_cuts();
          },
          "Uncuts every tet (reset does not: the cuts stay with the scene).")
      .def_prop_ro(
          "cut_order",
          [](const PyBlade& b) {
            const auto busy = claim(b);
            const std::span<const std::int32_t> order = b.blade.cuts().cut_order();
            auto out = new_array<std::int32_t>({order.size()});
            std::copy(order.begin(), order.end(), out.data());
            return out;
          },
          "(k,) int32: the cut tets in the order they were cut (what the servo streams, "
          "records and saves).",
          nb::rv_policy::move)
      .def(
          "set_cuts",
          [](PyBlade& b,
             const nb::ndarray<const std::int32_t, nb::ndim<1>, nb::device::cpu>& tets) {
            const auto busy = claim(b);
            b.blade.set_cuts({tets.data(), tets.shape(0)});
          },
          nb::arg("tets"),
          "Uncuts every tet, then cuts these in order. Raises ValueError naming the entry for "
          "a tet out of range, given twice or of a material that is never cut (then nothing "
          "is cut).")
      .def(
          "step",
          [](PyBlade& b, const nb::ndarray<const double, nb::shape<7>, nb::device::cpu>& pose,
             double dt_s) {
            const auto busy = claim(b);
            return tick_dict(b.blade.step(pose_from(pose), dt_s, b.settings));
          },
          nb::arg("pose"), nb::arg("dt_s") = 0.001)
      .def(
          "run",
          [](PyBlade& b,
             const nb::ndarray<const double, nb::shape<-1, 7>, nb::c_contig, nb::device::cpu>&
                 poses,
             double dt_s) {
            const auto busy = claim(b);
            const std::size_t n = poses.shape(0);
            auto force = new_array<double>({n, 3});
            auto torque = new_array<double>({n, 3});
            auto capped = new_array<std::int32_t>({n});
            auto transitions = new_array<std::int32_t>({n});
            auto rejected = new_array<bool>({n});
            double* force_out = force.data();
            double* torque_out = torque.data();
            std::int32_t* capped_out = capped.data();
            std::int32_t* transitions_out = transitions.data();
            bool* rejected_out = rejected.data();
            {
              const nb::gil_scoped_release released;
              for (std::size_t k = 0; k < n; ++k) {
                const Pose pose{{poses(k, 0), poses(k, 1), poses(k, 2)},
                                {poses(k, 3), poses(k, 4), poses(k, 5), poses(k, 6)}};
                const BladeTick t = b.blade.step(pose, dt_s, b.settings);
                for (int a = 0; a < 3; ++a) {
                  force_out[3 * k + a] = t.force_N[a];
                  torque_out[3 * k + a] = t.torque_N_mm[a];
                }
                capped_out[k] = t.capped_points;
                transitions_out[k] = t.max_transitions;
                rejected_out[k] = t.rejected;
              }
            }
            nb::dict d;
            d["force_N"] = force;
            d["torque_N_mm"] = torque;
            d["capped_points"] = capped;
            d["max_transitions"] = transitions;
            d["rejected"] = rejected;
            return d;
          },
          nb::arg("poses"), nb::arg("dt_s") = 0.001,
          "Step along an (M, 7) path of poses in one call (the GIL is released meanwhile); "
          "forces and torques per tick.")
      .def_prop_ro(
          "p",
          [](const PyBlade& b) {
            const auto busy = claim(b);
            return from_points(b.blade.world_points());
          },
          nb::rv_policy::move)
      .def_prop_ro(
          "q",
          [](const PyBlade& b) {
            const auto busy = claim(b);
            return gather_points(b.blade.proxies(), [](const Proxy& p) { return p.q(); });
          },
          nb::rv_policy::move)
      .def_prop_ro(
          "force_N",
          [](const PyBlade& b) {
            const auto busy = claim(b);
            return gather_points(b.blade.proxies(), [](const Proxy& p) { return p.force_N(); });
          },
          "Each point's force of the last tick.", nb::rv_policy::move)
      .def_prop_ro(
          "state",
          [](const PyBlade& b) {
            const auto busy = claim(b);
            return per_proxy<std::uint8_t>(b.blade.proxies().size(), [&](std::size_t i) {
              return static_cast<std::uint8_t>(b.blade.proxies()[i].place().state);
            });
          },
          nb::rv_policy::move)
      .def_prop_ro(
          "last_tick",
          [](const PyBlade& b) {
            const auto busy = claim(b);
            return tick_dict(b.blade.last_tick());
          },
          nb::rv_policy::move)
      .def_prop_ro(
          "blade_counters",
          [](const PyBlade& b) {
            const auto busy = claim(b);
            return blade_counters_dict(b.blade.counters());
          },
          nb::rv_policy::move)
      .def_prop_ro(
          "counters",
          [](const PyBlade& b) {
            const auto busy = claim(b);
            return counters_dict(b.blade.proxies());
          },
          nb::rv_policy::move)
      .def(
          "snapshot",
          [](const PyBlade& b) {
            const auto busy = claim(b);
            const std::size_t n = static_cast<std::size_t>(b.blade.point_count());
            std::vector<ProxySnapshot> points(n);
            BladeSnapshotHeader header;
            b.blade.snapshot(header, points);
            nb::dict d;
            d["tick_index"] = header.tick_index;
            d["tick"] = tick_dict(header.tick);
            d["counters"] = blade_counters_dict(header.counters);
            d["point_count"] = header.point_count;
            auto state = new_array<std::uint8_t>({n});
            auto tet = new_array<std::int32_t>({n});
            auto transitions = new_array<std::int32_t>({n});
            auto capped = new_array<bool>({n});
            auto deferred = new_array<bool>({n});
            std::vector<Vec3> q(n);
            std::vector<Vec3> p(n);
            std::vector<Vec3> f(n);
            for (std::size_t i = 0; i < n; ++i) {
              state.data()[i] = static_cast<std::uint8_t>(points[i].place.state);
              tet.data()[i] = points[i].place.tet;
              transitions.data()[i] = points[i].tick.transitions;
              capped.data()[i] = points[i].tick.capped;
              deferred.data()[i] = points[i].tick.deferred;
              q[i] = points[i].place.q;
              p[i] = points[i].p;
              f[i] = points[i].force_N;
            }
            d["state"] = state;
            d["tet"] = tet;
            d["q"] = from_points(q);
            d["p"] = from_points(p);
            d["force_N"] = from_points(f);
            d["transitions"] = transitions;
            d["capped"] = capped;
            d["deferred"] = deferred;
            return d;
          },
          "The last tick as the servo's snapshot holds it (Blade::snapshot).");
}

}  // namespace hapticut::python
