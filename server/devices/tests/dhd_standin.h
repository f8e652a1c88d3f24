// The stand-in for Force Dimension's DHD library (dhd_standin.cpp): a shared
// library exporting the same C symbols as libdhd (server/devices/dhd_api.h),
// built by the tests, loaded by the servo through $HAPTICUT_DHD_LIB. Its
// behaviour is a script, from $HAPTICUT_DHD_STANDIN at the first call or
// from hapticut_dhd_standin_configure: comma-separated key=value pairs,
//   devices=1          what dhdGetDeviceCount returns (0: none connected)
//   type=33            dhdGetSystemType (DHD_DEVICE_OMEGA3; 35 an omega.7, with a wrist)
//   reset=0            1: dhdGetStatus says RESET mode (powered up, not initialised)
//   max_force=-1       dhdGetMaxForce (N; negative: no limit set in the device)
//   buttons=0          dhdGetButtonMask
//   from=X:Y:Z, to=X:Y:Z, reads=N   the position (m, the SDK's frame) goes from
//                      `from` to `to` over the first N dhdGetPosition calls, then holds
//   yaw_deg=0          dhdGetOrientationFrame: a rotation about the SDK's z (degrees)
//   open_error=CODE    dhdOpenID fails with this DHD error (20: device in use)
//   fail_position_at=N dhdGetPosition call N (from 1) fails with a COM error ...
//   fail_count=1       ... and as many calls after it
//   fail_force_at=N    dhdSetForce call N (from 1) fails with a COM error
//   position_result=0, force_result=0   what dhdGetPosition and dhdSetForce return when
//                      they succeed (1: DHD_TIMEGUARD, 2: DHD_MOTOR_SATURATED)
//   watchdog_error=CODE  dhdSetWatchdog and dhdGetWatchdog fail with this DHD error (a
//                      device that refuses the firmware's watchdog)
// and records every call, which $HAPTICUT_DHD_STANDIN_LOG (if set) receives
// at each dhdClose, one line per call: "name a b c result time_s" (time_s:
// CLOCK_MONOTONIC at the call, the servo's clock).
//
// The firmware's watchdog, modelled: once dhdSetWatchdog(N) has set it, the
// force the arm applies at a time t is the last commanded one while t is at
// most N x 125 us after that command, else zero; forces then stay disabled
// until dhdEnableForce(DHD_ON) (the SDK does not say whether a real device
// lets them back on by itself: the stand-in takes the stricter reading).
// The record says when: a line "firmware_watchdog fx fy fz 0 time_s", the
// force dropped and the moment it was (the last command's time plus the
// duration), put in before the first call after it, or before a reading of
// the record. Built with HAPTICUT_DHD_STANDIN_NO_WATCHDOG, the stand-in lacks
// both watchdog symbols, as a libdhd before SDK 3.3.2 does.
#pragma once

extern "C" {

struct DhdStandinCall {
  char name[32];
  double a;  // The call's arguments: a force (N), the enable flag, the index or ID.
  double b;
  double c;
  int result;
  double time_s;  // CLOCK_MONOTONIC when the call was made.
};

// Resets the record and the counters and applies `script`.
void hapticut_dhd_standin_configure(const char* script);
// Copies up to `capacity` calls into `out`; returns how many were recorded.
int hapticut_dhd_standin_calls(DhdStandinCall* out, int capacity);
// The force the arm applies at `time_s` (CLOCK_MONOTONIC), by the record and the
// firmware's watchdog above, into `force` (the SDK's frame, N); 1 while forces are on.
int hapticut_dhd_standin_applied_force(double time_s, double force[3]);
}
