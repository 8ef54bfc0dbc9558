/// @file embree_device.cpp
/// new_embree_device(): every duet Embree device, capped at one ISA (see embree_device.hpp).
#include <duet/kernels/embree_device.hpp>
#include <duet/kernels/error.hpp>

#include <string>

namespace duet {

RTCDevice new_embree_device(const char* who) {
  RTCDevice device = rtcNewDevice(kEmbreeDeviceConfig);
  if (!device)
    fail(ErrorCode::kInternal, std::string(who) + ": rtcNewDevice(\"" + kEmbreeDeviceConfig + "\") failed (Embree error " +
                                   std::to_string(static_cast<int>(rtcGetDeviceError(nullptr))) + ")");
  return device;
}

}  // namespace duet
