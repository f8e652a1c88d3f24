// No allocation per tick, proven: this test binary replaces the global
// operator new and counts every heap allocation made while counting is on,
// over 10^6 proxy steps and 10^4 blade ticks (force shading on and off, the
// work budget exhausted, snapshots, rejected inputs). Construction and reset
// may allocate (proxy.h, blade.h) and run with counting off.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <memory>
#include <new>
#include <random>
#include <vector>

#include "hapticut/blade.h"
#include "hapticut/proxy.h"
#include "hapticut/reference_meshes.h"
#include "hapticut/scene_io.h"

#ifndef HAPTICUT_EXAMPLES_DIR
#define HAPTICUT_EXAMPLES_DIR "examples"
#endif

namespace {

std::atomic<bool> g_counting{false};
std::atomic<std::uint64_t> g_allocations{0};

void* counted_allocation(std::size_t size, std::size_t alignment) {
  if (g_counting.load(std::memory_order_relaxed)) {
    g_allocations.fetch_add(1, std::memory_order_relaxed);
  }
  if (size == 0) size = 1;
  void* p = alignment > alignof(std::max_align_t)
                ? std::aligned_alloc(alignment, (size + alignment - 1) / alignment * alignment)
                : std::malloc(size);
  return p;
}

// Counts the allocations of `body`.
template <class Body>
std::uint64_t allocations_of(Body body) {
  const std::uint64_t before = g_allocations.load();
  g_counting = true;
  body();
  g_counting = false;
  return g_allocations.load() - before;
}

}  // namespace

// The replaced global allocation functions (all of them route here).
void* operator new(std::size_t size) {
  void* p = counted_allocation(size, 0);
  if (p == nullptr) throw std::bad_alloc();
  return p;
}
void* operator new[](std::size_t size) { return operator new(size); }
void* operator new(std::size_t size, const std::nothrow_t& /*tag*/) noexcept {
  return counted_allocation(size, 0);
}
void* operator new[](std::size_t size, const std::nothrow_t& /*tag*/) noexcept {
  return counted_allocation(size, 0);
}
void* operator new(std::size_t size, std::align_val_t alignment) {
  void* p = counted_allocation(size, static_cast<std::size_t>(alignment));
  if (p == nullptr) throw std::bad_alloc();
  return p;
}
void* operator new[](std::size_t size, std::align_val_t alignment) {
  return operator new(size, alignment);
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t /*size*/) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t /*size*/) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t /*alignment*/) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t /*alignment*/) noexcept { std::free(p); }
void operator delete(void* p, std::size_t /*size*/, std::align_val_t /*alignment*/) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t /*size*/, std::align_val_t /*alignment*/) noexcept {
  std::free(p);
}

