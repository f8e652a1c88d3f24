// The rigid blade's solver (rigid_edge.h) on its own, without a Blade: seated
// only where no sample and no stretch is in bone, solved onto a bone floor
// with its contacts reduced to one plane, verified all the way, and held by
// friction until the pull leaves the cone.
#include "hapticut/rigid_edge.h"

#include <gtest/gtest.h>

#include <vector>

#include "test_support.h"

namespace hapticut {
namespace {

constexpr double kLength = 20.0;

// Bone below z = 0 in a free box, with the given bone material.
std::shared_ptr<const Space> floor_of(const Material& rigid) {
  const MeshData mesh =
      grid_mesh(testing::axis(-20, 20, 5), testing::axis(-20, 20, 5), testing::axis(-20, 20, 5));
  return testing::labelled_space(mesh, [](const Vec3& c) { return c.z < 0.0; },
                                 {testing::free_material(), testing::drag_material(1.0), rigid});
}

void set_targets(RigidEdge& edge, const std::vector<double>& f, const Vec3& start,
                 const Vec3& direction) {
  for (std::size_t i = 0; i < f.size(); ++i) {
    edge.targets()[i] = start + direction * (f[i] * kLength);
  }
}

TEST(RigidEdge, SeatsOnlyWhereNoSampleAndNoStretchIsInBone) {
  const auto space = floor_of(testing::rigid_material());
  // Two samples: the stretch between them is all that can meet the bone.
  RigidEdge edge(space, testing::evenly_spaced(2), kLength);
  // (Off the grid's planes: a sample on a face between two bone tets is not
  // in either by more than the tolerance.)
  EXPECT_FALSE(edge.seat({{-10.3, 0.3, -3}, {1, 0, 0}}));
  // A tilted edge with its far end below the floor is refused.
  EXPECT_FALSE(edge.seat({{-10.3, 0.3, 2}, Vec3{1, 0, -0.5} / norm(Vec3{1, 0, -0.5})}));
  ASSERT_TRUE(edge.seat({{-10.3, 0.3, 2}, {1, 0, 0}}));
  EXPECT_NEAR(edge.points()[1].x, 9.7, 1e-12);
  for (const std::int32_t t : edge.tets()) {
    ASSERT_NE(t, kNoTet);
    EXPECT_FALSE(space->tet_is_rigid(t));
  }
}

TEST(RigidEdge, SolvedOntoABoneFloorItRestsOnItWithOnePlanesTwoContacts) {
  const auto space = floor_of(testing::rigid_material());
  const std::vector<double> f = testing::evenly_spaced(21);
  for (const bool lock : {false, true}) {
    RigidEdge edge(space, f, kLength);
    ASSERT_TRUE(edge.seat({{-10, 0, 2}, {1, 0, 0}}));
    // Targets 3 mm into the bone and tilted: the edge comes down and lies flat.
    set_targets(edge, f, {-9, 1, -3}, Vec3{1, 0, -0.1} / norm(Vec3{1, 0, -0.1}));
    edge.begin_tick();
    int rounds = 0;
    const bool resolved = edge.solve(lock, {1, 0, 0}, rounds);
    EXPECT_TRUE(resolved) << lock;
    EXPECT_LE(rounds, RigidEdge::kMaxRounds);
    for (const Vec3& x : edge.points()) {
      EXPECT_GE(x.z, -1e-9) << lock;
      EXPECT_LE(x.z, 1e-3) << lock;
    }
    // Along the floor the edge follows the targets (no friction): its middle
    // under theirs.
    EXPECT_NEAR(edge.points()[0].x, -9.0 + 10.0 / norm(Vec3{1, 0, -0.1}) - 10.0, 1e-3) << lock;
    EXPECT_NEAR(edge.points()[0].y, 1.0, 1e-3) << lock;
    // However many samples touch, one plane keeps its two extremes.
    EXPECT_EQ(edge.contacts().size(), 2U) << lock;
  }
}

TEST(RigidEdge, TheMotionIsVerifiedNotOnlyItsEnd) {
  // A thin wall of bone across the path, thinner than the samples' spacing:
  // targets beyond it leave the edge against it, not through it.
  const MeshData mesh = grid_mesh(testing::axis(-20, 20, 5, {-0.2, 0.2}), testing::axis(-20, 20, 5),
                                  testing::axis(-20, 20, 5));
  const auto space =
      testing::labelled_space(mesh, [](const Vec3& c) { return std::abs(c.x) < 0.2 && c.z < 5.0; });
  const std::vector<double> f = testing::evenly_spaced(5);
  RigidEdge edge(space, f, kLength);
  // Along y, on the wall's left; the targets on its right.
  ASSERT_TRUE(edge.seat({{-3, -10, 1}, {0, 1, 0}}));
  set_targets(edge, f, {3, -10, 1}, {0, 1, 0});
  edge.begin_tick();
  int rounds = 0;
  edge.solve(false, {0, 1, 0}, rounds);
  for (const Vec3& x : edge.points()) EXPECT_LE(x.x, -0.2 + 1e-6);
}

TEST(RigidEdge, FrictionHoldsItUntilThePullLeavesTheCone) {
  const auto space = floor_of(testing::rigid_material(0.5, 0.4));
  const std::vector<double> f = testing::evenly_spaced(11);
  RigidEdge edge(space, f, kLength);
  ASSERT_TRUE(edge.seat({{-10, 0, 0.5}, {1, 0, 0}}));
  const auto step = [&](double pull_x) {
    // Pressed 1 mm into the floor, pulled along x.
    set_targets(edge, f, {-10 + pull_x, 0, -1}, {1, 0, 0});
    edge.begin_tick();
    int rounds = 0;
    edge.solve(false, {1, 0, 0}, rounds);
    edge.apply_friction(false);
    return edge.points()[0].x;
  };
  // Landed from half a millimetre above (friction holds a support, not an
  // approach), then a pull of 0.4 mm per 1 mm push: inside the cone.
  step(0.0);
  const double landed = step(0.0);
  for (const Vec3& x : edge.points()) EXPECT_LE(x.z, 1e-4);
  EXPECT_NEAR(step(0.4), landed, 1e-9);
  // 0.8 mm per 1 mm: it slides, as far as leaves the pull at the dynamic 0.4.
  const double slid = step(0.8);
  EXPECT_GT(slid, landed + 0.3);
  EXPECT_LT(slid, landed + 0.8);
}

}  // namespace
}  // namespace hapticut
