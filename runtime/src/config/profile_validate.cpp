/// @file profile_validate.cpp
/// The profile's range checks, each in its struct's validate() (DESIGN.md §5): the chassis and
/// the sensors here, the mapping and exploration kernels' in the kernels, the runtime's in the
/// runtime's settings headers. validate(Profile) runs them all and the constraints between
/// sections, and names the key a validate() rejects with the file:line:column it was read from.
#include <duet/kernels/error.hpp>
#include <duet/runtime/config/profile.hpp>

#include "config/profile_ranges.hpp"
#include "config/yaml_reader.hpp"

#include <regex>
#include <string>
#include <unordered_set>

namespace duet {
namespace {

using detail::describe;
using detail::format_number;
using detail::in_range;
using detail::Range;
using detail::ranges::kDegToRad;

/// "Struct.field must be in RANGE, got V": the form validate(Profile) locates at its key.
void check(const char* struct_name, const std::string& field, double v, const Range& r) {
  if (in_range(v, r)) return;
  std::string msg = struct_name;
  msg.append(".").append(field).append(" must be in ").append(describe(r)).append(", got ").append(format_number(v));
  fail(ErrorCode::kInvalidArgument, msg);
}

}  // namespace

void validate(const ChassisProfile& c) {
  using namespace detail::ranges;
  if (c.type != "differential")
    fail(ErrorCode::kInvalidArgument, "ChassisProfile.type must be one of: differential; got '" + c.type + "'");
  check("ChassisProfile", "radius_m", c.radius_m, kRadius);
  check("ChassisProfile", "footprint_diameter_m", c.footprint_diameter_m, kFootprint);
  check("ChassisProfile", "wheel_base_m", c.wheel_base_m, kWheelBase);
  check("ChassisProfile", "wheel_diameter_m", c.wheel_diameter_m, kWheelDiameter);
  check("ChassisProfile", "max_linear_speed_mps", c.max_linear_speed_mps, kLinearSpeed);
  check("ChassisProfile", "max_angular_speed_dps", c.max_angular_speed_dps, kAngularSpeed);
  check("ChassisProfile", "odometry_rate_hz", c.odometry_rate_hz, kRateHz);
}

void validate(const SensorProfile& s) {
  using namespace detail::ranges;
  constexpr const char* kS = "SensorProfile";
  if (s.name.empty()) fail(ErrorCode::kInvalidArgument, "SensorProfile.name must be a non-empty string");
  const PinholeIntrinsics& k = s.intrinsics;
  check(kS, "intrinsics.width", k.width, kImageSize);
  check(kS, "intrinsics.height", k.height, kImageSize);
  check(kS, "intrinsics.fx", k.fx, kFocal);
  check(kS, "intrinsics.fy", k.fy, kFocal);
  check(kS, "intrinsics.cx", k.cx, Range{0.0, static_cast<double>(k.width), false, false, "px (0 to width)"});
  check(kS, "intrinsics.cy", k.cy, Range{0.0, static_cast<double>(k.height), false, false, "px (0 to height)"});
  check(kS, "intrinsics.fov_h_deg", s.fov_h_deg, kFov);
  check(kS, "intrinsics.fov_v_deg", s.fov_v_deg, kFov);
  check(kS, "rate_hz", s.rate_hz, kRateHz);
  check(kS, "min_depth_m", s.min_depth_m, kMinDepth);
  check(kS, "max_depth_m", s.max_depth_m, kMaxDepth);
  if (!(s.max_depth_m > s.min_depth_m))
    fail(ErrorCode::kInvalidArgument, "SensorProfile.max_depth_m must be greater than min_depth_m (" +
                                          format_number(s.min_depth_m) + " m), got " + format_number(s.max_depth_m));
  check(kS, "depth_units_per_m", s.depth_units_per_m, kDepthUnits);
  static const char* const kIndex[3] = {"[0]", "[1]", "[2]"};
  for (int a = 0; a < 3; ++a) {
    check(kS, std::string("extrinsics.xyz_m") + kIndex[a], s.extrinsics.xyz_m[a], kOffset);
    check(kS, std::string("extrinsics.zyx_euler_deg") + kIndex[a], s.extrinsics.zyx_euler_deg[a], kEuler);
  }
}

void validate(const MappingSettings& m) {
  validate(m.back_projection);
  validate(m.voxel_filter);
  validate(m.normals);
  validate(m.segmentation);
  validate(m.grid_update);
  check("MappingSettings", "grid_resolution_m", m.grid_resolution_m, detail::ranges::kGridResolution);
}

namespace detail {
namespace {

/// Runs validate()s and names the key they reject.
class Checker {
 public:
  explicit Checker(const Locator& loc) : loc_(loc) {}

  [[noreturn]] void fail_at(const std::string& path, const std::string& msg) const {
    fail(ErrorCode::kInvalidArgument, loc_.where(path) + ": " + path + ": " + msg);
  }