namespace hapticut {
namespace {

constexpr double kDt = 0.001;

// A jittered grid with every material model: free, drag, rigid, viscous, membrane;
// with cut memory, flesh cut to fat and skin cut to air (docs/decisions.md, "Cut memory").
std::shared_ptr<const Space> mixed_space(bool cut_memory = false) {
  const MeshData mesh = grid_mesh({0, 10, 20, 30, 40}, {0, 10, 20, 30}, {0, 10, 20, 30}, 0.3, 7);
  std::vector<Material> materials{{"air", MaterialModel::Free},
                                  {"flesh", MaterialModel::Drag},
                                  {"bone", MaterialModel::Rigid},
                                  {"fat", MaterialModel::Viscous},
                                  {"skin", MaterialModel::Membrane}};
  materials[1].drag_distance_mm = 1.0;
  materials[3].viscosity_N_s_per_mm = 0.001;
  materials[4].break_force_N = 0.5;
  if (cut_memory) {
    materials[1].cut_to = "fat";
    materials[4].cut_to = "air";
  }
  std::vector<std::int32_t> labels(mesh.tets.size());
  std::mt19937 random(11);
  for (auto& label : labels) label = static_cast<std::int32_t>(random() % 5);
  return Space::create(TetMesh(mesh.vertices_mm, mesh.tets, labels), materials);
}

// A random walk over and around the mesh with jumps, NaN and far samples.
std::vector<Vec3> device_path(std::size_t count, std::uint32_t seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> step(-0.8, 0.8);
  std::uniform_real_distribution<double> anywhere(-5.0, 45.0);
  std::vector<Vec3> path(count);
  Vec3 p{20, 15, 15};
  for (std::size_t i = 0; i < count; ++i) {
    const std::uint32_t roll = random() % 1000;
    if (roll == 0) {
      path[i] = {std::numeric_limits<double>::quiet_NaN(), 0, 0};
      continue;
    }
    if (roll == 1) {
      path[i] = {0, 0, 1e18};
      continue;
    }
    if (roll < 20) {
      p = {anywhere(random), anywhere(random), anywhere(random)};
    } else {
      p += Vec3{step(random), step(random), step(random)};
      p = {std::clamp(p.x, -5.0, 45.0), std::clamp(p.y, -5.0, 35.0), std::clamp(p.z, -5.0, 35.0)};
    }
    path[i] = p;
  }
  return path;
}

TEST(NoAllocation, AMillionProxySteps) {
  const auto space = mixed_space();
  const std::vector<Vec3> path = device_path(1'000'000, 5);
  std::vector<Proxy> proxies(4, Proxy(space));
  for (Proxy& proxy : proxies) proxy.reset({20, 15, 15});
  RuntimeSettings other = space->runtime_settings();
  other.stiffness_N_per_mm = 0.3;
  other.max_transitions_per_tick = 8;
  std::uint64_t rejected = 0;
  const std::uint64_t count = allocations_of([&] {
    for (std::size_t i = 0; i < path.size(); ++i) {
      Proxy& proxy = proxies[i % proxies.size()];
      const TickResult r =
          (i & 1U) != 0 ? proxy.step(path[i], kDt) : proxy.step(path[i], kDt, other);
      rejected += r.rejected ? 1 : 0;
    }
  });
  EXPECT_EQ(count, 0u);
  EXPECT_GT(rejected, 1000u);  // The rejection path ran too.
  for (const Proxy& proxy : proxies) EXPECT_EQ(proxy.check_invariants(), "");
}

// points_tick: whether the blade's points tick (independent points, or a
// rigid blade in a Space with a resisting material); then the starved budget
// caps some.
void run_blade(const std::shared_ptr<const Space>& space, const Pose& start, double reach_mm,
               BladeCoupling coupling = BladeCoupling::Independent, bool points_tick = true) {
  BladeSpec spec{"b", {-20, 0, 0}, {20, 0, 0}, 50};
  spec.coupling = coupling;
  Blade blade(space, spec);
  blade.reset(start);
  RuntimeSettings plain = space->runtime_settings();
  RuntimeSettings shaded = plain;
  shaded.force_shading = true;
  RuntimeSettings starved = shaded;
  starved.blade_transition_budget = 20;  // Points deferred and capped: the budget's paths.
  std::vector<Pose> poses(10'000);
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const double s = std::sin(static_cast<double>(k) * 0.002);
    const double a = 0.3 * std::sin(static_cast<double>(k) * 0.0011);
    poses[k] = {start.position_mm + Vec3{0, reach_mm * s, -0.5 * reach_mm * std::abs(s)},
                {std::cos(a), 0, std::sin(a), 0}};
  }
  poses[500].rotation = {0, 0, 0, 0};  // Rejected: zero quaternion.
  auto snapshot = std::make_unique<BladeSnapshot<64>>();
  int capped = 0;
  int refused = 0;
  const std::uint64_t count = allocations_of([&] {
    for (std::size_t k = 0; k < poses.size(); ++k) {
      const RuntimeSettings& settings = k < 3000 ? plain : k < 7000 ? shaded : starved;
      refused += blade.check_pose(poses[k]) != PoseCheck::Fine ? 1 : 0;
      capped += blade.step(poses[k], kDt, settings).capped_points;
      blade.snapshot(*snapshot);
    }
    blade.step(poses[0], kDt);  // The Space's own settings.
  });
  EXPECT_EQ(count, 0u);
  if (points_tick) {
    EXPECT_GT(capped, 0);
  } else {
    EXPECT_EQ(capped, 0);
  }
  EXPECT_EQ(blade.counters().rejected_ticks, 1u);
  EXPECT_EQ(refused, 1);  // check_pose (no allocation either) refused the same pose.
  if (coupling == BladeCoupling::Rigid) {
    // The rigid rounds ran: seated from the start, contacts fitted.
    std::printf("rigid: %llu rounds in %llu ticks, %u at most, %llu unresolved, %llu unseated\n",
                static_cast<unsigned long long>(blade.counters().rigid_rounds),
                static_cast<unsigned long long>(blade.counters().ticks),
                blade.counters().max_rigid_rounds_in_tick,
                static_cast<unsigned long long>(blade.counters().unresolved_ticks),
                static_cast<unsigned long long>(blade.counters().unseated_ticks));
    EXPECT_EQ(blade.counters().unseated_ticks, 0u);
    EXPECT_GT(blade.counters().max_rigid_rounds_in_tick, 1u);
  }
  for (const Proxy& proxy : blade.proxies()) EXPECT_EQ(proxy.check_invariants(), "");
}

TEST(NoAllocation, TenThousandBladeTicksOnTheMixedGrid) {
  run_blade(mixed_space(), {{20, 15, 32}, {}}, 14.0);
}

TEST(NoAllocation, TenThousandBladeTicksOnTheRigidSphere) {
  const auto space = Space::from_scene(
      load_scene(std::string(HAPTICUT_EXAMPLES_DIR) + "/sphere80.hapticut.msgpack"));
  run_blade(space, {{0, 0, 40}, {}}, 30.0);
}

// The rigid coupling's rounds (walks, fits, the least-distance solve) add no allocation.
TEST(NoAllocation, TenThousandRigidBladeTicksOnTheMixedGrid) {
  run_blade(mixed_space(), {{20, 15, 32}, {}}, 14.0, BladeCoupling::Rigid);
}

TEST(NoAllocation, TenThousandRigidBladeTicksOnTheRigidSphere) {
  const auto space = Space::from_scene(
      load_scene(std::string(HAPTICUT_EXAMPLES_DIR) + "/sphere80.hapticut.msgpack"));
  // Lower: onto the sphere. Bone and air only: the points do not tick.
  run_blade(space, {{0, 0, 32}, {}}, 30.0, BladeCoupling::Rigid, false);
}

// Cut tets read through the cut byte, chords cut every tick, the cuts reset;
// then the memory switched off for a stroke (what the bench weighs it against)
// and on again.
TEST(NoAllocation, BladeTicksWithCutToAndResetCuts) {
  for (BladeCoupling coupling : {BladeCoupling::Independent, BladeCoupling::Rigid}) {
    const auto space = mixed_space(true);
    BladeSpec spec{"b", {-20, 0, 0}, {20, 0, 0}, 50};
    spec.coupling = coupling;
    Blade blade(space, spec);
    const Pose start{{20, 15, 32}, {}};
    blade.reset(start);
    std::int64_t cut = 0;
    std::int64_t cut_without_memory = 0;
    const auto stroke = [&] {
      for (int k = 0; k < 3000; ++k) {
        const double s = std::sin(k * 0.002);
        blade.step({start.position_mm + Vec3{0, 14.0 * s, -7.0 * std::abs(s)}, {}}, kDt);
      }
    };
    const std::uint64_t count = allocations_of([&] {
      for (int round = 0; round < 2; ++round) {
        stroke();
        cut = std::max(cut, blade.cuts().cut_count());
        blade.reset_cuts();
      }
      blade.set_cut_memory(false);
      stroke();
      cut_without_memory = blade.cuts().cut_count();
      blade.set_cut_memory(true);
    });
    EXPECT_EQ(count, 0u);
    EXPECT_GT(cut, 0);  // The cutting ran.
    EXPECT_EQ(cut_without_memory, 0);
    EXPECT_EQ(blade.cuts().cut_count(), 0);
  }
}

TEST(NoAllocation, TheCounterSeesAnAllocation) {
  // The test could not fail if the replacement were not in use.
  const std::uint64_t count = allocations_of([] {
    auto* v = new std::vector<int>(100);
    delete v;
  });
  EXPECT_EQ(count, 2u);
}

}  // namespace
}  // namespace hapticut
