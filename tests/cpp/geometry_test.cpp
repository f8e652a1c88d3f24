#include "hapticut/geometry.h"

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace hapticut