  /// Runs f (a validate() of the struct at `path`). A message "Struct.field ..." (or
  /// "Struct::field ...") names the key path.field: the error points at it where it was read
  /// (file or overlay) and says the rest. Any other message is located at the first key of this
  /// section it names, preferring one an overlay set (the value just changed is the likelier
  /// culprit of a cross-field constraint).
  template <class F>
  void operator()(const std::string& path, F&& f) const {
    try {
      f();
    } catch (const Error& e) {
      const std::string msg = e.what();
      static const std::regex lead(R"(^[A-Z][A-Za-z]*(?:::|\.)([a-z][a-z_0-9]*(?:\.[a-z][a-z_0-9]*|\[[0-9]+\])*) (.*)$)");
      std::smatch m;
      if (std::regex_match(msg, m, lead)) {
        const std::string key = path + "." + m[1].str();
        std::string base = key.substr(0, key.find('['));
        const std::string rest = m[2].str();
        if (loc_.has(key) || loc_.has(base) || !loc_.has(path)) fail_at(key, rest.starts_with("=") ? msg : rest);
      }
      static const std::regex word(R"([a-z][a-z_0-9]*)");
      std::string at = path;
      bool from_overlay = false;
      for (auto it = std::sregex_iterator(msg.begin(), msg.end(), word); it != std::sregex_iterator(); ++it) {
        const std::string key = path + "." + it->str();
        if (!loc_.has(key)) continue;
        if (at == path) at = key;
        if (!from_overlay && loc_.from_overlay(key)) {
          at = key;
          from_overlay = true;
        }
      }
      fail_at(at, msg);
    }
  }

 private:
  const Locator& loc_;
};

}  // namespace

void validate_profile(const Profile& p, const Locator& loc) {
  const Checker check(loc);
  if (p.name.empty()) check.fail_at("name", "must be a non-empty string");
  const ChassisProfile& ch = p.chassis;
  check("chassis", [&] { validate(ch); });

  if (p.sensors.empty() || p.sensors.size() > static_cast<std::size_t>(ranges::kMaxSensors))
    check.fail_at("sensors", "must hold 1 to " + std::to_string(ranges::kMaxSensors) + " sensors, got " +
                                 std::to_string(p.sensors.size()));
  std::unordered_set<std::string> names;
  for (std::size_t i = 0; i < p.sensors.size(); ++i) {
    const SensorProfile& s = p.sensors[i];
    const std::string sp = "sensors[" + std::to_string(i) + "]";
    check(sp, [&] { validate(s); });
    if (!names.insert(s.name).second)
      check.fail_at(sp + ".name", "'" + s.name + "' is already the name of another sensor; names must be unique");
  }

  const MappingSettings& m = p.mapping;
  check("mapping.back_projection", [&] { validate(m.back_projection); });
  check("mapping.voxel_filter", [&] { validate(m.voxel_filter); });
  check("mapping.normals", [&] { validate(m.normals); });
  check("mapping.segmentation.clustering", [&] { validate(m.segmentation.clustering); });  // before its parent's
  check("mapping.segmentation", [&] { validate(m.segmentation); });
  check("mapping.grid_update", [&] { validate(m.grid_update); });
  check("mapping", [&] { validate(m); });

  const ExplorationProfile& ex = p.exploration;
  if (!in_range(ex.rays_per_sensor, ranges::kRaysPerSensor))
    check.fail_at("exploration.rays_per_sensor",
                  "must be in " + describe(ranges::kRaysPerSensor) + ", got " + std::to_string(ex.rays_per_sensor));
  if (ex.inflation.robot_radius_m < ch.radius_m)
    check.fail_at("exploration.inflation.robot_radius_m",
                  "must be at least chassis.radius_m (" + format_number(ch.radius_m) + " m), got " +
                      format_number(ex.inflation.robot_radius_m));
  if (ex.dwa.limits.max_v_mps > ch.max_linear_speed_mps)
    check.fail_at("exploration.dwa.max_v_mps", "must not exceed chassis.max_linear_speed_mps (" +
                                                   format_number(ch.max_linear_speed_mps) + " m/s), got " +
                                                   format_number(ex.dwa.limits.max_v_mps));
  if (ex.dwa.limits.max_omega_rps > ch.max_angular_speed_dps * kDegToRad * (1.0 + 1e-6))
    check.fail_at("exploration.dwa.max_omega_rps", "must not exceed chassis.max_angular_speed_dps (" +
                                                       format_number(ch.max_angular_speed_dps * kDegToRad) +
                                                       " rad/s), got " + format_number(ex.dwa.limits.max_omega_rps));
  if (ex.strategy.simulation.v_max_mps > ch.max_linear_speed_mps)
    check.fail_at("exploration.simulation.v_max_mps", "must not exceed chassis.max_linear_speed_mps (" +
                                                          format_number(ch.max_linear_speed_mps) + " m/s), got " +
                                                          format_number(ex.strategy.simulation.v_max_mps));
  check("exploration.cells", [&] { validate(ex.cells); });
  check("exploration.observation", [&] { validate(ex.observation); });
  check("exploration.inflation", [&] { validate(ex.inflation); });
  check("exploration.path", [&] { validate(ex.path); });
  check("exploration.frontier", [&] { validate(ex.strategy.frontier); });
  check("exploration.simulation", [&] { validate(ex.strategy.simulation); });
  {
    // Procedure 1's cell budget (kMaxSimulatedCells) with this robot's fans and grid: checked here
    // so that a profile that passes does not fail at the first decision.
    const double cells = simulated_observations(ex.strategy.simulation) * fan_cells(observation_sectors(p), m.grid_resolution_m);
    if (!(cells <= kMaxSimulatedCells))
      check.fail_at("exploration.simulation.particles",
                    "particles * sum_i(phi_i) * stages * rays_per_sensor * the sensors' cells (max_depth_m / grid_resolution_m) = " +
                        format_number(cells) + " cell visits per decision, more than the budget of " + format_number(kMaxSimulatedCells));
  }
  check("exploration", [&] { validate(ex.strategy); });
  check("runtime", [&] { validate(p.runtime); });
  check("exploration.dwa", [&] {
    validate(ex.dwa.limits);
    validate(ex.dwa);
  });
}

}  // namespace detail
}  // namespace duet
