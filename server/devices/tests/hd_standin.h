// The stand-in for 3D Systems' OpenHaptics HD library (hd_standin.cpp): a
// shared library exporting the same C symbols as libHD (server/devices/hd_api.h),
// built by the tests, loaded by the servo through $HAPTICUT_OPENHAPTICS_LIB.
// Like OpenHaptics it runs its own scheduler thread (hdStartScheduler), which
// calls the scheduled callbacks once per period. Its behaviour is a script,
// from $HAPTICUT_HD_STANDIN at the first call or from
// hapticut_hd_standin_configure: comma-separated key=value pairs,
//   devices=1          0: hdInitDevice fails (HD_COMM_ERROR), as with nothing plugged in
//   init_error=CODE    hdInitDevice fails with this HD error (0x301: already initiated)
//   calibration=ok     ok | update (needs an update, which hdUpdateCalibration makes) | manual
//   max_force=3.3, continuous=0.88, stiffness=1.0   the nominal limits (N, N, N/mm)
//   ws_min=X:Y:Z, ws_max=X:Y:Z   HD_USABLE_WORKSPACE_DIMENSIONS (mm)
//   from=X:Y:Z, to=X:Y:Z, frames=N   the stylus's position (mm, OpenHaptics's
//                      frame) goes from `from` to `to` over the first N frames, then holds
//   buttons=0          HD_CURRENT_BUTTONS
//   rate=1000          the scheduler's rate (Hz)
//   fail_frame_at=N    in frame N (from 1) reading the transform fails (HD_COMM_ERROR) ...
//   fail_count=1       ... and in as many frames after it
//   fail_end_at=N      hdEndFrame of frame N fails (HD_COMM_ERROR)
//   stall_at=N, stall_ms=M   the scheduler stops for M ms before frame N
// It records every call but hdGetError's; $HAPTICUT_HD_STANDIN_LOG (if set)
// receives the record at each hdDisableDevice, one line per call:
// "name a b c frame in_frame result time_s" (hdGetDoublev(TRANSFORM) and
// hdSetDoublev(FORCE) are named apart, with the position and the force;
// time_s is CLOCK_MONOTONIC at the call, the servo's clock).
#pragma once

extern "C" {

struct HdStandinCall {
  char name[32];
  double a;  // The call's arguments: a parameter, a force (N), a position (mm).
  double b;
  double c;
  long frame;     // The scheduler's frame number at the call (0: before the first).
  int in_frame;   // 1 between hdBeginFrame and hdEndFrame.
  int result;     // 0, or the HD error the call pushed.
  double time_s;  // CLOCK_MONOTONIC when the call was made.
};

// Resets the record and the counters and applies `script`.
void hapticut_hd_standin_configure(const char* script);
// Copies up to `capacity` calls into `out`; returns how many were recorded.
int hapticut_hd_standin_calls(HdStandinCall* out, int capacity);
}
