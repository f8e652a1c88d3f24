// Bindings: many proxies stepped at once from an (N, 3) array (one call per
// tick, no Python loop per point), and the blade.
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "arrays.h"
#include "hapticut/blade.h"
#include "hapticut/proxy.h"

namespace hapticut::python {

namespace {

// N proxies in one Space; keeps the Space alive through nanobind's keep_alive.
struct ProxySet {
  ProxySet(const Space& space, std::size_t count) : proxies(count, Proxy(space)) {
    last.resize(count);
  }

  void check_count(std::size_t n) const {
    if (n != proxies.size()) {
      throw std::invalid_argument("expected " + std::to_string(proxies.size()) + " points, got " +
                                  std::to_string(n));
    }
  }

  std::vector<Proxy> proxies;
  std::vector<TickResult> last;
};

nb::dict counters_dict(const std::vector<Proxy>& proxies) {
  const std::size_t n = proxies.size();
  auto transitions = new_array<std::uint64_t>({n, kProxyStateCount, kProxyStateCount, 2});
  auto ticks = new_array<std::uint64_t>({n});
  auto capped = new_array<std::uint64_t>({n});
  auto rejected = new_array<std::uint64_t>({n});
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
    max_in_tick.data()[i] = c.max_transitions_in_tick;
    total.data()[i] = c.total_transitions;
  }
  nb::dict d;
  d["transitions"] = transitions;  // [proxy, from, to, to_neighbour]
  d["ticks"] = ticks;
  d["capped_ticks"] = capped;
  d["rejected_inputs"] = rejected;
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

}  // namespace

void bind_proxy(nb::module_& m) {
  nb::enum_<ProxyState>(m, "ProxyState", nb::is_arithmetic())
      .value("TET", ProxyState::Tet)
      .value("FACE", ProxyState::Face)
      .value("EDGE", ProxyState::Edge)
      .value("VERTEX", ProxyState::Vertex)
      .value("OUTSIDE", ProxyState::Outside);
  m.attr("STATE_NAMES") = nb::make_tuple("TET", "FACE", "EDGE", "VERTEX", "OUTSIDE");

  nb::class_<ProxySet>(m, "ProxySet", "N proxies in one Space, stepped together.")
      .def(nb::init<const Space&, std::size_t>(), nb::arg("space"), nb::arg("count"),
           nb::keep_alive<1, 2>())
      .def("__len__", [](const ProxySet& s) { return s.proxies.size(); })
      .def(
          "reset",
          [](ProxySet& s, const PointsIn& points) {
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
          "(0 inside a tet, 1 outside, 2 pushed out of rigid material).")
      .def(
          "step",
          [](ProxySet& s, const PointsIn& points, double dt_s) {
            s.check_count(points.shape(0));
            for (std::size_t i = 0; i < s.proxies.size(); ++i) {
              s.last[i] = s.proxies[i].step({points(i, 0), points(i, 1), points(i, 2)}, dt_s);
            }
          },
          nb::arg("points"), nb::arg("dt_s") = 0.001, "One servo tick for every proxy.")
      .def(
          "run",
          [](ProxySet& s,
             const nb::ndarray<const double, nb::shape<-1, -1, 3>, nb::c_contig, nb::device::cpu>&
                 path,
             double dt_s) {
            s.check_count(path.shape(1));
            const std::size_t ticks = path.shape(0);
            auto q = new_array<double>({ticks, s.proxies.size(), 3});
            for (std::size_t k = 0; k < ticks; ++k) {
              for (std::size_t i = 0; i < s.proxies.size(); ++i) {
                s.last[i] = s.proxies[i].step({path(k, i, 0), path(k, i, 1), path(k, i, 2)}, dt_s);
                const Vec3& qi = s.proxies[i].q();
                double* out = q.data() + (k * s.proxies.size() + i) * 3;
                out[0] = qi.x;
                out[1] = qi.y;
                out[2] = qi.z;
              }
            }
            return q;
          },
          nb::arg("path"), nb::arg("dt_s") = 0.001,
          "Step through a (ticks, N, 3) path; returns q for every tick, shape (ticks, N, 3).")
      .def_prop_ro(
          "q",
          [](const ProxySet& s) {
            return gather_points(s.proxies, [](const Proxy& p) { return p.q(); });
          },
          nb::rv_policy::move)
      .def_prop_ro(
          "force_N",
          [](const ProxySet& s) {
            return gather_points(s.proxies, [](const Proxy& p) { return p.force_N(); });
          },
          nb::rv_policy::move)
      .def_prop_ro(
          "state",
          [](const ProxySet& s) {
            auto out = new_array<std::uint8_t>({s.proxies.size()});
            for (std::size_t i = 0; i < s.proxies.size(); ++i) {
              out.data()[i] = static_cast<std::uint8_t>(s.proxies[i].place().state);
            }
            return out;
          },
          nb::rv_policy::move)
      .def_prop_ro(
          "tet",
          [](const ProxySet& s) {
            auto out = new_array<std::int32_t>({s.proxies.size()});
            for (std::size_t i = 0; i < s.proxies.size(); ++i) {
              out.data()[i] = s.proxies[i].place().tet;
            }
            return out;
          },
          "The tet that owns each proxy's state (-1 when OUTSIDE).", nb::rv_policy::move)
      .def_prop_ro(
          "local",
          [](const ProxySet& s) {
            auto out = new_array<std::int8_t>({s.proxies.size()});
            for (std::size_t i = 0; i < s.proxies.size(); ++i) {
              out.data()[i] = s.proxies[i].place().local;
            }
            return out;
          },
          "The owner's local face (0-3), edge (0-5) or vertex (0-3) of the state.",
          nb::rv_policy::move)
      .def_prop_ro(
          "last_transitions",
          [](const ProxySet& s) {
            auto out = new_array<std::int32_t>({s.proxies.size()});
            for (std::size_t i = 0; i < s.proxies.size(); ++i) {
              out.data()[i] = s.last[i].transitions;
            }
            return out;
          },
          nb::rv_policy::move)
      .def_prop_ro(
          "last_capped",
          [](const ProxySet& s) {
            auto out = new_array<bool>({s.proxies.size()});
            for (std::size_t i = 0; i < s.proxies.size(); ++i) {
              out.data()[i] = s.last[i].capped;
            }
            return out;
          },
          nb::rv_policy::move)
      .def_prop_ro(
          "counters", [](const ProxySet& s) { return counters_dict(s.proxies); },
          nb::rv_policy::move)
      .def("clear_counters",
           [](ProxySet& s) {
             for (Proxy& p : s.proxies) p.clear_counters();
           })
      .def(
          "check_invariants",
          [](const ProxySet& s, double factor) {
            std::vector<std::string> problems;
            for (const Proxy& p : s.proxies) problems.push_back(p.check_invariants(factor));
            return problems;
          },
          nb::arg("tolerance_factor") = 100.0,
          "Per proxy: '' when its state agrees with q and q is outside rigid tets, else why.")
      .def(
          "set_place",
          [](ProxySet& s, std::size_t i, ProxyState state, std::int32_t tet, int local,
             const nb::ndarray<const double, nb::shape<3>, nb::device::cpu>& q) {
            if (i >= s.proxies.size()) throw std::out_of_range("proxy index");
            s.proxies[i].set_place(
                {state, tet, static_cast<std::int8_t>(local), {q(0), q(1), q(2)}});
          },
          nb::arg("index"), nb::arg("state"), nb::arg("tet"), nb::arg("local"), nb::arg("q"),
          "Put proxy i in a given state (tests and benchmarks of single transitions).");

  nb::class_<Blade>(m, "Blade", "N points on a segment in the tool frame, one proxy each.")
      .def(
          "__init__",
          [](Blade* self, const Space& space, const std::vector<double>& start_mm,
             const std::vector<double>& end_mm, int points) {
            if (start_mm.size() != 3 || end_mm.size() != 3) {
              throw std::invalid_argument("start_mm and end_mm need 3 coordinates");
            }
            new (self) Blade(space, {"blade",
                                     {start_mm[0], start_mm[1], start_mm[2]},
                                     {end_mm[0], end_mm[1], end_mm[2]},
                                     points});
          },
          nb::arg("space"), nb::arg("start_mm"), nb::arg("end_mm"), nb::arg("points") = 50,
          nb::keep_alive<1, 2>())
      .def_prop_ro("point_count", &Blade::point_count, nb::rv_policy::move)
      .def(
          "reset",
          [](Blade& b, const nb::ndarray<const double, nb::shape<7>, nb::device::cpu>& pose) {
            b.reset(pose_from(pose));
          },
          nb::arg("pose"), "pose: (x, y, z, qw, qx, qy, qz), position in mm.")
      .def(
          "step",
          [](Blade& b, const nb::ndarray<const double, nb::shape<7>, nb::device::cpu>& pose,
             double dt_s) {
            const BladeTick t = b.step(pose_from(pose), dt_s);
            nb::dict d;
            d["force_N"] = from_vec3(t.force_N);
            d["torque_N_mm"] = from_vec3(t.torque_N_mm);
            d["capped_points"] = t.capped_points;
            d["max_transitions"] = t.max_transitions;
            d["rejected"] = t.rejected;
            return d;
          },
          nb::arg("pose"), nb::arg("dt_s") = 0.001)
      .def(
          "run",
          [](Blade& b,
             const nb::ndarray<const double, nb::shape<-1, 7>, nb::c_contig, nb::device::cpu>&
                 poses,
             double dt_s) {
            const std::size_t n = poses.shape(0);
            auto force = new_array<double>({n, 3});
            auto torque = new_array<double>({n, 3});
            auto capped = new_array<std::int32_t>({n});
            auto transitions = new_array<std::int32_t>({n});
            for (std::size_t k = 0; k < n; ++k) {
              const Pose pose{{poses(k, 0), poses(k, 1), poses(k, 2)},
                              {poses(k, 3), poses(k, 4), poses(k, 5), poses(k, 6)}};
              const BladeTick t = b.step(pose, dt_s);
              for (int a = 0; a < 3; ++a) {
                force.data()[3 * k + a] = t.force_N[a];
                torque.data()[3 * k + a] = t.torque_N_mm[a];
              }
              capped.data()[k] = t.capped_points;
              transitions.data()[k] = t.max_transitions;
            }
            nb::dict d;
            d["force_N"] = force;
            d["torque_N_mm"] = torque;
            d["capped_points"] = capped;
            d["max_transitions"] = transitions;
            return d;
          },
          nb::arg("poses"), nb::arg("dt_s") = 0.001,
          "Step along an (M, 7) path of poses in one call; forces and torques per tick.")
      .def_prop_ro(
          "p", [](const Blade& b) { return from_points(b.world_points()); }, nb::rv_policy::move)
      .def_prop_ro(
          "q",
          [](const Blade& b) {
            return gather_points(b.proxies(), [](const Proxy& p) { return p.q(); });
          },
          nb::rv_policy::move)
      .def_prop_ro(
          "state",
          [](const Blade& b) {
            auto out = new_array<std::uint8_t>({b.proxies().size()});
            for (std::size_t i = 0; i < b.proxies().size(); ++i) {
              out.data()[i] = static_cast<std::uint8_t>(b.proxies()[i].place().state);
            }
            return out;
          },
          nb::rv_policy::move)
      .def_prop_ro(
          "counters", [](const Blade& b) { return counters_dict(b.proxies()); },
          nb::rv_policy::move);
}

}  // namespace hapticut::python
