// What the servo needs from the engine: settings per tick, an exact cap and a
// work budget that degrades gracefully, force shading in the blade, a snapshot
// per tick, shared ownership of the Space, and input checks (blade size, zero
// quaternion, absurd device samples, set_place). docs/decisions.md has a record
// for each, from "Transitions per tick and a capped tick" to "Absurd device samples".
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <type_traits>

#include "hapticut/blade.h"
#include "hapticut/force_shading.h"
#include "hapticut/proxy.h"
#include "hapticut/scene_io.h"
#include "test_support.h"

#ifndef HAPTICUT_EXAMPLES_DIR
#define HAPTICUT_EXAMPLES_DIR "examples"
#endif

namespace hapticut {
namespace {

using testing::bone_floor;
using testing::make_space;

constexpr double kDt = 0.001;

// A free bar of 10 mm cells along x: a long move crosses many faces.
std::shared_ptr<const Space> free_bar(EngineSettings settings = {}) {
  return make_space(grid_mesh({0, 10, 20, 30, 40, 50}, {0, 10}, {0, 10}),
                    std::vector<std::int32_t>(30, 0), testing::paper_materials(), settings);
}

TEST(SettingsPerTick, StiffnessChangesBetweenTicksWithoutANewSpace) {
  const auto space = bone_floor();
  Proxy proxy(space);
  proxy.reset({1, 1, 5});
  for (int i = 0; i <= 10; ++i) proxy.step({1, 1, 5 - 0.7 * i}, kDt);  // 2 mm into the bone.
  EXPECT_NEAR(proxy.force_N().z, 0.1 * 2.0, 1e-9);
  RuntimeSettings stiffer = space->runtime_settings();
  stiffer.stiffness_N_per_mm = 0.4;
  proxy.step({1, 1, -2}, kDt, stiffer);
  EXPECT_NEAR(proxy.force_N().z, 0.4 * 2.0, 1e-9);
  proxy.step({1, 1, -2}, kDt);  // The overload without settings: the scene's.
  EXPECT_NEAR(proxy.force_N().z, 0.1 * 2.0, 1e-9);
}

TEST(SettingsPerTick, SettingsOutOfRangeAreRejectedNotUsed) {
  const auto space = bone_floor();
  Proxy proxy(space);
  proxy.reset({1, 1, -2});
  RuntimeSettings bad = space->runtime_settings();
  bad.stiffness_N_per_mm = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(bad.valid());
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  const TickResult r = proxy.step({1, 1, -2}, kDt, bad);
  EXPECT_TRUE(r.rejected);
  EXPECT_EQ(proxy.force_N(), Vec3(0, 0, 0));
  EXPECT_EQ(proxy.counters().rejected_inputs, 1u);
  RuntimeSettings huge = space->runtime_settings();
  huge.max_transitions_per_tick = 1000000000;
  EXPECT_FALSE(huge.valid());
  static_assert(std::is_trivially_copyable_v<RuntimeSettings>);
}

TEST(ExactCap, AWalkThatConvergesExactlyAtTheCapIsNotCapped) {
  // Find how many transitions the walk needs, then allow exactly that many.
  int needed = 0;
  {
    Proxy probe(free_bar());
    probe.reset({1, 5, 5});
    const TickResult r = probe.step({49, 5, 5}, kDt);
    ASSERT_FALSE(r.capped);
    needed = r.transitions;
  }
  ASSERT_GT(needed, 3);
  for (const int cap : {needed, needed - 1}) {
    EngineSettings settings;
    settings.max_transitions_per_tick = cap;
    Proxy proxy(free_bar(settings));
    proxy.reset({1, 5, 5});
    const TickResult r = proxy.step({49, 5, 5}, kDt);
    EXPECT_EQ(r.capped, cap < needed) << "cap " << cap << ", needed " << needed;
    EXPECT_EQ(r.transitions, cap);
    EXPECT_EQ(proxy.counters().capped_ticks, cap < needed ? 1u : 0u);
    EXPECT_EQ(proxy.check_invariants(), "");
  }
}

TEST(ExactCap, ACappedTickHoldsTheLastForceThenCatchesUp) {
  // Pressed into bone, then a far jump sideways on the bone with a tiny cap:
  // the force does not jump; the proxy catches up over the next ticks.
  EngineSettings settings;
  settings.max_transitions_per_tick = 1;
  settings.capped_tick_force_N = 10.0;
  const auto space = bone_floor(settings);
  Proxy proxy(space);
  proxy.reset({-15, -15, 5});
  for (int i = 0; i <= 10; ++i) proxy.step({-15, -15, 5 - 0.7 * i}, kDt);
  const Vec3 before = proxy.force_N();
  ASSERT_NEAR(before.z, 0.2, 1e-9);
  const TickResult r = proxy.step({15, 15, -2}, kDt);
  ASSERT_TRUE(r.capped);
  EXPECT_EQ(proxy.force_N(), before);
  EXPECT_EQ(proxy.check_invariants(), "");
  for (int i = 0; i < 200 && proxy.step({15, 15, -2}, kDt).capped; ++i) {
  }
  EXPECT_NEAR(proxy.force_N().z, 0.2, 1e-9);
  EXPECT_NEAR(proxy.q().x, 15.0, 1e-9);
}

TEST(WorkBudget, APointThatNeedsMoreThanTheCapFinishesOnTheBladesBudget) {
  EngineSettings settings;
  settings.max_transitions_per_tick = 3;
  const auto space = free_bar(settings);
  Blade blade(space, {"b", {0, 0, 0}, {0, 1, 0}, 2});
  blade.reset({{1, 3, 4}, {}});
  RuntimeSettings settings_per_tick = space->runtime_settings();
  settings_per_tick.blade_transition_budget = 200;
  const BladeTick tick = blade.step({{49, 3, 4}, {}}, kDt, settings_per_tick);
  EXPECT_EQ(tick.capped_points, 0);
  EXPECT_GT(tick.max_transitions, 3);
  EXPECT_EQ(blade.proxies()[0].q(), Vec3(49, 3, 4));
  EXPECT_EQ(blade.proxies()[1].q(), Vec3(49, 4, 4));
}

TEST(WorkBudget, AnExhaustedBudgetDefersPointsWhichCatchUpNextTick) {
  const auto space = free_bar();
  Blade blade(space, {"b", {0, 1, 0}, {0, 8, 0}, 8});
  blade.reset({{1, 1, 5}, {}});
  RuntimeSettings settings = space->runtime_settings();
  settings.blade_transition_budget = 10;
  const BladeTick first = blade.step({{49, 1, 5}, {}}, kDt, settings);
  EXPECT_LE(first.transitions, 10);
  EXPECT_GT(first.capped_points, 0);
  EXPECT_GT(first.deferred_points, 0);
  EXPECT_EQ(blade.counters().unfinished_ticks, 1u);
  for (const Proxy& p : blade.proxies()) EXPECT_EQ(p.check_invariants(), "");
  // Free air: every point feels zero, finished or not; no force jump.
  EXPECT_EQ(first.force_N, Vec3(0, 0, 0));
  BladeTick tick = first;
  int ticks = 1;
  while (tick.capped_points > 0 && ticks < 100) {
    tick = blade.step({{49, 1, 5}, {}}, kDt, settings);
    EXPECT_LE(tick.transitions, 10);
    ++ticks;
  }
  EXPECT_EQ(tick.capped_points, 0);
  for (std::size_t i = 0; i < blade.proxies().size(); ++i) {
    EXPECT_EQ(blade.proxies()[i].q(), blade.world_points()[i]) << "point " << i;
  }
  EXPECT_GT(blade.counters().deferred_points, 0u);
}

std::shared_ptr<const Space> sphere80() {
  return Space::from_scene(
      load_scene(std::string(HAPTICUT_EXAMPLES_DIR) + "/sphere80.hapticut.msgpack"));
}

TEST(BladeShading, ShadingIsAppliedWhenTheSettingsAskForIt) {
  // Two equal blades pressed into the rigid sphere off its facets' centres:
  // the shaded one feels what ForceShading makes of the plain one's force.
  // Shading acts per point: on the paper's independent points.
  const auto space = sphere80();
  const BladeSpec spec{"b", {-6, 0, 0}, {6, 0, 0}, 7, BladeCoupling::Independent};
  Blade plain(space, spec);
  Blade shaded(space, spec);
  RuntimeSettings on = space->runtime_settings();
  on.force_shading = true;
  const Quaternion tilt{0.97, 0.1, 0.2, 0.05};
  plain.reset({{3, 2, 45}, tilt});
  shaded.reset({{3, 2, 45}, tilt});
  for (int i = 0; i <= 40; ++i) {
    plain.step({{3, 2, 45 - 0.5 * i}, tilt}, kDt);
    shaded.step({{3, 2, 45 - 0.5 * i}, tilt}, kDt, on);
  }
  const ForceShading shading(*space);
  Vec3 expected;
  double tilt_from_plain = 0.0;
  for (int i = 0; i < spec.points; ++i) {
    const Proxy& a = plain.proxies()[i];
    const Proxy& b = shaded.proxies()[i];
    ASSERT_EQ(a.place().q, b.place().q) << "point " << i;  // Shading never moves q.
    const Vec3 f = shading.shade(a.place(), a.force_N());
    EXPECT_NEAR(norm(b.force_N() - f), 0.0, 1e-12) << "point " << i;
    expected += f;
    tilt_from_plain += norm(f - a.force_N());
  }
  EXPECT_NEAR(norm(shaded.last_tick().force_N - expected), 0.0, 1e-12);
  EXPECT_GT(norm(plain.last_tick().force_N), 1.0);
  EXPECT_GT(tilt_from_plain, 1e-3);  // The case does exercise shading.
}

TEST(Snapshot, IsTriviallyCopyableAndFilledWithoutAllocation) {
  static_assert(std::is_trivially_copyable_v<ProxySnapshot>);
  static_assert(std::is_trivially_copyable_v<BladeSnapshotHeader>);
  static_assert(std::is_trivially_copyable_v<BladeSnapshot<64>>);
  const auto space = bone_floor();
  // Independent points: each proxy's own state and exact force in the snapshot.
  Blade blade(space, {"b", {0, 0, 0}, {10, 0, 0}, 5, BladeCoupling::Independent});
  blade.reset({{-5, 0, 5}, {}});
  for (int i = 0; i <= 20; ++i) blade.step({{-5, 0, 5 - 0.35 * i}, {}}, kDt);
  BladeSnapshot<8> snapshot;
  blade.snapshot(snapshot);
  EXPECT_EQ(snapshot.header.tick_index, 21u);
  EXPECT_EQ(snapshot.header.point_count, 5);
  EXPECT_EQ(snapshot.header.points_written, 5);
  EXPECT_EQ(snapshot.header.tick.force_N, blade.last_tick().force_N);
  for (int i = 0; i < 5; ++i) {
    // On the floor: FACE, or EDGE/VERTEX where a point rests on a grid line.
    const ProxyPlace& place = blade.proxies()[i].place();
    EXPECT_NE(place.state, ProxyState::Tet);
    EXPECT_NE(place.state, ProxyState::Outside);
    EXPECT_EQ(snapshot.points[i].place.state, place.state);
    EXPECT_EQ(snapshot.points[i].place.tet, place.tet);
    EXPECT_EQ(snapshot.points[i].place.q, place.q);
    EXPECT_EQ(snapshot.points[i].p, blade.world_points()[i]);
    EXPECT_NEAR(snapshot.points[i].force_N.z, 0.2, 1e-9);
  }
  BladeSnapshot<2> small;
  blade.snapshot(small);
  EXPECT_EQ(small.header.points_written, 2);
}

TEST(Ownership, SpaceIsNeitherCopyableNorMovable) {
  static_assert(!std::is_copy_constructible_v<Space>);
  static_assert(!std::is_move_constructible_v<Space>);
  static_assert(!std::is_copy_assignable_v<Space>);
  static_assert(!std::is_move_assignable_v<Space>);
  SUCCEED();
}

TEST(Ownership, LoadingANewSceneWhileProxiesOfTheOldExistCannotDangle) {
  std::shared_ptr<const Space> scene = bone_floor();
  // Independent points: the exact force of five points on the floor.
  Blade blade(scene, {"b", {0, 0, 0}, {10, 0, 0}, 5, BladeCoupling::Independent});
  Proxy proxy(*scene);  // From a reference: still shares ownership.
  const ForceShading shading(*scene);
  blade.reset({{-5, 0, 5}, {}});
  proxy.reset({1, 1, 5});
  const std::weak_ptr<const Space> old = scene;
  scene = free_bar();  // The servo loads another scene; the old one is still in use.
  EXPECT_FALSE(old.expired());
  for (int i = 0; i <= 20; ++i) blade.step({{-5, 0, 5 - 0.35 * i}, {}}, kDt);
  proxy.step({1, 1, -2}, kDt);
  EXPECT_NEAR(blade.last_tick().force_N.z, 5 * 0.2, 1e-9);
  EXPECT_NEAR(proxy.force_N().z, 0.2, 1e-9);
  EXPECT_EQ(shading.shade(proxy.place(), proxy.force_N()).z > 0.0, true);
  blade = Blade(scene, {"b", {0, 0, 0}, {1, 0, 0}, 2});
  proxy = Proxy(scene);
  EXPECT_FALSE(old.expired());  // `shading` still holds it.
}

TEST(Ownership, TheOldSpaceIsFreedWithItsLastUser) {
  std::weak_ptr<const Space> old;
  {
    auto scene = bone_floor();
    old = scene;
    Proxy proxy(scene);
    scene.reset();
    EXPECT_FALSE(old.expired());
  }
  EXPECT_TRUE(old.expired());
}

TEST(InputChecks, BladePointCountIsBounded) {
  const auto space = bone_floor();
  for (const int n : {0, -1, Blade::kMaxPoints + 1, std::numeric_limits<int>::max()}) {
    try {
      Blade blade(space, {"b", {0, 0, 0}, {10, 0, 0}, n});
      ADD_FAILURE() << "accepted " << n << " points";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(std::to_string(n)), std::string::npos) << e.what();
    }
  }
  EXPECT_NO_THROW(Blade(space, {"b", {0, 0, 0}, {10, 0, 0}, 1}));
}

TEST(InputChecks, BladeWhoseSpanOverflowsIsRefused) {
  // Both ends finite, end - start not: the points a + s_i b could not be placed.
  const auto space = bone_floor();
  try {
    Blade blade(space, {"b", {-1e308, 0, 0}, {1e308, 0, 0}, 5});
    ADD_FAILURE() << "accepted a span of 2e308 mm";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("end_mm - start_mm"), std::string::npos) << e.what();
  }
}

