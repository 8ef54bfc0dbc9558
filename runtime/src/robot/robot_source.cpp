/// @file robot_source.cpp
/// The registry of robot sources (see robot_source.hpp).
#include <duet/kernels/error.hpp>
#include <duet/runtime/robot/robot_source.hpp>

#include <algorithm>

namespace duet {

void RobotSourceRegistry::add(RobotSourceKind kind) {
  const bool good = !kind.name.empty() && std::all_of(kind.name.begin(), kind.name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
  });
  if (!good) fail(ErrorCode::kInvalidArgument, "robot source name '" + kind.name + "': use lower-case letters, digits and '_'");
  if (!kind.make) fail(ErrorCode::kInvalidArgument, "robot source '" + kind.name + "': no factory");
  for (const RobotSourceKind& k : kinds_)
    if (k.name == kind.name) fail(ErrorCode::kInvalidArgument, "robot source '" + kind.name + "' is registered twice");
  kinds_.push_back(std::move(kind));
}

std::unique_ptr<RobotSource> RobotSourceRegistry::make(std::string_view spec, const Profile& profile, std::uint64_t seed) const {
  const std::size_t colon = spec.find(':');
  const std::string_view name = spec.substr(0, colon);
  RobotSourceRequest request;
  request.argument = colon == std::string_view::npos ? std::string() : std::string(spec.substr(colon + 1));
  request.seed = seed;
  for (const RobotSourceKind& k : kinds_)
    if (k.name == name) {
      std::unique_ptr<RobotSource> source = k.make(profile, request);
      if (!source) fail(ErrorCode::kInternal, "robot source '" + k.name + "': the factory made nothing");
      if (source->sensors().size() != profile.sensors.size())
        fail(ErrorCode::kInvalidArgument, "robot source '" + k.name + "' has " + std::to_string(source->sensors().size()) +
                                              " sensors, the profile '" + profile.name + "' " + std::to_string(profile.sensors.size()));
      return source;
    }
  std::string known;
  for (const RobotSourceKind& k : kinds_) known += (known.empty() ? "" : ", ") + k.name;
  fail(ErrorCode::kInvalidArgument, "unknown robot source '" + std::string(name) + "' (in '" + std::string(spec) +
                                        "'); known: " + (known.empty() ? "none" : known));
}

}  // namespace duet
