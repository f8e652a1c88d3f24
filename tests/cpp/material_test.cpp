#include "hapticut/material.h"

#include <gtest/gtest.h>

namespace hapticut {
namespace {

MoveContext context(double speed = 0.0) { return {0.1, speed, 1e-9}; }

TEST(Material, FreeGoesToTheTarget) {
  const MoveResult r = move({"air", MaterialModel::Free}, {1, 2, 3}, {0, 0, 0}, context());
  EXPECT_TRUE(r.moved);
  EXPECT_EQ(r.q, Vec3(1, 2, 3));
}

TEST(Material, DragTrailsByAtMostD) {
  Material flesh{"flesh", MaterialModel::Drag};
  flesh.drag_distance_mm = 1.0;
  EXPECT_FALSE(move(flesh, {0.9, 0, 0}, {0, 0, 0}, context()).moved);
  const MoveResult r = move(flesh, {5, 0, 0}, {0, 0, 0}, context());
  ASSERT_TRUE(r.moved);
  EXPECT_NEAR(r.q.x, 4.0, 1e-15);
  // Repair 5 (docs/method.md): exactly D behind does not creep.
  EXPECT_FALSE(move(flesh, {5, 0, 0}, r.q, context()).moved);
}

TEST(Material, RigidNeverMoves) {
  EXPECT_FALSE(move({"bone", MaterialModel::Rigid}, {9, 9, 9}, {0, 0, 0}, context()).moved);
}

TEST(Material, ViscousLagGrowsWithSpeed) {
  Material fluid{"fluid", MaterialModel::Viscous};
  fluid.viscosity_N_s_per_mm = 0.001;  // 0.1 N at 100 mm/s.
  fluid.max_lag_mm = 5.0;
  EXPECT_NEAR(lag_distance_mm(fluid, context(100.0)), 1.0, 1e-12);
  EXPECT_NEAR(lag_distance_mm(fluid, context(200.0)), 2.0, 1e-12);
  EXPECT_NEAR(lag_distance_mm(fluid, context(1e6)), 5.0, 1e-12);
  // At rest it offers no resistance.
  EXPECT_EQ(move(fluid, {3, 0, 0}, {0, 0, 0}, context(0.0)).q, Vec3(3, 0, 0));
  const MoveResult r = move(fluid, {3, 0, 0}, {0, 0, 0}, context(100.0));
  EXPECT_NEAR(r.q.x, 2.0, 1e-12);
}

TEST(Material, MembraneBreaksAboveItsForce) {
  Material skin{"skin", MaterialModel::Membrane};
  skin.break_force_N = 0.5;  // 5 mm of push at k = 0.1 N/mm.
  EXPECT_FALSE(move(skin, {4.9, 0, 0}, {0, 0, 0}, context()).moved);
  const MoveResult r = move(skin, {5.1, 0, 0}, {0, 0, 0}, context());
  EXPECT_TRUE(r.moved);
  EXPECT_EQ(r.q, Vec3(5.1, 0, 0));
}

}  // namespace
}  // namespace hapticut
