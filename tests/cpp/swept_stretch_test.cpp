// The swept narrow phase of the rigid edge (swept_stretch.h) on its own: a
// stretch's patch against the rigid surface's edges, by the tree's query and
// among given candidates, and the pieces a turn is cut into.
#include "hapticut/swept_stretch.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "hapticut/reference_meshes.h"
#include "test_support.h"

namespace hapticut {
namespace {

using testing::axis;

template <class InBone>
std::shared_ptr<const Space> space_of(const MeshData& mesh, InBone in_bone) {
  return testing::labelled_space(mesh, in_bone);
}

TEST(SweptStretch, AnEdgeAcrossTheSweptPatchIsHitWhereItCrosses) {
  const MeshData mesh =
      grid_mesh(axis(-8, 8, 4, {-0.1, 0.1}), axis(-8, 8, 4), axis(-8, 8, 4, {-0.2, 0.0}));
  const auto space =
      space_of(mesh, [](const Vec3& c) { return std::abs(c.x) < 0.1 && c.z < 0.0 && c.z > -0.2; });
  const RigidSurfaceEdges edges(*space);
  EXPECT_GT(edges.size(), 0U);
  // A stretch along x over the rod, from z = 1 to z = -1.
  const SweptHit hit =
      sweep_stretch(edges, {-1, 0, 1}, {1, 0, 1}, {-1, 0, -1}, {1, 0, -1}, 0.0, 1.0, 1e-9);
  ASSERT_TRUE(hit.hit);
  EXPECT_NEAR(hit.motion, 0.5, 1e-9);  // The rod's top at z = 0.
  EXPECT_NEAR(hit.contact.normal.z, 1.0, 1e-9);
  EXPECT_NEAR(hit.contact.offset, 0.0, 1e-9);
  // Beside the rod, or not reaching it: no hit.
  EXPECT_FALSE(
      sweep_stretch(edges, {2, 0, 1}, {4, 0, 1}, {2, 0, -1}, {4, 0, -1}, 0.0, 1.0, 1e-9).hit);
  EXPECT_FALSE(
      sweep_stretch(edges, {-1, 0, 1}, {1, 0, 1}, {-1, 0, 0.5}, {1, 0, 0.5}, 0.0, 1.0, 1e-9).hit);
  // Sliding along the rod's top, a tolerance above it: no hit.
  EXPECT_FALSE(sweep_stretch(edges, {-1, -2, 1e-6}, {1, -2, 1e-6}, {-1, 2, 1e-6}, {1, 2, 1e-6}, 0.0,
                             1.0, 1e-9)
                   .hit);
  EXPECT_EQ(swept_pieces(0.0, 100.0, 0.01), 1);
  EXPECT_EQ(swept_pieces(M_PI, 100.0, 0.01), kMaxSweptPieces);
  const int pieces = swept_pieces(0.2, 100.0, 0.01);
  EXPECT_LE(100.0 * (0.2 / pieces) * (0.2 / pieces) / 8.0, 0.01);
}

TEST(SweptStretch, AmongTheGivenEdgesItFindsWhatTheTreeFinds) {
  // A jagged bone; stretches swept in random motions through and past it: the
  // test over every rigid surface edge given as candidates (the blade's broad
  // phase hands it a superset) answers as the tree's own query does, and the
  // motion found never takes the stretch's sample past the contact plane.
  const MeshData mesh = grid_mesh(axis(-8, 8, 2), axis(-8, 8, 2), axis(-8, 8, 2));
  const auto space =
      space_of(mesh, [](const Vec3& c) { return c.z < 1.5 * std::sin(c.x) + std::cos(1.3 * c.y); });
  const RigidSurfaceEdges edges(*space);
  std::vector<std::int32_t> all(edges.size());
  for (std::size_t k = 0; k < all.size(); ++k) all[k] = static_cast<std::int32_t>(k);
  std::uint64_t state = 12345;
  const auto uniform = [&state](double lo, double hi) {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return lo + (hi - lo) * double(state >> 11) / double(1ULL << 53);
  };
  int hits = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const Vec3 a0{uniform(-5, 5), uniform(-5, 5), uniform(1, 5)};
    const Vec3 b0 = a0 + Vec3{uniform(-2, 2), uniform(-2, 2), uniform(-1, 1)};
    const Vec3 move{uniform(-3, 3), uniform(-3, 3), uniform(-6, 0)};
    const Vec3 a1 = a0 + move;
    const Vec3 b1 = b0 + move + Vec3{uniform(-1, 1), uniform(-1, 1), uniform(-1, 1)};
    const SweptHit tree = sweep_stretch(edges, a0, b0, a1, b1, 0.0, 1.0, 1e-9);
    const SweptHit among = sweep_stretch_among(edges, all, a0, b0, a1, b1, 0.0, 1.0, 1e-9);
    ASSERT_EQ(tree.hit, among.hit) << "trial " << trial;
    if (!tree.hit) continue;
    ++hits;
    EXPECT_EQ(tree.motion, among.motion) << "trial " << trial;
    EXPECT_EQ(tree.along, among.along) << "trial " << trial;
    // The sample there, moved to the motion found, has not passed the
    // contact plane: the advance stops at or before the meeting.
    const Vec3 start = a0 + (b0 - a0) * tree.along;
    const Vec3 end = a1 + (b1 - a1) * tree.along;
    if (tree.motion > 0.0) {
      EXPECT_GE(tree.contact.signed_distance(start + (end - start) * tree.motion), -1e-9)
          << "trial " << trial;
    }
  }
  std::printf("%d of 400 random sweeps met the bone\n", hits);
  EXPECT_GT(hits, 40);
}

}  // namespace
}  // namespace hapticut
