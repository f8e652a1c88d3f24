#include "devices/bridge_datagram.h"

#include <cmath>
#include <cstring>

namespace hapticut::servo {
namespace {

// Little-endian field writers and readers, one byte at a time.
class Writer {
 public:
  explicit Writer(std::uint8_t* bytes) : bytes_(bytes) {}
  void u16(std::uint16_t v) { put(v, 2); }
  void u32(std::uint32_t v) { put(v, 4); }
  void u64(std::uint64_t v) { put(v, 8); }
  void f64(double v) {
    std::uint64_t bits = 0;
    std::memcpy(&bits, &v, 8);
    put(bits, 8);
  }
  void vec3(const Vec3& v) {
    f64(v.x);
    f64(v.y);
    f64(v.z);
  }

 private:
  void put(std::uint64_t v, int n) {
    for (int i = 0; i < n; ++i) bytes_[offset_++] = static_cast<std::uint8_t>(v >> (8 * i));
  }
  std::uint8_t* bytes_;
  std::size_t offset_ = 0;
};

class Reader {
 public:
  explicit Reader(const std::uint8_t* bytes) : bytes_(bytes) {}
  std::uint16_t u16() { return static_cast<std::uint16_t>(get(2)); }
  std::uint32_t u32() { return static_cast<std::uint32_t>(get(4)); }
  std::uint64_t u64() { return get(8); }
  double f64() {
    const std::uint64_t bits = get(8);
    double v = 0.0;
    std::memcpy(&v, &bits, 8);
    finite_ = finite_ && std::isfinite(v);
    return v;
  }
  Vec3 vec3() {
    const double x = f64();
    const double y = f64();
    const double z = f64();
    return {x, y, z};
  }
  bool finite() const { return finite_; }

 private:
  std::uint64_t get(int n) {
    std::uint64_t v = 0;
    for (int i = 0; i < n; ++i) v |= static_cast<std::uint64_t>(bytes_[offset_++]) << (8 * i);
    return v;
  }
  const std::uint8_t* bytes_;
  std::size_t offset_ = 0;
  bool finite_ = true;
};

BridgeDecode check_header(Reader& reader, std::uint16_t kind) {
  if (reader.u32() != kBridgeMagic) return BridgeDecode::BadMagic;
  if (reader.u16() != kBridgeVersion) return BridgeDecode::BadVersion;
  if (reader.u16() != kind) return BridgeDecode::BadKind;
  return BridgeDecode::Ok;
}

}  // namespace

const char* bridge_decode_name(BridgeDecode result) {
  switch (result) {
    case BridgeDecode::Ok:
      return "ok";
    case BridgeDecode::WrongLength:
      return "wrong length";
    case BridgeDecode::BadMagic:
      return "bad magic";
    case BridgeDecode::BadVersion:
      return "bad version";
    case BridgeDecode::BadKind:
      return "bad kind";
    case BridgeDecode::NotFinite:
      return "not finite";
    case BridgeDecode::BadRotation:
      return "bad rotation";
  }
  return "?";
}

std::array<std::uint8_t, kBridgePoseBytes> encode_bridge_pose(const BridgePose& pose) {
  std::array<std::uint8_t, kBridgePoseBytes> bytes{};
  Writer w(bytes.data());
  w.u32(kBridgeMagic);
  w.u16(kBridgeVersion);
  w.u16(kBridgePoseKind);
  w.u64(pose.sequence);
  w.f64(pose.time_s);
  w.vec3(pose.pose.position_mm);
  w.f64(pose.pose.rotation.w);
  w.f64(pose.pose.rotation.x);
  w.f64(pose.pose.rotation.y);
  w.f64(pose.pose.rotation.z);
  w.u32(pose.buttons);
  w.u32(pose.flags);
  w.u64(pose.applied_force_sequence);
  return bytes;
}

std::array<std::uint8_t, kBridgeForceBytes> encode_bridge_force(const BridgeForce& force) {
  std::array<std::uint8_t, kBridgeForceBytes> bytes{};
  Writer w(bytes.data());
  w.u32(kBridgeMagic);
  w.u16(kBridgeVersion);
  w.u16(kBridgeForceKind);
  w.u64(force.sequence);
  w.f64(force.time_s);
  w.vec3(force.force_N);
  w.vec3(force.torque_N_mm);
  w.u64(force.pose_sequence);
  w.u32(force.flags);
  w.u32(0);
  return bytes;
}

BridgeDecode decode_bridge_pose(const std::uint8_t* bytes, std::size_t length, BridgePose& pose) {
  if (length != kBridgePoseBytes) return BridgeDecode::WrongLength;
  Reader r(bytes);
  if (const BridgeDecode header = check_header(r, kBridgePoseKind); header != BridgeDecode::Ok) {
    return header;
  }
  BridgePose out;
  out.sequence = r.u64();
  out.time_s = r.f64();
  out.pose.position_mm = r.vec3();
  out.pose.rotation.w = r.f64();
  out.pose.rotation.x = r.f64();
  out.pose.rotation.y = r.f64();
  out.pose.rotation.z = r.f64();
  out.buttons = r.u32();
  out.flags = r.u32();
  out.applied_force_sequence = r.u64();
  if (!r.finite()) return BridgeDecode::NotFinite;
  const Quaternion& q = out.pose.rotation;
  const double length_squared = q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z;
  if (!(length_squared >= 0.25 && length_squared <= 4.0)) return BridgeDecode::BadRotation;
  out.pose.rotation = q.normalized();
  pose = out;
  return BridgeDecode::Ok;
}

BridgeDecode decode_bridge_force(const std::uint8_t* bytes, std::size_t length,
                                 BridgeForce& force) {
  if (length != kBridgeForceBytes) return BridgeDecode::WrongLength;
  Reader r(bytes);
  if (const BridgeDecode header = check_header(r, kBridgeForceKind); header != BridgeDecode::Ok) {
    return header;
  }
  BridgeForce out;
  out.sequence = r.u64();
  out.time_s = r.f64();
  out.force_N = r.vec3();
  out.torque_N_mm = r.vec3();
  out.pose_sequence = r.u64();
  out.flags = r.u32();
  if (!r.finite()) return BridgeDecode::NotFinite;
  force = out;
  return BridgeDecode::Ok;
}

}  // namespace hapticut::servo
