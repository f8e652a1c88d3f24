#include "hapticut/geometry.h"

#include <gtest/gtest.h>

#include <limits>
#include <utility>
#include <vector>

#include "hapticut/aabb_tree.h"
#include "hapticut/reference_meshes.h"
#include "hapticut/tet_mesh.h"

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
  // Leaving: no re-entry (repair 3, docs/method.md).
  EXPECT_LT(segment_entry_parameter(0.0, 1.0, eps), 0.0);
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

TEST(Geometry, PointsStrictlyIntoNeedsEveryPlanePassedByMoreThanEps) {
  constexpr double eps = 1e-9;
  EXPECT_TRUE(points_strictly_into(std::array<double, 3>{-1.0, -2e-9, -0.5}, eps));
  EXPECT_FALSE(points_strictly_into(std::array<double, 3>{-1.0, -1e-9, -0.5}, eps));  // On a plane.
  EXPECT_FALSE(points_strictly_into(std::array<double, 2>{-1.0, 0.0}, eps));  // In a face plane.
  EXPECT_FALSE(points_strictly_into(std::array<double, 2>{-1.0, 2.0}, eps));
}

TEST(Geometry, PointsStrictlyOutOfAClosedConeNeedsOnePlanePassedByMoreThanEps) {
  constexpr double eps = 1e-9;
  EXPECT_TRUE(points_strictly_out_of(std::array<double, 3>{-1.0, 2e-9, -0.5}, eps));
  EXPECT_FALSE(points_strictly_out_of(std::array<double, 3>{-1.0, 1e-9, -0.5}, eps));  // Closed.
  EXPECT_FALSE(points_strictly_out_of(std::array<double, 2>{0.0, 0.0}, eps));  // Along the edge.
  EXPECT_FALSE(points_strictly_out_of(std::array<double, 2>{-1.0, -1.0}, eps));
  // Neither strictly into nor strictly out of: in the closed cone's boundary,
  // where repair 2 keeps the walk on the feature (docs/method.md).
  const std::array<double, 3> in_a_face_plane{-1.0, 0.0, -0.5};
  EXPECT_FALSE(points_strictly_into(in_a_face_plane, eps));
  EXPECT_FALSE(points_strictly_out_of(in_a_face_plane, eps));
}

TEST(Geometry, WithinToleranceIsClosed) {
  constexpr double eps = 1e-3;
  EXPECT_TRUE(within_tolerance({0.0, 0.0, 0.0}, eps));
  EXPECT_TRUE(within_tolerance({0.0, 1e-3, 0.0}, eps));    // Exactly eps: no motion.
  EXPECT_TRUE(within_tolerance({6e-4, 0.0, 7e-4}, eps));   // |d| ~ 9.2e-4.
  EXPECT_FALSE(within_tolerance({8e-4, 0.0, 7e-4}, eps));  // |d| ~ 1.06e-3.
  EXPECT_FALSE(within_tolerance({-1.0, 0.0, 0.0}, eps));
}

TEST(Geometry, StrictlyBeyondAndOnOrBeyondAreComplementsAcrossThePlane) {
  constexpr double eps = 1e-9;
  EXPECT_TRUE(strictly_beyond(2e-9, eps));
  EXPECT_FALSE(strictly_beyond(1e-9, eps));  // Within eps: on the plane.
  EXPECT_FALSE(strictly_beyond(-1.0, eps));
  EXPECT_TRUE(on_or_beyond(-1e-9, eps));
  EXPECT_TRUE(on_or_beyond(5.0, eps));
  EXPECT_FALSE(on_or_beyond(-2e-9, eps));
  // The one-plane forms agree with the wedge and cone tests.
  EXPECT_EQ(strictly_beyond(2e-9, eps), points_strictly_out_of(std::array<double, 1>{2e-9}, eps));
  EXPECT_EQ(!on_or_beyond(-2e-9, eps), points_strictly_into(std::array<double, 1>{-2e-9}, eps));
}

