/// @file embree_device.cpp
/// new_embree_device(): every duet Embree device (see embree_device.hpp).
#include <duet/kernels/embree_device.hpp>
#include <duet/kernels/error.hpp>

#include <cstdlib>
#include <string>

namespace duet {

namespace {
const char* config_from_env() { return std::getenv("DUET_EMBREE_CONFIG"); }
}  // namespace

std::string embree_device_config() {
  const char* env = config_from_env();
  return env != nullptr ? std::string(env) : std::string(kEmbreeDeviceConfig);
}

RTCDevice new_embree_device(const char* who) {
  const char* env = config_from_env();
  const bool from_env = env != nullptr;
  const std::string config = from_env ? std::string(env) : std::string(kEmbreeDeviceConfig);
  RTCDevice device = rtcNewDevice(config.c_str());
  if (!device)
    fail(ErrorCode::kInternal, std::string(who) + ": rtcNewDevice(\"" + config + "\"" +
                                   (from_env ? ", from DUET_EMBREE_CONFIG" : "") + ") failed (Embree error " +
                                   std::to_string(static_cast<int>(rtcGetDeviceError(nullptr))) + ")");
  return device;
}

}  // namespace duet
