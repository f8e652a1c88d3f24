// The UDP bridge's two datagrams (docs/devices.md, "The bridge format"):
// a bridge (a small program beside a vendor SDK) sends the tool's pose and
// buttons; the servo answers with the force and torque to render. Fixed
// layouts, little-endian, no padding surprises: encoded and decoded byte
// by byte, so both ends agree on every machine.
//
// Pose (bridge -> servo), 96 bytes:
//   0  u32  magic 0x50424348 ("HCBP")     4  u16 version (1)   6  u16 kind (1)
//   8  u64  sequence (increments per datagram, from 1)
//  16  f64  time_s, the bridge's clock when the pose was sampled
//  24  f64  position_mm x, y, z          48  f64 rotation w, x, y, z (unit quaternion)
//  80  u32  buttons                      84  u32 flags (bit 0: the device faulted)
//  88  u64  sequence of the last force datagram the bridge applied (0: none yet)
// Force (servo -> bridge), 88 bytes:
//   0  u32  magic                        4  u16 version (1)   6  u16 kind (2)
//   8  u64  sequence                    16  f64 time_s, the servo's clock
//  24  f64  force_N x, y, z             48  f64 torque_N_mm x, y, z
//  72  u64  sequence of the newest pose the servo has used
//  80  u32  flags (bit 0: engaged)      84  u32 zero
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "hapticut/pose.h"
#include "hapticut/vec3.h"

namespace hapticut::servo {

inline constexpr std::uint32_t kBridgeMagic = 0x50424348U;  // "HCBP" little-endian.
inline constexpr std::uint16_t kBridgeVersion = 1;
inline constexpr std::uint16_t kBridgePoseKind = 1;
inline constexpr std::uint16_t kBridgeForceKind = 2;
inline constexpr std::size_t kBridgePoseBytes = 96;
inline constexpr std::size_t kBridgeForceBytes = 88;
inline constexpr std::uint32_t kBridgePoseFaultFlag = 1U << 0;
inline constexpr std::uint32_t kBridgeForceEngagedFlag = 1U << 0;

struct BridgePose {
  std::uint64_t sequence = 0;
  double time_s = 0.0;
  Pose pose;
  std::uint32_t buttons = 0;
  std::uint32_t flags = 0;
  std::uint64_t applied_force_sequence = 0;
};

struct BridgeForce {
  std::uint64_t sequence = 0;
  double time_s = 0.0;
  Vec3 force_N;
  Vec3 torque_N_mm;
  std::uint64_t pose_sequence = 0;
  std::uint32_t flags = 0;
};

// Why a datagram was refused (counted per reason by the bridge device).
enum class BridgeDecode : std::uint8_t {
  Ok,
  WrongLength,
  BadMagic,
  BadVersion,
  BadKind,
  NotFinite,    // A NaN or inf in a number.
  BadRotation,  // The quaternion is far from unit length (|q| outside [0.5, 2]).
};
inline constexpr int kBridgeDecodeCount = 7;
const char* bridge_decode_name(BridgeDecode result);

std::array<std::uint8_t, kBridgePoseBytes> encode_bridge_pose(const BridgePose& pose);
std::array<std::uint8_t, kBridgeForceBytes> encode_bridge_force(const BridgeForce& force);
// A decoded pose has a unit rotation (normalized).
BridgeDecode decode_bridge_pose(const std::uint8_t* bytes, std::size_t length, BridgePose& pose);
BridgeDecode decode_bridge_force(const std::uint8_t* bytes, std::size_t length, BridgeForce& force);

}  // namespace hapticut::servo