TEST(InputChecks, ZeroQuaternionIsRejectedNotTakenForTheIdentity) {
  const auto space = bone_floor();
  Blade blade(space, {"b", {0, 0, 0}, {10, 0, 0}, 5});
  EXPECT_THROW(blade.reset({{-5, 0, 5}, {0, 0, 0, 0}}), std::invalid_argument);
  blade.reset({{-5, 0, 5}, {}});
  for (int i = 0; i <= 20; ++i) blade.step({{-5, 0, 5 - 0.35 * i}, {}}, kDt);
  ASSERT_GT(blade.last_tick().force_N.z, 0.5);
  std::vector<ProxyPlace> before;
  for (const Proxy& p : blade.proxies()) before.push_back(p.place());
  const BladeTick tick = blade.step({{-5, 0, 2}, {0, 0, 0, 0}}, kDt);
  EXPECT_TRUE(tick.rejected);
  EXPECT_EQ(tick.force_N, Vec3(0, 0, 0));
  EXPECT_EQ(blade.counters().rejected_ticks, 1u);
  for (std::size_t i = 0; i < before.size(); ++i) {
    const Proxy& p = blade.proxies()[i];
    EXPECT_EQ(p.force_N(), Vec3(0, 0, 0));
    EXPECT_EQ(p.place().state, before[i].state);  // Place kept.
    EXPECT_EQ(p.place().q, before[i].q);
  }
  EXPECT_TRUE(blade.step({{-5, 0, 2}, {1e-300, 0, 0, 0}}, kDt).rejected);
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(blade.step({{-5, 0, 2}, {inf, 0, 0, 0}}, kDt).rejected);
}

