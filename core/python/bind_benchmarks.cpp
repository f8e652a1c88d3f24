// Timing loops of `hapticut bench`, in C++ so no Python overhead is measured.
// They return raw figures; the Python side prints the tables.
#include <nanobind/stl/vector.h>

#include <algorithm>
#include <chrono>
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

void bind_benchmarks(nb::module_& m) {
  m.def(
      "time_transition",
      [](const Space& space, ProxyState state, std::int32_t tet, int local,
         const nb::ndarray<const double, nb::shape<3>, nb::device::cpu>& q_array,
         const nb::ndarray<const double, nb::shape<3>, nb::device::cpu>& p_array, int repeats,
         int batches) {
        const ProxyPlace start{state, tet, static_cast<std::int8_t>(local), vec3_from(q_array)};
        const Vec3 p = vec3_from(p_array);
        MoveContext context;
        context.stiffness_N_per_mm = space.settings().stiffness_N_per_mm;
        context.tolerance_mm = space.tolerance();
        Proxy proxy(space);
        proxy.set_place(start);
        const Transition kind = proxy.transition(p, context);
        const ProxyPlace after = proxy.place();
        std::vector<double> per_call;
        double sink = 0.0;
        for (int b = 0; b < batches; ++b) {
          // The same loop without the transition, to subtract its own cost.
          auto t0 = Clock::now();
          for (int r = 0; r < repeats; ++r) {
            proxy.set_place(start);
            sink += proxy.place().q.x;
            asm volatile("" ::: "memory");
          }
          const double empty_ns = elapsed_ns(t0);
          t0 = Clock::now();
          for (int r = 0; r < repeats; ++r) {
            proxy.set_place(start);
            const Transition t = proxy.transition(p, context);
            sink += proxy.place().q.x + static_cast<double>(t.changed);
            asm volatile("" ::: "memory");
          }
          per_call.push_back(std::max(0.0, elapsed_ns(t0) - empty_ns) / repeats);
        }
        std::sort(per_call.begin(), per_call.end());
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
      [](const Space& space, const std::vector<double>& start_mm, const std::vector<double>& end_mm,
         int points,
         const nb::ndarray<const double, nb::shape<-1, 7>, nb::c_contig, nb::device::cpu>& poses,
         double dt_s) {
        Blade blade(space, {"bench",
                            {start_mm.at(0), start_mm.at(1), start_mm.at(2)},
                            {end_mm.at(0), end_mm.at(1), end_mm.at(2)},
                            points});
        const std::size_t n = poses.shape(0);
        auto pose_at = [&](std::size_t k) {
          return Pose{{poses(k, 0), poses(k, 1), poses(k, 2)},
                      {poses(k, 3), poses(k, 4), poses(k, 5), poses(k, 6)}};
        };
        blade.reset(pose_at(0));
        auto tick_ns = new_array<double>({n});
        auto transitions = new_array<std::int32_t>({n});
        auto capped = new_array<std::int32_t>({n});
        for (std::size_t k = 0; k < n; ++k) {
          const auto t0 = Clock::now();
          const BladeTick t = blade.step(pose_at(k), dt_s);
          tick_ns.data()[k] = elapsed_ns(t0);
          transitions.data()[k] = t.max_transitions;
          capped.data()[k] = t.capped_points;
        }
        nb::dict d;
        d["tick_ns"] = tick_ns;
        d["max_transitions"] = transitions;
        d["capped_points"] = capped;
        d["counters"] = nb::none();
        std::uint64_t total = 0;
        for (const Proxy& p : blade.proxies()) total += p.counters().total_transitions;
        d["total_transitions"] = total;
        return d;
      },
      nb::arg("space"), nb::arg("start_mm"), nb::arg("end_mm"), nb::arg("points"), nb::arg("poses"),
      nb::arg("dt_s") = 0.001, "Run a blade along (M, 7) poses; wall-clock ns of every tick.");
}

}  // namespace hapticut::python
