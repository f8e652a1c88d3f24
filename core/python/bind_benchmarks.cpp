// Timing loops of `hapticut bench`, in C++ so no Python overhead is measured.
// They return raw figures; the Python side prints the tables.
#include <nanobind/stl/optional.h>
#include <nanobind/stl/shared_ptr.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "arrays.h"
#include "hapticut/blade.h"
#include "hapticut/proxy.h"

namespace hapticut::python {

namespace {

using Clock = std::chrono::steady_clock;

double elapsed_ns(Clock::time_point start) {
  return std::chrono::duration<double, std::nano>(Clock::now() - start).count();
}

Vec3 vec3_from(const nb::ndarray<const double, nb::shape<3>, nb::device::cpu>& a) {
  return {a(0), a(1), a(2)};
}

}  // namespace

}  // namespace hapticut::python

namespace hapticut {

// See Proxy's friend declaration: the timing loop's restore of a checked start place.
struct TransitionTimingAccess {
  static void restore(Proxy& proxy, const ProxyPlace& place) { proxy.place_ = place; }
};

}  // namespace hapticut

namespace hapticut::python {

void bind_benchmarks(nb::module_& m) {
  m.def(
      "time_transition",
      [](std::shared_ptr<const Space> space, int state, std::int64_t tet, int local,
         const nb::ndarray<const double, nb::shape<3>, nb::device::cpu>& q_array,
         const nb::ndarray<const double, nb::shape<3>, nb::device::cpu>& p_array, int repeats,
         int batches) {
        if (repeats < 1 || batches < 1) {
          throw std::invalid_argument("repeats and batches must be >= 1, got " +
                                      std::to_string(repeats) + " and " + std::to_string(batches));
        }
        if (state < 0 || state >= kProxyStateCount || tet < kNoTet || tet > INT32_MAX ||
            local < INT8_MIN || local > INT8_MAX) {
          throw std::invalid_argument("time_transition: state " + std::to_string(state) + ", tet " +
                                      std::to_string(tet) + ", local " + std::to_string(local) +
                                      " out of range");
        }
        const ProxyPlace start{static_cast<ProxyState>(state), static_cast<std::int32_t>(tet),
                               static_cast<std::int8_t>(local), vec3_from(q_array)};
        const Vec3 p = vec3_from(p_array);
        if (!is_finite(p)) throw std::invalid_argument("time_transition: p is not finite");
        MoveContext context;
        context.stiffness_N_per_mm = space->settings().stiffness_N_per_mm;
        context.tolerance_mm = space->tolerance();
        Proxy proxy(space);
        proxy.set_place(start);  // Throws naming a tet or local index out of range.
        const nb::gil_scoped_release released;
        const Transition kind = proxy.transition(p, context);
        const ProxyPlace after = proxy.place();
        std::vector<double> per_call;
        double sink = 0.0;
        for (int b = 0; b < batches; ++b) {
          // The same loop without the transition, to subtract its own cost.
          auto t0 = Clock::now();
          for (int r = 0; r < repeats; ++r) {
            TransitionTimingAccess::restore(proxy, start);
            sink += proxy.place().q.x;
            asm volatile("" ::: "memory");
          }
          const double empty_ns = elapsed_ns(t0);
          t0 = Clock::now();
          for (int r = 0; r < repeats; ++r) {
            TransitionTimingAccess::restore(proxy, start);
            const Transition t = proxy.transition(p, context);
            sink += proxy.place().q.x + static_cast<double>(t.changed);
            asm volatile("" ::: "memory");
          }
          per_call.push_back(std::max(0.0, elapsed_ns(t0) - empty_ns) / repeats);
        }
        std::sort(per_call.begin(), per_call.end());
        const nb::gil_scoped_acquire acquired;
        nb::dict d;
        d["ns"] = per_call[per_call.size() / 2];
        d["ns_min"] = per_call.front();
        d["from"] = kind.from;
        d["to"] = kind.to;
        d["to_neighbour"] = kind.to_neighbour;
        d["changed"] = kind.changed;
        d["to_tet"] = after.tet;
        d["q_after"] = from_vec3(after.q);
        d["sink"] = sink;
        return d;
      },
      nb::arg("space"), nb::arg("state"), nb::arg("tet"), nb::arg("local"), nb::arg("q"),
      nb::arg("p"), nb::arg("repeats") = 20000, nb::arg("batches") = 15,
      "Time one transition from a given place toward p: median ns per call over batches, "
      "and which transition it was.");

  m.def(
      "time_blade",
      [](std::shared_ptr<const Space> space, const std::vector<double>& start_mm,
         const std::vector<double>& end_mm, int points,
         const nb::ndarray<const double, nb::shape<-1, 7>, nb::c_contig, nb::device::cpu>& poses,
         double dt_s, std::optional<RuntimeSettings> settings_in, const std::string& coupling,
         bool cut_memory) {
        if (poses.shape(0) < 1) throw std::invalid_argument("time_blade needs at least one pose");
        const auto parsed_coupling = blade_coupling_from_name(coupling);
        if (!parsed_coupling) {
          throw std::invalid_argument("coupling must be \"rigid\" or \"independent\", got \"" +
                                      coupling + "\"");
        }
        const RuntimeSettings settings = settings_in ? *settings_in : space->runtime_settings();
        settings.validate();
        Blade blade(space, {"bench",
                            {start_mm.at(0), start_mm.at(1), start_mm.at(2)},
                            {end_mm.at(0), end_mm.at(1), end_mm.at(2)},
                            points,
                            *parsed_coupling});
        blade.set_cut_memory(cut_memory);
        const std::size_t n = poses.shape(0);
        auto pose_at = [&](std::size_t k) {
          return Pose{{poses(k, 0), poses(k, 1), poses(k, 2)},
                      {poses(k, 3), poses(k, 4), poses(k, 5), poses(k, 6)}};
        };
        blade.reset(pose_at(0));
        auto tick_ns = new_array<double>({n});
        auto transitions = new_array<std::int32_t>({n});
        auto tick_transitions = new_array<std::int32_t>({n});
        auto capped = new_array<std::int32_t>({n});
        auto deferred = new_array<std::int32_t>({n});
        auto rounds = new_array<std::int32_t>({n});
        auto contacts = new_array<std::int32_t>({n});
        auto unresolved = new_array<std::int32_t>({n});
        {
          const nb::gil_scoped_release released;
          for (std::size_t k = 0; k < n; ++k) {
            const auto t0 = Clock::now();
            const BladeTick t = blade.step(pose_at(k), dt_s, settings);
            tick_ns.data()[k] = elapsed_ns(t0);
            transitions.data()[k] = t.max_transitions;
            tick_transitions.data()[k] = t.transitions;
            capped.data()[k] = t.capped_points;
            deferred.data()[k] = t.deferred_points;
            rounds.data()[k] = t.rigid_rounds;
            contacts.data()[k] = t.contacts;
            unresolved.data()[k] = t.unresolved ? 1 : 0;
          }
        }
        nb::dict d;
        d["tick_ns"] = tick_ns;
        d["max_transitions"] = transitions;
        d["tick_transitions"] = tick_transitions;
        d["capped_points"] = capped;
        d["deferred_points"] = deferred;
        d["rigid_rounds"] = rounds;
        d["contacts"] = contacts;
        d["unresolved"] = unresolved;
        d["counters"] = nb::none();
        d["total_transitions"] = blade.counters().total_transitions;
        d["unfinished_ticks"] = blade.counters().unfinished_ticks;
        d["budget"] = settings.blade_budget(blade.point_count());
        d["cut_tets"] = blade.cuts().cut_count();
        return d;
      },
      nb::arg("space"), nb::arg("start_mm"), nb::arg("end_mm"), nb::arg("points"), nb::arg("poses"),
      nb::arg("dt_s") = 0.001, nb::arg("settings") = nb::none(), nb::arg("coupling") = "rigid",
      nb::arg("cut_memory") = true,
      "Run a blade along (M, 7) poses; wall-clock ns of every tick (GIL released). "
      "settings: a RuntimeSettings, default the Space's own; coupling: \"rigid\" (the "
      "default) or \"independent\"; cut_memory: False for a blade that reads and cuts no "
      "tet (Blade::set_cut_memory). cut_tets: the tets the stroke cut, from none.");
}

}  // namespace hapticut::python