TEST(Geometry, ProjectedStrictlyIntoMatchesTheProjectedTarget) {
  constexpr double eps = 1e-9;
  // Planes through q = 0: m with normal z, g with normal -x (the wedge x > 0, z < 0).
  const Plane m{{0, 0, 1}, 0.0};
  const Plane g{{-1, 0, 0}, 0.0};
  for (const Vec3& p : {Vec3{1, 0, 2}, Vec3{-1, 0, 2}, Vec3{1e-10, 3, -1}, Vec3{2e-9, 0, 5}}) {
    const double height = m.signed_distance(p);
    const Vec3 projected = p - m.normal * height;
    EXPECT_EQ(projected_strictly_into(dot(p, g.normal), height, dot(m.normal, g.normal), eps),
              dot(projected, g.normal) < -eps)
        << p.x << " " << p.y << " " << p.z;
  }
  EXPECT_TRUE(projected_strictly_into(-1.0, 2.0, 0.0, eps));
  EXPECT_FALSE(projected_strictly_into(-1e-9, 2.0, 0.0, eps));  // On plane g: closed.
  // Tilted planes: the height counts through n_m . n_g.
  EXPECT_FALSE(projected_strictly_into(-1.0, 2.0, -0.5, eps));  // -1 + 1 = 0.
  EXPECT_TRUE(projected_strictly_into(-1.0, 2.0, 0.25, eps));   // -1 - 0.5.
}

TEST(Geometry, BeyondAnEdgesEndIsExactAndInclusive) {
  const Vec3 o0{0, 0, 0};
  const Vec3 o1{2, 0, 0};
  const Vec3 a{1, 0, 0};
  EXPECT_TRUE(beyond_edge_start({0, 1, 0}, o0, a));  // Off the line: its projection counts.
  EXPECT_TRUE(beyond_edge_start({-1e-300, 0, 0}, o0, a));
  EXPECT_FALSE(beyond_edge_start({1e-300, 0, 0}, o0, a));
  EXPECT_FALSE(beyond_edge_end({1.5, 0, 0}, o1, a));
  EXPECT_TRUE(beyond_edge_end({2, 0, 0}, o1, a));
  EXPECT_TRUE(beyond_edge_end({3, 0, 0}, o1, a));
  EXPECT_FALSE(beyond_edge_start({1, 0, 0}, o0, a));
}

TEST(Geometry, SideOfRimIsClosedWithinEps) {
  constexpr double eps = 1e-9;
  EXPECT_EQ(side_of_rim(-1.0, eps), RimSide::Inside);
  EXPECT_EQ(side_of_rim(-1e-9, eps), RimSide::OnRim);
  EXPECT_EQ(side_of_rim(0.0, eps), RimSide::OnRim);
  EXPECT_EQ(side_of_rim(1e-9, eps), RimSide::OnRim);
  EXPECT_EQ(side_of_rim(1.1e-9, eps), RimSide::Outside);
}

TEST(Geometry, SlideReachesEdgeOnlyOnItsLineAndWithTheTargetNotBackInside) {
  constexpr double eps = 1e-9;
  EXPECT_TRUE(slide_reaches_edge(0.0, 1.0, eps));     // Ended on the line, target beyond it.
  EXPECT_TRUE(slide_reaches_edge(-5e-10, 0.0, eps));  // Target on the line too.
  EXPECT_FALSE(slide_reaches_edge(-2e-9, 1.0, eps));  // Stopped short of the line.
  EXPECT_FALSE(slide_reaches_edge(2e-9, 1.0, eps));   // Past it: an exit, not an arrival.
  // Target strictly back inside: the complement of EDGE's (a-3) test, which
  // picked this face, so FACE and EDGE cannot hand the proxy back and forth.
  EXPECT_FALSE(slide_reaches_edge(0.0, -2e-9, eps));
}

