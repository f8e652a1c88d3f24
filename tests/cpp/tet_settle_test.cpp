// The inline settles in a tet, on a face and beside the mesh (Proxy::settle_in_tet,
// settle_on_bone and settle_in_air) are shortcuts of the walk: every tick they take must leave
// the proxy exactly as the walk would (place, force and counters, bit for
// bit), and they must decline every other tick.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <cstring>
#include <random>

#include "hapticut/force_shading.h"
#include "hapticut/proxy.h"
#include "test_support.h"

namespace hapticut {

struct TetSettleTestAccess {
  // Proxy::step's tick with the walk alone (the inputs here are always valid).
  static TickResult step_walking(Proxy& proxy, const Vec3& p, double dt_s,
                                 const RuntimeSettings& settings) {
    TickResult result;
    ++proxy.counters_.ticks;
    proxy.walk(p, dt_s, settings, settings.max_transitions_per_tick, nullptr, false, result);
    return result;
  }
  static bool settles_in_tet(Proxy proxy, const Vec3& p, const RuntimeSettings& settings) {
    TickResult result;
    return proxy.settle_in_tet(p, settings, settings.max_transitions_per_tick, result);
  }
  static bool settles_on_face(Proxy proxy, const Vec3& p, const RuntimeSettings& settings) {
    TickResult result;
    return proxy.settle_on_bone(p, settings, settings.max_transitions_per_tick, nullptr, result);
  }
  static bool settles_beside(Proxy proxy, const Vec3& p, const RuntimeSettings& settings,
                             const ForceShading* shading = nullptr) {
    TickResult result;
    return proxy.settle_in_air(p, settings, settings.max_transitions_per_tick, shading, result);
  }
};

namespace {

using testing::make_space;

bool same_bits(const Vec3& a, const Vec3& b) { return std::memcmp(&a, &b, sizeof(Vec3)) == 0; }

void expect_same(const Proxy& a, const Proxy& b, const TickResult& ra, const TickResult& rb,
                 int step) {
  SCOPED_TRACE("step " + std::to_string(step));
  ASSERT_EQ(a.place().state, b.place().state);
  ASSERT_EQ(a.place().tet, b.place().tet);
  ASSERT_EQ(a.place().local, b.place().local);
  ASSERT_TRUE(same_bits(a.place().q, b.place().q));
  ASSERT_TRUE(same_bits(a.force_N(), b.force_N()));
  ASSERT_TRUE(same_bits(a.last_p(), b.last_p()));
  ASSERT_EQ(ra.transitions, rb.transitions);
  ASSERT_EQ(ra.capped, rb.capped);
  ASSERT_EQ(ra.rejected, rb.rejected);
  const ProxyCounters& ca = a.counters();
  const ProxyCounters& cb = b.counters();
  ASSERT_EQ(ca.ticks, cb.ticks);
  ASSERT_EQ(ca.total_transitions, cb.total_transitions);
  ASSERT_EQ(ca.max_transitions_in_tick, cb.max_transitions_in_tick);
  ASSERT_EQ(ca.capped_ticks, cb.capped_ticks);
  ASSERT_EQ(ca.transitions, cb.transitions);
}

// Every material the settle handles or declines: free, drag, membrane,
// viscous (declined: it needs the tick's speed) and rigid (never a TET owner).
std::vector<Material> all_models() {
  Material membrane{"skin", MaterialModel::Membrane};
  membrane.break_force_N = 0.3;
  Material viscous{"fat", MaterialModel::Viscous};
  viscous.viscosity_N_s_per_mm = 0.002;
  return {testing::free_material(), testing::drag_material(1.0), membrane, viscous,
          testing::rigid_material()};
}

// A vector of three draws from `d`, x first.
template <class Distribution>
Vec3 draw(Distribution& d, std::mt19937_64& random) {
  const double x = d(random);
  const double y = d(random);
  return {x, y, d(random)};
}

// Counts a shortcut taken, or declined by a proxy in the state it is for.
void tally(bool taken, bool in_its_state, int& taken_count, int& declined_count) {
  taken_count += taken ? 1 : 0;
  declined_count += !taken && in_its_state ? 1 : 0;
}

// 200 strokes of 200 steps, each from start() and on by p = next(k, p): at
// every step the proxy's own tick (settles first) against the walk alone,
// after look(settling proxy, p). Returns the steps run (fewer on a failure).
template <class Start, class Next, class Look>
int compare_strokes_with_walk(const std::shared_ptr<const Space>& space,
                              const RuntimeSettings& settings, Start start, Next next, Look look) {
  int steps = 0;
  for (int stroke = 0; stroke < 200; ++stroke) {
    Vec3 p = start();
    Proxy walking(space);
    walking.reset(p);
    Proxy settling = walking;
    for (int k = 0; k < 200; ++k, ++steps) {
      p = next(k, p);
      look(settling, p);
      const TickResult rw = TetSettleTestAccess::step_walking(walking, p, 1e-3, settings);
      const TickResult rs = settling.step(p, 1e-3, settings);
      expect_same(settling, walking, rs, rw, steps);
      if (::testing::Test::HasFatalFailure()) return steps;
    }
  }
  return steps;
}

TEST(TetSettle, GivesWhatTheWalkGivesOnRandomStrokes) {
  const MeshData mesh =
      grid_mesh({0, 4, 9, 15, 20}, {0, 5, 10, 16, 20}, {0, 6, 10, 14, 20}, 0.3, 7);
  std::mt19937_64 random(11);
  std::vector<std::int32_t> materials(mesh.tets.size());
  std::uniform_int_distribution<int> model(0, 9);
  for (auto& m : materials) {
    // Of ten tets: 4 free, 2 drag, 1 membrane, 1 viscous, 2 rigid.
    static constexpr std::array<std::int32_t, 10> kModel{0, 0, 0, 0, 1, 1, 2, 3, 4, 4};
    m = kModel[model(random)];
  }
  const auto space = make_space(mesh, materials, all_models());
  RuntimeSettings settings = space->runtime_settings();
  std::uniform_real_distribution<double> inside(-2.0, 22.0);
  std::normal_distribution<double> small(0.0, 0.05);
  std::normal_distribution<double> large(0.0, 3.0);
  int settled = 0;
  int slid = 0;
  int declined_in_tet = 0;
  int declined_on_face = 0;
  const int steps = compare_strokes_with_walk(
      space, settings, [&] { return draw(inside, random); },
      [&](int k, const Vec3& p) {
        const bool jump = k % 17 == 0;
        return p + (jump ? draw(large, random) : draw(small, random));
      },
      [&](const Proxy& settling, const Vec3& p) {
        const ProxyState state = settling.place().state;
        tally(TetSettleTestAccess::settles_in_tet(settling, p, settings), state == ProxyState::Tet,
              settled, declined_in_tet);
        tally(TetSettleTestAccess::settles_on_face(settling, p, settings),
              state == ProxyState::Face, slid, declined_on_face);
      });
  if (::testing::Test::HasFatalFailure()) return;
  // Both branches of both were exercised: many ticks settle or slide, and the
  // declined TET and FACE ticks (an exit, an edge reached, a free neighbour, a
  // viscous tet) went through the walk with the same result.
  EXPECT_GT(settled, steps / 10);
  EXPECT_GT(declined_in_tet, steps / 100);
  EXPECT_GT(slid, steps / 100);
  EXPECT_GT(declined_on_face, steps / 100);
  std::printf("settled %d, declined in a tet %d, slid %d, declined on a face %d of %d\n", settled,
              declined_in_tet, slid, declined_on_face, steps);
}

TEST(TetSettle, DeclinesAnythingButAFreshTetTick) {
  const MeshData mesh = cube_mesh(10.0);
  const auto space = make_space(mesh, 0);
  const RuntimeSettings settings = space->runtime_settings();
  Proxy proxy(space);
  proxy.reset({2.0, 4.0, 6.0});  // x < y < z: inside one Kuhn tet.
  ASSERT_EQ(proxy.place().state, ProxyState::Tet);
  EXPECT_TRUE(TetSettleTestAccess::settles_in_tet(proxy, {2.0, 4.0, 6.01}, settings));
  // Out of the cube: the walk leaves through a face.
  EXPECT_FALSE(TetSettleTestAccess::settles_in_tet(proxy, {2.0, 4.0, 15.0}, settings));
  proxy.reset({15.0, 5.0, 5.0});
  ASSERT_EQ(proxy.place().state, ProxyState::Outside);
  EXPECT_FALSE(TetSettleTestAccess::settles_in_tet(proxy, {15.0, 5.0, 5.01}, settings));
  // Beside the mesh: the OUTSIDE shortcut takes a move beyond one face of the
  // entry box, and declines one that could enter, any other state, or shading.
  EXPECT_TRUE(TetSettleTestAccess::settles_beside(proxy, {15.0, 5.0, 5.01}, settings));
  EXPECT_TRUE(TetSettleTestAccess::settles_beside(proxy, {25.0, -9.0, 30.0}, settings));
  EXPECT_FALSE(TetSettleTestAccess::settles_beside(proxy, {5.0, 5.0, 5.0}, settings));
  EXPECT_FALSE(TetSettleTestAccess::settles_beside(proxy, {10.0, 5.0, 5.0}, settings));
  RuntimeSettings shaded = settings;
  shaded.force_shading = true;
  const ForceShading shading(*space);
  EXPECT_FALSE(TetSettleTestAccess::settles_beside(proxy, {15.0, 5.0, 5.01}, shaded, &shading));
  proxy.reset({2.0, 4.0, 6.0});
  EXPECT_FALSE(TetSettleTestAccess::settles_beside(proxy, {2.0, 4.0, 6.01}, settings));
}

// OUTSIDE strokes round a body of rigid and soft tets, in and out of it: every
// move the shortcut takes leaves the proxy as the walk does, and the moves it
// declines (near the mesh, or entering it) go through the walk alike.
TEST(TetSettle, BesideTheMeshGivesWhatTheWalkGives) {
  const MeshData mesh = grid_mesh({0, 5, 10}, {0, 5, 10}, {0, 5, 10}, 0.3, 21);
  std::vector<std::int32_t> materials(mesh.tets.size());
  for (std::size_t t = 0; t < materials.size(); ++t) materials[t] = t % 3 == 0 ? 4 : 1;
  const auto space = make_space(mesh, materials, all_models());
  const RuntimeSettings settings = space->runtime_settings();
  std::mt19937_64 random(5);
  std::uniform_real_distribution<double> around(-12.0, 22.0);
  std::normal_distribution<double> small(0.0, 0.3);
  int beside = 0;
  int declined = 0;
  const int steps = compare_strokes_with_walk(
      space, settings, [&] { return draw(around, random); },
      [&](int k, const Vec3& p) {
        return p + (k % 23 == 0 ? draw(around, random) * 0.2 : draw(small, random));
      },
      [&](const Proxy& settling, const Vec3& p) {
        tally(TetSettleTestAccess::settles_beside(settling, p, settings),
              settling.place().state == ProxyState::Outside, beside, declined);
      });
  if (::testing::Test::HasFatalFailure()) return;
  EXPECT_GT(beside, steps / 10);
  EXPECT_GT(declined, steps / 2000);
  std::printf("beside the mesh %d, declined outside %d of %d\n", beside, declined, steps);
}

}  // namespace
}  // namespace hapticut
