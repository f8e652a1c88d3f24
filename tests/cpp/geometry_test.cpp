#include "hapticut/geometry.h"

#include <gtest/gtest.h>

#include <limits>

#include "hapticut/aabb_tree.h"

namespace hapticut {
namespace {

TEST(Geometry, ProjectToPlaneLandsOnIt) {
  const Plane plane{{0, 0, 1}, 2.0};
  const Vec3 p = project_to_plane({3, 4, 7}, plane);
  EXPECT_EQ(p, Vec3(3, 4, 2));
}

TEST(Geometry, ProjectToLine) {
  const Vec3 p = project_to_line({3, 4, 7}, {1, 1, 1}, {1, 0, 0});
  EXPECT_EQ(p, Vec3(3, 1, 1));
}

TEST(Geometry, ExitParameterNeedsARealExit) {
  constexpr double eps = 1e-9;
  EXPECT_DOUBLE_EQ(segment_exit_parameter(-1.0, 1.0, eps), 0.5);
  EXPECT_LT(segment_exit_parameter(0.0, 0.0, eps), 0.0);     // Lying in the plane (0/0).
  EXPECT_LT(segment_exit_parameter(0.0, -1.0, eps), 0.0);    // Leaving the plane inward.
  EXPECT_LT(segment_exit_parameter(-1.0, 1e-12, eps), 0.0);  // A rounding error is no exit.
  EXPECT_EQ(segment_exit_parameter(1e-12, 1.0, eps), 0.0);   // Already a hair outside.
  EXPECT_LT(segment_exit_parameter(2.0, 1.0, eps), 0.0);     // Moving back in.
}

TEST(Geometry, EntryParameterMirrorsExit) {
  constexpr double eps = 1e-9;
  EXPECT_DOUBLE_EQ(segment_entry_parameter(1.0, -3.0, eps), 0.25);
  EXPECT_EQ(segment_entry_parameter(0.0, -1.0, eps), 0.0);
  EXPECT_LT(segment_entry_parameter(0.0, 1.0, eps), 0.0);    // Leaving: no re-entry (repair 3).
  EXPECT_LT(segment_entry_parameter(-1.0, -2.0, eps), 0.0);  // Already behind the plane.
}

TEST(Geometry, ClosestPointOnTriangleRegions) {
  const Vec3 a{0, 0, 0}, b{1, 0, 0}, c{0, 1, 0};
  EXPECT_NEAR(norm(closest_point_on_triangle({0.2, 0.3, 5}, a, b, c) - Vec3(0.2, 0.3, 0)), 0.0,
              1e-15);
  EXPECT_EQ(closest_point_on_triangle({-1, -1, 0}, a, b, c), a);
  EXPECT_EQ(closest_point_on_triangle({3, -1, 0}, a, b, c), b);
  EXPECT_EQ(closest_point_on_triangle({0.5, -2, 1}, a, b, c), Vec3(0.5, 0, 0));
  const Vec3 on_hypotenuse = closest_point_on_triangle({1, 1, 0}, a, b, c);
  EXPECT_NEAR(on_hypotenuse.x, 0.5, 1e-15);
  EXPECT_NEAR(on_hypotenuse.y, 0.5, 1e-15);
}

TEST(Geometry, IsFiniteRejectsInfinityAndNaNInAnyComponent) {
  const double inf = std::numeric_limits<double>::infinity();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double huge = std::numeric_limits<double>::max();
  const double tiny = std::numeric_limits<double>::denorm_min();
  EXPECT_TRUE(is_finite({0.0, -0.0, 1.0}));
  EXPECT_TRUE(is_finite({huge, -huge, tiny}));
  for (int axis = 0; axis < 3; ++axis) {
    for (double bad : {inf, -inf, nan}) {
      Vec3 v{1.0, 2.0, 3.0};
      (axis == 0 ? v.x : axis == 1 ? v.y : v.z) = bad;
      EXPECT_FALSE(is_finite(v)) << "axis " << axis << " value " << bad;
    }
  }
}

TEST(Geometry, SlabTestTreatsAnAxisWithoutMotionAsContainment) {
  const Aabb box{{0.0, 0.0, 0.0}, {1.0, 1.0, 1.0}};
  auto hits = [&box](const Vec3& a, const Vec3& b) {
    const Vec3 d = b - a;
    return box.hits_segment(a, {1.0 / d.x, 1.0 / d.y, 1.0 / d.z}, d, 0.0);
  };
  EXPECT_TRUE(hits({-1.0, 0.5, 0.5}, {2.0, 0.5, 0.5}));    // Straight through.
  EXPECT_FALSE(hits({-1.0, 1.5, 0.5}, {2.0, 1.5, 0.5}));   // Parallel, above.
  EXPECT_FALSE(hits({-2.0, 0.5, 0.5}, {-1.0, 0.5, 0.5}));  // Stops short.
  EXPECT_TRUE(hits({0.5, 0.5, 0.5}, {0.5, 0.5, 0.5}));     // A point inside.
  // A movement so small along y and z that 1 / d overflows: those axes count
  // as parallel (the old slab test turned 0 x inf into NaN there).
  const double sub = 1e-310;
  EXPECT_TRUE(hits({0.0, 0.0, 0.0}, {-0.5, sub, -sub}));
  EXPECT_FALSE(hits({0.0, 2.0, 0.0}, {-0.5, 2.0 + sub, 0.0}));
}

}  // namespace
}  // namespace hapticut
