#pragma once
/// @file robot_source.hpp
/// Where a robot's data comes from, by name: a RobotSource bundles the chassis and the sensors of
/// robot_io.hpp with what moves them on (a simulator steps its physics and renders; a driver fed
/// by its own threads has nothing to do), and a RobotSourceRegistry makes one from a spec
/// "NAME" or "NAME:ARGUMENT" (`duet run --robot sim:lab`). A new source is one file (its class
/// and its factory) plus one registration line in the application's list of sources
/// (runtime/apps/robot_sources.cpp); the runtime library itself knows none of them.
///
/// Thread safety: a source is used from the runtime's control thread; the registry is filled
/// once at start-up and is read-only afterwards (make() may then be called from any thread).
#include <duet/runtime/config/profile.hpp>
#include <duet/runtime/robot/robot_io.hpp>

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace duet {

class RobotSource {
 public:
  virtual ~RobotSource() = default;
  [[nodiscard]] virtual ChassisInterface& chassis() = 0;
  /// One sensor per profile sensor, in the profile's order.
  [[nodiscard]] virtual std::span<RgbdSensorInterface* const> sensors() = 0;
  /// Moves the source on to now_s on the runtime's clock, before the runtime's tick at now_s.
  virtual void advance(double now_s) = 0;
};

/// What a factory gets besides the profile.
struct RobotSourceRequest {
  std::string argument;    ///< the spec's text after "NAME:" (empty if none)
  std::uint64_t seed = 1;  ///< for sources with randomness (the simulator's noise)
};

struct RobotSourceKind {
  std::string name;  ///< [a-z0-9_]+, unique in a registry
  std::string help;  ///< one line: what it is and what its argument means
  std::function<std::unique_ptr<RobotSource>(const Profile&, const RobotSourceRequest&)> make;
};

class RobotSourceRegistry {
 public:
  /// Throws duet::Error(kInvalidArgument) for a bad or duplicate name or an empty factory.
  void add(RobotSourceKind kind);
  /// The source a spec names ("NAME" or "NAME:ARGUMENT"). Throws duet::Error(kInvalidArgument)
  /// for an unknown name (the message lists the known ones); the factory's errors pass through.
  [[nodiscard]] std::unique_ptr<RobotSource> make(std::string_view spec, const Profile& profile, std::uint64_t seed = 1) const;
  [[nodiscard]] const std::vector<RobotSourceKind>& kinds() const noexcept { return kinds_; }

 private:
  std::vector<RobotSourceKind> kinds_;
};

}  // namespace duet
