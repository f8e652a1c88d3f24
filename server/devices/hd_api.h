// The few calls, types and constants of 3D Systems' OpenHaptics HD API
// (libHD) that the openhaptics device kind uses, declared here so that the
// servo builds without the OpenHaptics SDK: its headers (HD/hd.h) are not
// ours to ship, and the library is loaded at run time (hd_library.h).
//
// The calls and their meaning: "OpenHaptics Toolkit API Reference Guide",
// 3D Systems (version 3.5.0; chapters "Device Routines", "Calibration
// Routines", "Scheduler Routines", "HDAPI Types"; a public copy at
// https://usermanual.wiki/Document/OpenHapticsRefGuide.268437991/help), and
// the "OpenHaptics Toolkit Programmer's Guide" (HDAPI: haptic frames, the
// scheduler and its callbacks).
//
// The constants' values and the types: OpenHaptics's HD/hdDefines.h as
// published in the public repository hhmai/PhantomAPI
// (include/HD/hdDefines.h). HD_CALLBACK_DONE (0) / HD_CALLBACK_CONTINUE (1),
// HDCallbackCode, HDSchedulerHandle and the callback's type are the SDK's
// HD/hdScheduler.h's (its text as indexed publicly, without a repository we
// could name), and the reference guide's "HDAPI Types" chapter.
//
// Units: mm, N, N/mm. The device's frame: x right, y up, z towards the user.
// HD_CURRENT_TRANSFORM is a 4x4 matrix in column-major order (OpenGL's),
// the translation in elements 12 to 14. Errors are not return values: each
// call that fails pushes an HDErrorInfo that hdGetError pops (errorCode
// HD_SUCCESS: none).
#pragma once

namespace hapticut::servo::hd {

// hdDefines.h's types.
using HHD = unsigned int;
using HDenum = unsigned int;
using HDerror = unsigned int;
using HDdouble = double;
using HDint = int;
using HDushort = unsigned short;
using HDstring = const char*;
struct HDErrorInfo {
  HDerror errorCode;      // HD_* error code; HD_SUCCESS (0) when none.
  int internalErrorCode;  // The device driver's own code.
  HHD hHD;                // The device current when it happened.
};
// hdScheduler.h's.
using HDCallbackCode = unsigned int;
using HDSchedulerHandle = unsigned long;
using HDSchedulerCallback = HDCallbackCode (*)(void* user_data);

// Values (hdDefines.h, hdScheduler.h).
inline constexpr HDCallbackCode kCallbackDone = 0;          // HD_CALLBACK_DONE: unscheduled after.
inline constexpr HDCallbackCode kCallbackContinue = 1;      // HD_CALLBACK_CONTINUE: run next tick.
inline constexpr HDerror kSuccess = 0x0000;                 // HD_SUCCESS
inline constexpr HDerror kDeviceFault = 0x0300;             // HD_DEVICE_FAULT
inline constexpr HDerror kCommError = 0x0302;               // HD_COMM_ERROR
inline constexpr HDerror kCommConfigError = 0x0303;         // HD_COMM_CONFIG_ERROR
inline constexpr HDerror kDeviceAlreadyInitiated = 0x0301;  // HD_DEVICE_ALREADY_INITIATED
inline constexpr HDerror kInvalidLicense = 0x0600;          // HD_INVALID_LICENSE
inline constexpr HHD kInvalidHandle = 0xFFFFFFFFU;          // HD_INVALID_HANDLE
inline constexpr const char* kDefaultDevice = nullptr;      // HD_DEFAULT_DEVICE (NULL)

inline constexpr HDenum kCurrentButtons = 0x2000;             // HD_CURRENT_BUTTONS: 1 int
inline constexpr HDenum kCurrentTransform = 0x2052;           // HD_CURRENT_TRANSFORM: 16 double
inline constexpr HDenum kUsableWorkspaceDimensions = 0x2551;  // 6 double: min xyz, max xyz (mm)
inline constexpr HDenum kNominalMaxStiffness = 0x2602;        // 1 double (N/mm)
inline constexpr HDenum kNominalMaxForce = 0x2603;            // 1 double (N), peak
inline constexpr HDenum kNominalMaxContinuousForce = 0x2604;  // 1 double (N)
inline constexpr HDenum kCurrentForce = 0x2700;               // HD_CURRENT_FORCE: 3 double (N)
inline constexpr HDenum kForceOutput = 0x4000;                // HD_FORCE_OUTPUT (hdEnable)
inline constexpr HDushort kMaxSchedulerPriority = 0xFFFF;     // HD_MAX_SCHEDULER_PRIORITY

// hdCheckCalibration's answers and hdUpdateCalibration's styles.
inline constexpr HDenum kCalibrationOk = 0x5000;                // HD_CALIBRATION_OK
inline constexpr HDenum kCalibrationNeedsUpdate = 0x5001;       // HD_CALIBRATION_NEEDS_UPDATE
inline constexpr HDenum kCalibrationNeedsManualInput = 0x5002;  // ..._NEEDS_MANUAL_INPUT
inline constexpr HDenum kCalibrationAuto = 1U << 1;             // HD_CALIBRATION_AUTO

// The signatures, as pointers to the library's C functions.
using InitDevice = HHD (*)(HDstring name);       // hdInitDevice: HD_INVALID_HANDLE on error
using DisableDevice = void (*)(HHD device);      // hdDisableDevice
using MakeCurrentDevice = void (*)(HHD device);  // hdMakeCurrentDevice
using GetCurrentDevice = HHD (*)();              // hdGetCurrentDevice
using Enable = void (*)(HDenum capability);      // hdEnable(HD_FORCE_OUTPUT)
using GetDoublev = void (*)(HDenum parameter, HDdouble* values);        // hdGetDoublev
using GetIntegerv = void (*)(HDenum parameter, HDint* values);          // hdGetIntegerv
using SetDoublev = void (*)(HDenum parameter, const HDdouble* values);  // hdSetDoublev
using CheckCalibration = HDenum (*)();             // hdCheckCalibration: HD_CALIBRATION_*
using UpdateCalibration = void (*)(HDenum style);  // hdUpdateCalibration
using StartScheduler = void (*)();                 // hdStartScheduler
using StopScheduler = void (*)();                  // hdStopScheduler
using ScheduleAsynchronous = HDSchedulerHandle (*)(HDSchedulerCallback callback, void* user_data,
                                                   HDushort priority);  // hdScheduleAsynchronous
using Unschedule = void (*)(HDSchedulerHandle handle);                  // hdUnschedule
using BeginFrame = void (*)(HHD device);                                // hdBeginFrame
using EndFrame = void (*)(HHD device);                                  // hdEndFrame
using GetError = HDErrorInfo (*)();                 // hdGetError: pops the newest error
using GetErrorString = HDstring (*)(HDerror code);  // hdGetErrorString

}  // namespace hapticut::servo::hd