TEST(Geometry, DistanceToTetIsEuclidean) {
  const MeshData data = cube_mesh(10.0);
  const TetMesh mesh(data.vertices_mm, data.tets, std::vector<std::int32_t>(data.tets.size(), 0));
  double nearest = 1e300;
  for (std::int32_t t = 0; t < mesh.tet_count(); ++t) {
    nearest = std::min(nearest, distance_to_tet(mesh, t, {13, 14, 10}));
  }
  EXPECT_NEAR(nearest, 5.0, 1e-12);  // From the corner (10, 10, 10).
  const std::int32_t inside = mesh.locate({2, 3, 4});
  ASSERT_NE(inside, kNoTet);
  EXPECT_EQ(distance_to_tet(mesh, inside, {2, 3, 4}), 0.0);
}

TEST(Geometry, MeshInteriorExcludesTheBoundaryAndIncludesInnerFacesAndVertices) {
  const MeshData data = grid_mesh({0, 10, 20}, {0, 10, 20}, {0, 10, 20});
  const TetMesh mesh(data.vertices_mm, data.tets, std::vector<std::int32_t>(data.tets.size(), 0));
  constexpr double margin = 1e-6;
  EXPECT_TRUE(lies_in_mesh_interior(mesh, {10, 10, 10}, margin));  // The inner vertex.
  EXPECT_TRUE(lies_in_mesh_interior(mesh, {10, 4, 3}, margin));    // An inner face plane.
  EXPECT_TRUE(lies_in_mesh_interior(mesh, {4, 3, 2}, margin));
  EXPECT_TRUE(lies_in_mesh_interior(mesh, {2e-6, 3, 2}, margin));   // Deeper than the margin.
  EXPECT_FALSE(lies_in_mesh_interior(mesh, {5e-7, 3, 2}, margin));  // Within it of the boundary.
  EXPECT_FALSE(lies_in_mesh_interior(mesh, {0, 3, 2}, margin));
  EXPECT_FALSE(lies_in_mesh_interior(mesh, {0, 0, 0}, margin));  // A boundary corner.
  EXPECT_FALSE(lies_in_mesh_interior(mesh, {-1, 3, 2}, margin));
  EXPECT_FALSE(lies_in_mesh_interior(mesh, {-1e-7, -1e-7, -1e-7}, margin));
  EXPECT_FALSE(lies_in_mesh_interior(mesh, {1e18, 0, 0}, margin));
}

TEST(Geometry, MeshBoxAndReachBox) {
  const MeshData data = cube_mesh(10.0);
  const TetMesh mesh(data.vertices_mm, data.tets, std::vector<std::int32_t>(data.tets.size(), 0));
  const Aabb box = reach_box(mesh_box(mesh, 0.0));
  const double diagonal = std::sqrt(300.0);
  EXPECT_NEAR(box.lo.x, -diagonal, 1e-12);
  EXPECT_NEAR(box.hi.z, 10.0 + diagonal, 1e-12);
  EXPECT_EQ(mesh_box(mesh, 0.5).lo, Vec3(-0.5, -0.5, -0.5));
  EXPECT_EQ(mesh_box(mesh, 0.5).hi, Vec3(10.5, 10.5, 10.5));
  EXPECT_TRUE(box_holds(mesh_box(mesh, 0.0), {10, 0, 5}));  // Closed.
  EXPECT_FALSE(box_holds(mesh_box(mesh, 0.0), {10.001, 0, 5}));
}

TEST(Geometry, EntryBoxIsTheMeshBoxGrownByAThousandthOfItsDiagonalAndAThousandTolerances) {
  const MeshData data = cube_mesh(10.0);
  const TetMesh mesh(data.vertices_mm, data.tets, std::vector<std::int32_t>(data.tets.size(), 0));
  const double pad = 1e-3 * std::sqrt(300.0) + 1e3 * 1e-6;
  const Aabb box = entry_box(mesh_box(mesh, 0.0), 1e-6);
  EXPECT_NEAR(box.lo.y, -pad, 1e-15);
  EXPECT_NEAR(box.hi.x, 10.0 + pad, 1e-15);
}

