// XR_FB_eye_tracking_social (per-eye gaze), for OpenXR headers that predate
// it: Debian 12's OpenXR SDK is 1.0.20, the extension came with 1.0.22. The
// handle, structures, enum values and function pointer types are those of
// the OpenXR specification's registry (xr.xml; extension number 203, so its
// enum values are 1000000000 + (203 − 1) × 1000 + n: "The OpenXR
// Specification", §12, XR_FB_eye_tracking_social, and Appendix "Core Revisions
// / Extension enumerant values"). A header that has the extension
// (XR_FB_eye_tracking_social defined) is used as it is.
//
// Include after <openxr/openxr.h>. Shared by curvlab's XR backend and the
// scripted test runtime, so both speak the same layout.
#pragma once

#include <openxr/openxr.h>

#ifndef XR_FB_eye_tracking_social
#define XR_FB_eye_tracking_social 1
#define XR_FB_eye_tracking_social_SPEC_VERSION 1
#define XR_FB_EYE_TRACKING_SOCIAL_EXTENSION_NAME "XR_FB_eye_tracking_social"

XR_DEFINE_HANDLE(XrEyeTrackerFB)

inline constexpr XrObjectType XR_OBJECT_TYPE_EYE_TRACKER_FB = static_cast<XrObjectType>(1000202000);
inline constexpr XrStructureType XR_TYPE_EYE_TRACKER_CREATE_INFO_FB = static_cast<XrStructureType>(1000202001);
inline constexpr XrStructureType XR_TYPE_EYE_GAZES_INFO_FB = static_cast<XrStructureType>(1000202002);
inline constexpr XrStructureType XR_TYPE_EYE_GAZES_FB = static_cast<XrStructureType>(1000202003);
inline constexpr XrStructureType XR_TYPE_SYSTEM_EYE_TRACKING_PROPERTIES_FB =
    static_cast<XrStructureType>(1000202004);

typedef enum XrEyePositionFB {
  XR_EYE_POSITION_LEFT_FB = 0,
  XR_EYE_POSITION_RIGHT_FB = 1,
  XR_EYE_POSITION_COUNT_FB = 2,
  XR_EYE_POSITION_MAX_ENUM_FB = 0x7FFFFFFF
} XrEyePositionFB;

typedef struct XrEyeGazeFB {
  XrBool32 isValid;
  XrPosef gazePose;  // the eye, looking along its −Z axis
  float gazeConfidence;  // 0–1
} XrEyeGazeFB;

typedef struct XrEyeTrackerCreateInfoFB {
  XrStructureType type;
  const void* XR_MAY_ALIAS next;
} XrEyeTrackerCreateInfoFB;

typedef struct XrEyeGazesInfoFB {
  XrStructureType type;
  const void* XR_MAY_ALIAS next;
  XrSpace baseSpace;
  XrTime time;
} XrEyeGazesInfoFB;

// Extends XrSystemProperties.
typedef struct XrSystemEyeTrackingPropertiesFB {
  XrStructureType type;
  void* XR_MAY_ALIAS next;
  XrBool32 supportsEyeTracking;
} XrSystemEyeTrackingPropertiesFB;

typedef struct XrEyeGazesFB {
  XrStructureType type;
  void* XR_MAY_ALIAS next;
  XrEyeGazeFB gaze[XR_EYE_POSITION_COUNT_FB];
  XrTime time;
} XrEyeGazesFB;

typedef XrResult(XRAPI_PTR* PFN_xrCreateEyeTrackerFB)(XrSession session, const XrEyeTrackerCreateInfoFB* createInfo,
                                                       XrEyeTrackerFB* eyeTracker);
typedef XrResult(XRAPI_PTR* PFN_xrDestroyEyeTrackerFB)(XrEyeTrackerFB eyeTracker);
typedef XrResult(XRAPI_PTR* PFN_xrGetEyeGazesFB)(XrEyeTrackerFB eyeTracker, const XrEyeGazesInfoFB* gazeInfo,
                                                  XrEyeGazesFB* eyeGazes);
#endif  // XR_FB_eye_tracking_social
