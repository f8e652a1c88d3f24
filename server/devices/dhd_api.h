// The few calls and constants of Force Dimension's haptic SDK (DHD, libdhd)
// that the forcedimension device kind uses, declared here from the SDK's
// public documentation so that the servo builds without the SDK: its headers
// (dhdc.h) are not ours to ship, and the library is loaded at run time
// (dhd_library.h).
//
// Source: "DHD - Haptic SDK Documentation", Force Dimension, shipped as the
// SDK's doc/ pages (https://forcedimension.com/downloads/sdk/, e.g.
// sdk-3.17.1-linux-x86_64-gcc.tar.gz), sections "Device Types", "Axis
// Convention", "Device Modes", "Error Management" and the function reference; the same
// reference adapted function by function, with the constants' values, in
// forcedimension_core's "DHD Reference"
// (https://forcedimension-core-python-docs.readthedocs.io/en/latest/forcedimension_core.dhd-doc.html).
// dhdSetWatchdog and dhdGetWatchdog are from the SDK's header dhdc.h (its
// "expert SDK" part, marked "added in release 3.3.2") and the same reference;
// the servo does not turn on expert mode (dhdEnableExpertMode), so a library
// that wants it for these calls refuses them (dhd_device.h: a warning).
//
// Every device call takes the device ID as its last argument (a char; -1:
// the default device); positions are in m, forces in N, the frame is the
// SDK's (x towards the user, y to the right, z up). A call that fails
// returns -1 (a negative value) and sets the calling thread's last error;
// DHD_TIMEGUARD and DHD_MOTOR_SATURATED are successes.
#pragma once

namespace hapticut::servo::dhd {

// Return values that are not errors.
inline constexpr int kTimeGuard = 1;       // DHD_TIMEGUARD: the call was skipped, data still valid.
inline constexpr int kMotorSaturated = 2;  // DHD_MOTOR_SATURATED: force scaled down by the device.
inline constexpr unsigned char kOn = 1;    // DHD_ON
inline constexpr unsigned char kOff = 0;   // DHD_OFF

// dhdGetSystemType's device types (DHD_DEVICE_*).
inline constexpr int kDeviceNone = 0;
inline constexpr int kDeviceDelta3 = 63;
inline constexpr int kDeviceOmega3 = 33;
inline constexpr int kDeviceOmega6Right = 34;
inline constexpr int kDeviceOmega6Left = 36;
inline constexpr int kDeviceOmega7Right = 35;
inline constexpr int kDeviceOmega7Left = 37;
inline constexpr int kDeviceController = 81;
inline constexpr int kDeviceControllerHr = 82;
inline constexpr int kDeviceCustom = 91;
inline constexpr int kDeviceSigma3 = 206;
inline constexpr int kDeviceSigma7Right = 104;
inline constexpr int kDeviceSigma7Left = 105;
inline constexpr int kDeviceLambda3 = 203;
inline constexpr int kDeviceLambda7Right = 108;
inline constexpr int kDeviceLambda7Left = 109;
inline constexpr int kDeviceFalcon = 60;

// dhdErrorGetLast's codes this kind names in its messages (DHD_ERROR_*).
inline constexpr int kErrorNone = 0;
inline constexpr int kErrorCom = 2;
inline constexpr int kErrorNoDriverFound = 4;
inline constexpr int kErrorNoDeviceFound = 5;
inline constexpr int kErrorTimeout = 7;
inline constexpr int kErrorDeviceNotReady = 12;
inline constexpr int kErrorDeviceInUse = 20;

// dhdGetStatus's array: DHD_MAX_STATUS entries (16 before SDK 3.14, 17 since), so the
// servo passes a larger one; DHD_STATUS_RESET is 1 while the device waits in RESET mode
// for its initialisation (the calibration position reached by hand).
inline constexpr int kStatusArraySize = 32;
inline constexpr int kStatusReset = 3;  // DHD_STATUS_RESET

// The device firmware's watchdog (dhdSetWatchdog, "on compatible devices"): when no force
// command arrives for its duration, the firmware disables forces. Its unit is 125 us, in
// an unsigned char (0 turns it off), so the longest is 255 units: 31.875 ms.
inline constexpr double kWatchdogUnit_s = 125e-6;
inline constexpr int kWatchdogMaxUnits = 255;

// The signatures, as pointers to the library's C functions.
using GetDeviceCount = int (*)();                           // dhdGetDeviceCount: devices, -1 error
using OpenId = int (*)(char index);                         // dhdOpenID: the device ID, -1 error
using GetSystemType = int (*)(char id);                     // dhdGetSystemType: DHD_DEVICE_*
using EnableForce = int (*)(unsigned char value, char id);  // dhdEnableForce(DHD_ON / DHD_OFF)
using GetPosition = int (*)(double* x_m, double* y_m, double* z_m, char id);  // dhdGetPosition
using GetOrientationFrame = int (*)(double matrix[3][3], char id);         // dhdGetOrientationFrame
using GetButtonMask = unsigned int (*)(char id);                           // dhdGetButtonMask
using GetStatus = int (*)(int status[kStatusArraySize], char id);          // dhdGetStatus
using SetForce = int (*)(double fx_N, double fy_N, double fz_N, char id);  // dhdSetForce
using GetMaxForce = double (*)(char id);    // dhdGetMaxForce: the set limit (N); < 0: none set
using ErrorGetLast = int (*)();             // dhdErrorGetLast: this thread's last DHD_ERROR_*
using ErrorGetLastStr = const char* (*)();  // dhdErrorGetLastStr: the same as text
using Stop = int (*)(char id);              // dhdStop: forces off, brakes on
using Close = int (*)(char id);             // dhdClose
// dhdSetWatchdog(units of kWatchdogUnit_s, 0: off) and dhdGetWatchdog: SDK 3.3.2 and
// later only, so loaded as optional symbols (dhd_library.h).
using SetWatchdog = int (*)(unsigned char units, char id);
using GetWatchdog = int (*)(unsigned char* units, char id);

}  // namespace hapticut::servo::dhd