TEST(Geometry, SegmentBeyondABoxFaceNeedsBothEndsStrictlyBeyondTheSameFace) {
  const Aabb box{{0, 0, 0}, {1, 1, 1}};
  auto beyond = [&](const Vec3& a, const Vec3& b) {
    return box_beyond_face(segment_box(a, b), box);
  };
  EXPECT_TRUE(beyond({-1, 0.5, 0.5}, {-2, 5, -3}));
  EXPECT_TRUE(beyond({0.5, 0.5, 1.5}, {9, -9, 1.01}));
  // Beside the box at a corner, but beyond different faces: not decided here.
  EXPECT_FALSE(beyond({-1, 0.5, 0.5}, {0.5, -1, 0.5}));
  // The box is closed: an end on a face is not beyond it.
  EXPECT_FALSE(beyond({-1, 0.5, 0.5}, {0, 0.5, 0.5}));
  EXPECT_FALSE(beyond({-1, 0.5, 0.5}, {2, 0.5, 0.5}));
}

TEST(Geometry, ABoxHoldsASegmentExactlyWhenItHoldsBothEnds) {
  const Aabb box{{0, 0, 0}, {1, 1, 1}};
  for (const auto& [a, b] :
       std::vector<std::pair<Vec3, Vec3>>{{{0, 0, 0}, {1, 1, 1}},
                                          {{0.5, 0.2, 0.9}, {1.01, 0.5, 0.5}},
                                          {{-0.1, 0.5, 0.5}, {0.5, 0.5, 0.5}},
                                          {{0.3, 0.3, 0.3}, {0.6, 0.2, 1.0}}}) {
    EXPECT_EQ(box_holds_box(box, segment_box(a, b)), box_holds(box, a) && box_holds(box, b));
  }
}

TEST(Geometry, ClipSegmentToBoxKeepsInsideEndsAndPutsClippedOnesOnItsSurface) {
  const Aabb box{{-10, -10, -10}, {10, 10, 10}};
  const ClippedSegment inside = clip_segment_to_box({1, 2, 3}, {-4, 5, 6}, box);
  EXPECT_TRUE(inside.hits);
  EXPECT_EQ(inside.start, Vec3(1, 2, 3));
  EXPECT_EQ(inside.end, Vec3(-4, 5, 6));
  // A jump of 1e18 mm and back: the clipped start is exactly on the top face.
  const ClippedSegment back = clip_segment_to_box({0, 0, 1e18}, {0, 0, 0}, box);
  EXPECT_TRUE(back.hits);
  EXPECT_EQ(back.start, Vec3(0, 0, 10));
  EXPECT_EQ(back.end, Vec3(0, 0, 0));
  // Both ends far, on opposite sides: both clipped, and b - a overflowing
  // (1.8e308 - -1.8e308) does not matter.
  const double huge = std::numeric_limits<double>::max();
  const ClippedSegment through = clip_segment_to_box({huge, 1, 2}, {-huge, 1, 2}, box);
  EXPECT_TRUE(through.hits);
  EXPECT_EQ(through.start, Vec3(10, 1, 2));
  EXPECT_EQ(through.end, Vec3(-10, 1, 2));
  // A diagonal from far away keeps the clipped point on the box's surface.
  const ClippedSegment diagonal = clip_segment_to_box({1e18, -1e18, 1e18}, {0, 0, 0}, box);
  EXPECT_TRUE(diagonal.hits);
  EXPECT_NEAR(norm(diagonal.start - Vec3(10, -10, 10)), 0.0, 1e-12);  // Its digits kept.
  EXPECT_EQ(diagonal.end, Vec3(0, 0, 0));
  EXPECT_FALSE(clip_segment_to_box({20, 20, 0}, {20, -20, 0}, box).hits);  // Passes by.
  EXPECT_FALSE(clip_segment_to_box({0, 0, 1e3}, {0, 0, 11}, box).hits);    // Stops short.
  // Short by 1 mm in 1e18: not resolvable, but whatever is kept lies on the surface.
  const ClippedSegment grazing = clip_segment_to_box({0, 0, 1e18}, {0, 0, 11}, box);
  if (grazing.hits) {
    EXPECT_EQ(grazing.start, Vec3(0, 0, 10));
    EXPECT_EQ(grazing.end, Vec3(0, 0, 10));
  }
}

}  // namespace
}  // namespace hapticut