TEST(InputChecks, SetPlaceRefusesIndicesOutOfRange) {
  const auto space = bone_floor();
  Proxy proxy(space);
  EXPECT_THROW(proxy.set_place({ProxyState::Tet, space->mesh().tet_count(), 0, {}}),
               std::invalid_argument);
  EXPECT_THROW(proxy.set_place({ProxyState::Face, 0, 4, {}}), std::invalid_argument);
  EXPECT_THROW(proxy.set_place({ProxyState::Edge, 0, 6, {}}), std::invalid_argument);
  EXPECT_THROW(proxy.set_place({ProxyState::Outside, 3, 0, {}}), std::invalid_argument);
  EXPECT_THROW(proxy.set_place({static_cast<ProxyState>(9), 0, 0, {}}), std::invalid_argument);
  EXPECT_NO_THROW(proxy.set_place({ProxyState::Edge, 0, 5, {}}));
}

TEST(AbsurdSample, AFarDeviceSampleIsRejectedAndTheProxyKeepsItsPlace) {
  // An absurd sample on sphere80: reset at (0,0,40), a glitch to (0,0,1e18), then the
  // origin. The glitch is a device fault: zero force, counted, state kept;
  // the next sample is felt (the rigid sphere pushes back, 4.7 N).
  const Scene scene = load_scene(std::string(HAPTICUT_EXAMPLES_DIR) + "/sphere80.hapticut.msgpack");
  const auto space = Space::from_scene(scene);
  Proxy proxy(space);
  proxy.reset({0, 0, 40});
  const ProxyPlace before = proxy.place();
  const TickResult glitch = proxy.step({0, 0, 1e18}, kDt);
  EXPECT_TRUE(glitch.rejected);
  EXPECT_EQ(proxy.force_N(), Vec3(0, 0, 0));
  EXPECT_EQ(proxy.place().q, before.q);
  EXPECT_EQ(proxy.counters().out_of_workspace_inputs, 1u);
  proxy.step({0, 0, 0}, kDt);
  EXPECT_GT(norm(proxy.force_N()), 1.0);
  EXPECT_EQ(proxy.check_invariants(), "");
  EXPECT_THROW(proxy.reset({0, 0, -1e18}), std::invalid_argument);
  // Just inside the workspace is still an ordinary sample.
  const Aabb& box = space->workspace();
  EXPECT_FALSE(proxy.step({0, 0, box.hi.z * 0.99}, kDt).rejected);
}

