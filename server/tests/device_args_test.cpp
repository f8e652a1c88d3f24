// Parsing `--device NAME=KIND:ARGS`, the device table, and the sim path.
#include "devices/device_args.h"

#include <gtest/gtest.h>

#include "devices/device_factory.h"
#include "devices/sim_path.h"

namespace hapticut::servo {
namespace {

TEST(DeviceSpec, ParsesNameKindValueAndOptions) {
  const DeviceSpec spec = parse_device_spec("scalpel=sim:stroke.json,fail_at_s=0.2,hand=0");
  EXPECT_EQ(spec.blade, "scalpel");
  EXPECT_EQ(spec.kind, "sim");
  EXPECT_EQ(spec.value, "stroke.json");
  EXPECT_EQ(spec.number("fail_at_s", -1), 0.2);
  EXPECT_EQ(spec.number("hand", 1), 0.0);
  EXPECT_EQ(spec.number("absent", 7), 7.0);
  const DeviceSpec bare = parse_device_spec("viewport");
  EXPECT_EQ(bare.blade, "");
  EXPECT_EQ(bare.kind, "viewport");
  EXPECT_TRUE(bare.options.empty());
}

TEST(DeviceSpec, RefusesMalformedText) {
  EXPECT_THROW(parse_device_spec("=sim"), DeviceError);
  EXPECT_THROW(parse_device_spec("scalpel=:x"), DeviceError);
  EXPECT_THROW(parse_device_spec("sim:a,b"), DeviceError);  // Only the first may be bare.
  EXPECT_THROW(parse_device_spec("sim:x=1,x=2"), DeviceError);
  const DeviceSpec spec = parse_device_spec("sim:speed=fast");
  EXPECT_THROW(spec.number("speed", 1), DeviceError);
  EXPECT_THROW(spec.check_options({"hand"}), DeviceError);
}

TEST(DeviceTable, NamesTheKnownKindsForAnUnknownOne) {
  DeviceContext context;
  try {
    make_device(parse_device_spec("warp:9"), context);
    FAIL() << "no error";
  } catch (const DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("known: sim, replay, viewport"), std::string::npos);
  }
}

TEST(SimPath, BuiltInStrokeInterpolates) {
  const SimPath path = SimPath::builtin("press", {-10, -10, -10}, {10, 10, 10}, 10.0);
  EXPECT_EQ(path.at(0).position_mm.z, 9.0);    // 45 % of the height above the centre.
  EXPECT_NEAR(path.duration_s(), 0.8, 1e-12);  // 8 mm at 10 mm/s.
  EXPECT_NEAR(path.at(0.4).position_mm.z, 5.0, 1e-12);
  EXPECT_NEAR(path.at(5.0).position_mm.z, 1.0, 1e-12);  // Holds at the end.
  EXPECT_THROW(SimPath::builtin("loop", {}, {1, 1, 1}, 1.0), DeviceError);
  EXPECT_THROW(SimPath::from_file("/nonexistent/path.json"), DeviceError);
}

}  // namespace
}  // namespace hapticut::servo
