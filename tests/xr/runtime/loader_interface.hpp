// The loader ↔ runtime negotiation structures (OpenXR loader specification,
// "Runtime Interface Negotiation"); Debian's libopenxr-dev 1.0.20 does not
// install the header that declares them. Shared by the test runtime and the
// test that asks it for its functions directly.
#pragma once

#include <openxr/openxr.h>

extern "C" {
enum XrLoaderInterfaceStructs {
  XR_LOADER_INTERFACE_STRUCT_UNINTIALIZED = 0,
  XR_LOADER_INTERFACE_STRUCT_LOADER_INFO = 1,
  XR_LOADER_INTERFACE_STRUCT_API_LAYER_REQUEST = 2,
  XR_LOADER_INTERFACE_STRUCT_RUNTIME_REQUEST = 3,
};
struct XrNegotiateLoaderInfo {
  XrLoaderInterfaceStructs structType;
  uint32_t structVersion;
  size_t structSize;
  uint32_t minInterfaceVersion;
  uint32_t maxInterfaceVersion;
  XrVersion minApiVersion;
  XrVersion maxApiVersion;
};
struct XrNegotiateRuntimeRequest {
  XrLoaderInterfaceStructs structType;
  uint32_t structVersion;
  size_t structSize;
  uint32_t runtimeInterfaceVersion;
  XrVersion runtimeApiVersion;
  PFN_xrGetInstanceProcAddr getInstanceProcAddr;
};
using PFN_xrNegotiateLoaderRuntimeInterface = XrResult (*)(const XrNegotiateLoaderInfo*, XrNegotiateRuntimeRequest*);
}