TEST(AbsurdSample, ABladePoseFarAwayIsRejected) {
  const auto space = bone_floor();
  Blade blade(space, {"b", {0, 0, 0}, {10, 0, 0}, 5});
  blade.reset({{-5, 0, 5}, {}});
  const BladeTick tick = blade.step({{-5, 0, 1e18}, {}}, kDt);
  EXPECT_TRUE(tick.rejected);
  EXPECT_EQ(blade.counters().out_of_workspace_ticks, 1u);
  EXPECT_FALSE(blade.step({{-5, 0, 5}, {}}, kDt).rejected);
}

TEST(Idempotence, SteppingTwiceWithTheSamePointChangesNothing) {
  // Free, drag, rigid and membrane tets at random on a jittered grid (viscous
  // is left out on purpose: a point held still lets its lag relax).
  const MeshData mesh = grid_mesh({0, 10, 20, 30}, {0, 10, 20}, {0, 10, 20}, 0.3, 5);
  std::vector<Material> materials = testing::paper_materials();
  Material skin{"skin", MaterialModel::Membrane};
  skin.break_force_N = 0.5;
  materials.push_back(skin);
  std::vector<std::int32_t> labels(mesh.tets.size());
  for (std::size_t t = 0; t < labels.size(); ++t) labels[t] = static_cast<std::int32_t>(t * 7 % 4);
  const auto space = make_space(mesh, labels, materials);
  Proxy proxy(space);
  proxy.reset({-2, 10, 10});
  std::uint32_t seed = 1;
  auto next = [&] {
    seed = seed * 1664525U + 1013904223U;
    return static_cast<double>(seed >> 8) / double(1U << 24);
  };
  Vec3 p{-2, 10, 10};
  for (int i = 0; i < 20000; ++i) {
    p += Vec3{next() - 0.5, next() - 0.5, next() - 0.5} * 1.5;
    p = {std::clamp(p.x, -3.0, 33.0), std::clamp(p.y, -3.0, 23.0), std::clamp(p.z, -3.0, 23.0)};
    if (proxy.step(p, kDt).capped) continue;
    const ProxyPlace first = proxy.place();
    const Vec3 force = proxy.force_N();
    const TickResult again = proxy.step(p, kDt);
    ASSERT_EQ(again.transitions, 0) << "tick " << i;
    ASSERT_EQ(proxy.place().state, first.state) << "tick " << i;
    ASSERT_EQ(proxy.place().tet, first.tet) << "tick " << i;
    ASSERT_EQ(proxy.place().local, first.local) << "tick " << i;
    ASSERT_EQ(proxy.place().q, first.q) << "tick " << i;
    ASSERT_EQ(proxy.force_N(), force) << "tick " << i;
  }
}

}  // namespace
}  // namespace hapticut
