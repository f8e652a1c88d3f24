// The binary layouts the servo writes: stream frames (UDP, one datagram per
// frame) and recording records (one per tick). Each fixed part is declared
// once here as a field list; the same list makes the C++ struct and the
// description `hapticut-servo --print-layout` prints, which the Python side
// (core/hapticut/servo_layout.py) is tested against. Little-endian, every
// field naturally aligned, every struct a multiple of 8 bytes.
//
// A frame:  FrameHeader, then per blade: BladeBlock, points block; a CutBlock.
// A record: RecordHeader, then per blade: BladeBlock, points block; a CutBlock.
// A recording ends with one RecordingTrailer (recording/recording_file.h).
// Points block of a blade with N points: q (N x 3 f64), p (N x 3 f64),
// state (N x u8), zero padding to a multiple of 8 bytes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace hapticut::servo {

inline constexpr std::uint16_t kFrameVersion = 4;
inline constexpr std::uint16_t kRecordVersion = 5;
inline constexpr char kFrameMagic[4] = {'H', 'C', 'F', 'R'};
inline constexpr char kRecordingEndMarker[8] = {'H', 'C', 'R', 'E', 'C', 'E', 'N', 'D'};
// The largest UDP payload over IPv4; a scene whose frame is larger is refused.
inline constexpr std::size_t kMaxFrameBytes = 65507;

// F(type, name) for a scalar, A(type, name, count) for an array.
#define HAPTICUT_FRAME_HEADER_FIELDS(F, A)                               \
  A(char, magic, 4)         /* "HCFR" */                                 \
  F(std::uint16_t, version) /* kFrameVersion */                          \
  F(std::uint16_t, blade_count)                                          \
  F(std::uint32_t, frame_bytes) /* This datagram's size. */              \
  F(std::uint32_t, session)     /* Increments with every start. */       \
  F(std::uint64_t, sequence)    /* Frame number, from 1; newest wins. */ \
  F(std::uint64_t, tick)        /* Servo tick of this frame. */          \
  F(double, servo_time_s)       /* Tick time, CLOCK_MONOTONIC. */        \
  F(double, dt_s)               /* Measured time since the last tick. */ \
  F(double, compute_p50_us)                                              \
  F(double, compute_p99_us)                                              \
  F(double, compute_max_us)                                              \
  F(double, wake_p50_us)                                                 \
  F(double, wake_p99_us)                                                 \
  F(double, wake_max_us)                                                 \
  F(std::uint64_t, late_ticks)                                           \
  F(std::uint64_t, dropped_records)                                      \
  F(std::uint32_t, servo_flags) /* ServoFlag bits. */                    \
  F(std::uint32_t, reserved)

#define HAPTICUT_RECORD_HEADER_FIELDS(F, A)                                      \
  F(std::uint64_t, tick)                                                         \
  F(double, time_s)          /* Tick time (virtual when as fast as possible). */ \
  F(double, dt_s)            /* Measured time since the last tick. */            \
  F(double, compute_us)      /* This tick's compute, wake to device write. */    \
  F(double, wake_latency_us) /* Wake-up minus the tick's deadline. */            \
  F(std::uint64_t, late_ticks)                                                   \
  F(std::uint64_t, dropped_records) /* Records lost before this one. */          \
  F(std::uint32_t, servo_flags)                                                  \
  F(std::uint32_t, blade_count)

#define HAPTICUT_BLADE_BLOCK_FIELDS(F, A)                                                    \
  A(double, pose, 7)           /* Device pose: x, y, z mm, qw, qx, qy, qz. */                \
  A(double, ideal_pose, 7)     /* Blade::ideal_pose, as pose (independent: the device's). */ \
  A(double, engine_force_N, 3) /* The blade's force before safety. */                        \
  A(double, engine_torque_N_mm, 3)                                                           \
  A(double, force_N, 3) /* Written to the device (after safety). */                          \
  A(double, torque_N_mm, 3)                                                                  \
  F(double, ramp)      /* Safety ramp factor, 0..1. */                                       \
  F(double, step_dt_s) /* dt the engine stepped with (0: no step). */                        \
  F(std::uint32_t, point_count)                                                              \
  F(std::uint32_t, buttons)                                                                  \
  F(std::uint32_t, safety_flags)    /* SafetyFlag bits, the state this tick. */              \
  F(std::uint32_t, events)          /* SafetyFlag bits that started this tick. */            \
  A(std::uint16_t, state_counts, 5) /* Proxies in TET, FACE, EDGE, VERTEX, OUTSIDE. */       \
  F(std::uint16_t, capped_points)                                                            \
  F(std::uint8_t, device_status) /* DeviceStatus: 0 fresh, 1 stale, 2 lost. */               \
  F(std::uint8_t, step_kind)     /* StepKind: 0 none, 1 step, 2 reset + step. */             \
  F(std::uint16_t, max_transitions)                                                          \
  F(double, stiffness_N_per_mm)    /* k stepped with (limited to the device). */             \
  F(std::uint64_t, rejected_ticks) /* Engine counters of the run. */                         \
  F(std::uint64_t, out_of_workspace_ticks)                                                   \
  F(std::uint64_t, unfinished_ticks)                                                         \
  F(std::uint32_t, transitions) /* This tick, all points. */                                 \
  F(std::uint16_t, deferred_points)                                                          \
  F(std::uint8_t, engine_rejected) /* 1: the engine refused the sample. */                   \
  F(std::uint8_t, force_shading)   /* 1: this tick's settings shade. */

