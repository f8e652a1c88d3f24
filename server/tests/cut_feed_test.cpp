// CutFeed: the cut order handed from the loop's thread to the control
// thread. While a blade cuts (appends) and its cuts are reset (a new
// generation), a reader beside it gets, each time, a prefix of one
// generation's order: never entries of two generations, never an entry past
// the count. Under ThreadSanitizer (tests/scripts/tsan.sh) a missing
// ordering is also a report.
#include "cut_feed.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdint>
#include <map>
#include <memory>
#include <thread>
#include <utility>
#include <vector>

#include "hapticut/blade.h"
#include "hapticut/cut_state.h"
#include "hapticut/reference_meshes.h"
#include "hapticut/space.h"

namespace hapticut::servo {
namespace {

std::vector<double> lines(double from, double to, double step) {
  std::vector<double> out;
  for (double x = from; x <= to + 1e-9; x += step) out.push_back(x);
  return out;
}

// Flesh (drag 1 mm) filling a 40 x 20 x 20 mm block on a 2 mm grid.
std::shared_ptr<const Space> flesh_block() {
  const MeshData mesh = grid_mesh(lines(-20, 20, 2), lines(-10, 10, 2), lines(-10, 10, 2));
  Material flesh{"flesh", MaterialModel::Drag};
  flesh.drag_distance_mm = 1.0;
  return Space::create(
      TetMesh(mesh.vertices_mm, mesh.tets, std::vector<std::int32_t>(mesh.tets.size(), 0)),
      {flesh});
}

TEST(CutFeedThreads, ReadsAreAPrefixOfOneGenerationsOrder) {
  const auto space = flesh_block();
  BladeSpec spec{"knife", {0, 0, 0}, {0, 0, 0}, 1};
  spec.coupling = BladeCoupling::Independent;
  Blade blade(space, spec);
  CutFeed feed(static_cast<std::size_t>(space->mesh().tet_count()));
  feed.follow(blade.cuts());

  std::atomic<bool> done{false};
  std::atomic<int> read_count{0};
  std::vector<std::pair<std::uint32_t, std::vector<std::int32_t>>> reads;
  std::thread reader([&] {
    std::vector<std::int32_t> out;
    while (!done.load(std::memory_order_acquire)) {
      const CutFeed::Part part = feed.read(0, 1U << 20, out);
      if (out.size() != part.total) {
        reads.emplace_back(part.generation, std::vector<std::int32_t>{-1});
        return;
      }
      if (reads.size() < 4000) reads.emplace_back(part.generation, out);
      read_count.fetch_add(1, std::memory_order_relaxed);
      std::this_thread::yield();
    }
  });

  // Zigzags through the block; the cuts reset every 400 ticks.
  std::map<std::uint32_t, std::vector<std::int32_t>> orders;  // Each generation's last order.
  blade.reset({{-18, -7.3, 0.3}, {}});
  for (int tick = 1; tick <= 4000; ++tick) {
    const double t = tick * 0.001;
    const Vec3 p{-18 + 36 * std::abs(std::fmod(t, 2.0) - 1.0), -7.3 + 7 * std::sin(t * 9),
                 0.3 + 5 * std::cos(t * 5)};
    blade.step({p, {}}, 0.001);
    if (tick % 400 == 0) {
      // The reader has read during this generation (a loaded machine may
      // not have run it yet): then the checks below see more than one.
      const int seen = read_count.load(std::memory_order_relaxed);
      for (int wait = 0; wait < 100000 && read_count.load(std::memory_order_relaxed) < seen + 2;
           ++wait) {
        std::this_thread::yield();
      }
      const auto order = blade.cuts().cut_order();
      orders[blade.cuts().generation()] = {order.begin(), order.end()};
      blade.reset_cuts();
    }
    feed.follow(blade.cuts());
  }
  done.store(true, std::memory_order_release);
  reader.join();

  ASSERT_FALSE(reads.empty());
  std::size_t nonempty = 0;
  for (const auto& [generation, read] : reads) {
    ASSERT_TRUE(read.empty() || read[0] != -1) << "a read whose length is not its count";
    const auto found = orders.find(generation);
    if (found == orders.end()) continue;  // The last generation, never reset.
    const std::vector<std::int32_t>& order = found->second;
    ASSERT_LE(read.size(), order.size());
    ASSERT_TRUE(std::equal(read.begin(), read.end(), order.begin())) << generation;
    nonempty += read.empty() ? 0 : 1;
  }
  EXPECT_GT(nonempty, 0U);
  EXPECT_GT(orders.size(), 5U);
  for (const auto& [generation, order] : orders) EXPECT_GT(order.size(), 10U) << generation;
}

}  // namespace
}  // namespace hapticut::servo
