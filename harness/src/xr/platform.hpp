// OpenXR's platform header with what curvlab uses of it: the Vulkan graphics
// API (XR_KHR_vulkan_enable2), timespec time conversion
// (XR_KHR_convert_timespec_time) and, on Windows, the performance counter's.
// Every source here that needs openxr_platform.h includes it through this
// header, so the macros are set before its first inclusion. Private to
// harness/src/xr.
#pragma once

#include <time.h>
#include <vulkan/vulkan.h>
#define XR_USE_GRAPHICS_API_VULKAN
#define XR_USE_TIMESPEC
#ifdef _WIN32
#include <windows.h>
#define XR_USE_PLATFORM_WIN32
#endif
#include <openxr/openxr_platform.h>
