#pragma once
/// @file profile_ranges.hpp
/// The ranges of the profile's own structs (chassis, sensors): validate(ChassisProfile) and
/// validate(SensorProfile) check them; the sensor reader checks the focal lengths and fields of
/// view against the same ranges before it derives one from the other. The kernels' settings
/// are checked by the kernels' validate().
#include "config/yaml_reader.hpp"

namespace duet::detail::ranges {

inline constexpr double kDegToRad = 0.017453292519943295;

inline constexpr Range kRadius{0.0, 5.0, true, false, "m"};
inline constexpr Range kFootprint{0.0, 10.0, true, false, "m"};
inline constexpr Range kWheelBase{0.0, 5.0, true, false, "m"};
inline constexpr Range kWheelDiameter{0.0, 2.0, true, false, "m"};
inline constexpr Range kLinearSpeed{0.0, 10.0, true, false, "m/s"};
inline constexpr Range kAngularSpeed{0.0, 3600.0, true, false, "deg/s"};
inline constexpr Range kRateHz{0.0, 1000.0, true, false, "Hz"};
inline constexpr Range kImageSize{1.0, 16384.0, false, false, "px"};
inline constexpr Range kFocal{0.0, 1e6, true, false, "px"};
inline constexpr Range kFov{0.0, 180.0, true, true, "deg"};
inline constexpr Range kMinDepth{0.0, 100.0, false, true, "m"};
inline constexpr Range kMaxDepth{0.0, 100.0, true, false, "m"};
inline constexpr Range kDepthUnits{0.0, 1e6, true, false, "units/m"};
inline constexpr Range kOffset{-10.0, 10.0, false, false, "m"};
inline constexpr Range kEuler{-360.0, 360.0, false, false, "deg"};
inline constexpr Range kRaysPerSensor{1.0, 10000.0, false, false, ""};
inline constexpr Range kGridResolution{0.001, 10.0, false, false, "m"};  // within grid.hpp's [kMinGridResolutionM, kMaxGridResolutionM]
inline constexpr int kMaxSensors = 16;

}  // namespace duet::detail::ranges