// The cut tets (CutState::cut_order: in the order they were cut) a frame or a
// record carries: the next entries of that order after those the last frame
// (or record) carried, at most kCutBlockTets, so that a reader that gets every
// one rebuilds the set by appending, and one that missed some sees `first`
// beyond what it has (docs/protocol.md, "Cut tets").
inline constexpr std::uint16_t kCutBlockTets = 64;
#define HAPTICUT_CUT_BLOCK_FIELDS(F, A)                                                   \
  F(std::uint32_t, generation)  /* Increments with every reset_cuts or load_cuts. */      \
  F(std::uint32_t, total)       /* Tets cut after this tick: the order's length. */       \
  F(std::uint32_t, before_tick) /* Tets cut when the tick began (after a reset in it). */ \
  F(std::uint32_t, first)       /* The order's index of tets[0]. */                       \
  F(std::uint16_t, carried)     /* Entries of tets in use. */                             \
  F(std::uint16_t, capacity)    /* kCutBlockTets. */                                      \
  F(std::uint32_t, reserved)                                                              \
  A(std::int32_t, tets, kCutBlockTets)

// Written once, after the last record, when a recording is closed cleanly:
// a file without it was cut short. The marker is last, so that the file's
// final 8 bytes tell a complete recording.
#define HAPTICUT_RECORDING_TRAILER_FIELDS(F, A)                                             \
  F(std::uint64_t, record_count)    /* Records in the file. */                              \
  F(std::uint64_t, dropped_records) /* Records lost (ring full) while the file was open. */ \
  A(char, end_marker, 8)            /* "HCRECEND" */

#define HAPTICUT_DECLARE_FIELD(type, name) type name{};
#define HAPTICUT_DECLARE_ARRAY(type, name, count) type name[count]{};

struct FrameHeader {
  HAPTICUT_FRAME_HEADER_FIELDS(HAPTICUT_DECLARE_FIELD, HAPTICUT_DECLARE_ARRAY)
};
struct RecordHeader {
  HAPTICUT_RECORD_HEADER_FIELDS(HAPTICUT_DECLARE_FIELD, HAPTICUT_DECLARE_ARRAY)
};
struct BladeBlock {
  HAPTICUT_BLADE_BLOCK_FIELDS(HAPTICUT_DECLARE_FIELD, HAPTICUT_DECLARE_ARRAY)
};

struct CutBlock {
  HAPTICUT_CUT_BLOCK_FIELDS(HAPTICUT_DECLARE_FIELD, HAPTICUT_DECLARE_ARRAY)
};

struct RecordingTrailer {
  HAPTICUT_RECORDING_TRAILER_FIELDS(HAPTICUT_DECLARE_FIELD, HAPTICUT_DECLARE_ARRAY)
};

static_assert(sizeof(FrameHeader) % 8 == 0);
static_assert(sizeof(RecordHeader) % 8 == 0);
static_assert(sizeof(BladeBlock) % 8 == 0);
static_assert(sizeof(CutBlock) % 8 == 0);
static_assert(sizeof(RecordingTrailer) % 8 == 0);
// Shorter than any record, so a trailer cut in half never reads as a record.
static_assert(sizeof(RecordingTrailer) < sizeof(RecordHeader));

// What the engine did with a blade this tick (BladeBlock::step_kind).
enum class StepKind : std::uint8_t { None = 0, Step = 1, ResetAndStep = 2 };

// FrameHeader::servo_flags and RecordHeader::servo_flags.
enum ServoFlag : std::uint32_t {
  kServoRunning = 1U << 0,
  kServoStopping = 1U << 1,  // Ramping down before the loop ends.
  kServoAsFastAsPossible = 1U << 2,
  kServoRecording = 1U << 3,
};

// Bytes of the points block of a blade with `points` points.
constexpr std::size_t points_block_bytes(std::size_t points) {
  return (points * 6 * sizeof(double) + points + 7) / 8 * 8;
}

// Writes q, p and states of `points` points into `out` (points_block_bytes long).
struct PointsView {
  double* q;
  double* p;
  std::uint8_t* state;
};
PointsView points_view(unsigned char* block, std::size_t points);

// The layout as JSON text: every fixed struct with its fields' names, numpy
// type codes, offsets and shapes, and the points block rule.
std::string layout_json();

}  // namespace hapticut::servo
