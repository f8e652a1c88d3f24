// The rigid blade's contact set: one plane keeps its two extreme samples.
#include "hapticut/edge_contact_set.h"

#include <gtest/gtest.h>

#include <cmath>

namespace hapticut {
namespace {

TEST(EdgeContactSet, ManySamplesOnOnePlaneKeepTheirTwoExtremes) {
  EdgeContactSet set;
  const Plane floor{{0, 0, 1}, 0.0};
  for (int i = 0; i < 200; ++i) {
    // Coplanar faces of a mesh differ by rounding.
    const Plane face{{1e-12 * i, 0, 1}, 1e-12 * (i % 3)};
    EXPECT_TRUE(set.add(0.3 + 0.002 * (i % 100), face, 1e-9));
  }
  EXPECT_EQ(set.plane_count(), 1);
  const auto constraints = set.constraints();
  ASSERT_EQ(constraints.size(), 2U);
  EXPECT_DOUBLE_EQ(constraints[0].fraction, 0.3);
  EXPECT_DOUBLE_EQ(constraints[1].fraction, 0.3 + 0.002 * 99);
  EXPECT_EQ(constraints[0].plane.normal, floor.normal);
}

TEST(EdgeContactSet, ACreaseIsTwoPlanesAndFourConstraints) {
  EdgeContactSet set;
  const double s = std::sqrt(0.5);
  for (int i = 0; i <= 100; ++i) {
    set.add(i / 100.0, {{0, s, s}, 0.0}, 1e-9);
    set.add(i / 100.0, {{0, -s, s}, 0.0}, 1e-9);
  }
  EXPECT_EQ(set.plane_count(), 2);
  EXPECT_EQ(set.constraints().size(), 4U);
}

TEST(EdgeContactSet, ASinglePointContactIsOneConstraintAndChangesAreCounted) {
  EdgeContactSet set;
  set.add(0.5, {{0, 0, 1}, 0.0}, 1e-9);
  EXPECT_EQ(set.constraints().size(), 1U);
  const int before = set.changes();
  set.add(0.5, {{0, 0, 1}, 0.0}, 1e-9);  // Nothing new.
  EXPECT_EQ(set.changes(), before);
  set.add(0.7, {{0, 0, 1}, 0.0}, 1e-9);  // The range widens.
  EXPECT_GT(set.changes(), before);
  // Offsets farther apart than the tolerance are other planes.
  set.add(0.5, {{0, 0, 1}, 1e-6}, 1e-9);
  EXPECT_EQ(set.plane_count(), 2);
}

TEST(EdgeContactSet, AFullSetRefusesNewPlanesAndKeepsWideningOldOnes) {
  EdgeContactSet set;
  for (int j = 0; j < EdgeContactSet::kMaxPlanes; ++j) {
    EXPECT_TRUE(set.add(0.5, {{0, 0, 1}, double(j)}, 1e-9));
  }
  EXPECT_TRUE(set.full());
  EXPECT_FALSE(set.add(0.5, {{0, 0, 1}, 1000.0}, 1e-9));
  EXPECT_TRUE(set.add(0.9, {{0, 0, 1}, 3.0}, 1e-9));
  EXPECT_EQ(set.constraints().size(), std::size_t(EdgeContactSet::kMaxPlanes + 1));
  set.clear();
  EXPECT_EQ(set.constraints().size(), 0U);
}

}  // namespace
}  // namespace hapticut
