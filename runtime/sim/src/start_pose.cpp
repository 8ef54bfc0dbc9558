/// @file start_pose.cpp
/// Start poses from a file (a map's `.start`), from `--start` text, and set on a world with a
/// check that the robot stands there (world.hpp).
#include <duet/kernels/error.hpp>
#include <duet/runtime/io/input_limits.hpp>
#include <duet/sim/world.hpp>

#include "config/yaml_reader.hpp"
#include "io/cloud_io_detail.hpp"
#include "io/file_util.hpp"

#include <cmath>
#include <numbers>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace duet::sim {
namespace {

using detail::format_number;

/// Three finite numbers from `fields`, or the reason they are not.
std::string to_pose(const std::vector<std::string>& fields, Pose2& out) {
  if (fields.size() != 3) return "expected 3 numbers (x y theta: m, m, rad), got " + std::to_string(fields.size());
  float v[3];
  static const char* const kNames[3] = {"x", "y", "theta"};
  for (int i = 0; i < 3; ++i) {
    const std::string& f = fields[static_cast<std::size_t>(i)];
    double d = 0.0;
    if (!duet::detail::cloud_io::parse_real(f, d)) return std::string(kNames[i]) + " is not a number: '" + f + "'";
    if (!std::isfinite(d) || std::fabs(d) > 1e6) return std::string(kNames[i]) + " must be finite and within 1e6, got " + f;
    v[i] = static_cast<float>(d);
  }
  out = Pose2{v[0], v[1], std::remainder(v[2], 2.0f * std::numbers::pi_v<float>)};
  return {};
}

}  // namespace

Pose2 read_start_file(const std::filesystem::path& path) {
  const std::string text = duet::detail::read_whole_file(path, input_limits::kYamlBytes, "start pose file");
  std::istringstream in(text);
  std::string line;
  int number = 0;
  std::optional<Pose2> pose;
  while (std::getline(in, line)) {
    ++number;
    if (const auto hash = line.find('#'); hash != std::string::npos) line.resize(hash);
    std::istringstream words(line);
    std::vector<std::string> fields;
    for (std::string w; words >> w;) fields.push_back(w);
    if (fields.empty()) continue;
    const std::string where = path.string() + ":" + std::to_string(number) + ": ";
    if (pose) fail(ErrorCode::kInvalidArgument, where + "a second pose (the file holds one line: x y theta)");
    Pose2 p;
    if (const std::string why = to_pose(fields, p); !why.empty()) fail(ErrorCode::kInvalidArgument, where + why);
    pose = p;
  }
  if (!pose) fail(ErrorCode::kInvalidArgument, path.string() + ": no pose (expected one line: x y theta, in m, m, rad)");
  return *pose;
}

Pose2 parse_start(std::string_view text) {
  std::vector<std::string> fields;
  std::string cur;
  for (const char c : text) {
    if (c == ',') {
      fields.push_back(cur);
      cur.clear();
    } else if (c != ' ') {
      cur += c;
    }
  }
  fields.push_back(cur);
  Pose2 p;
  if (const std::string why = to_pose(fields, p); !why.empty())
    fail(ErrorCode::kInvalidArgument, "start '" + std::string(text) + "': " + why + " (expected x,y,theta in m, m, rad)");
  return p;
}

void set_start(World& world, const Pose2& start, float radius_m, std::string_view what) {
  const std::string at = std::string(what) + " (" + format_number(start.x) + ", " + format_number(start.y) + ")";
  if (!(std::isfinite(start.x) && std::isfinite(start.y) && std::isfinite(start.theta)))
    fail(ErrorCode::kInvalidArgument, at + ": not a finite pose");
  const Eigen::Vector2f c(start.x, start.y);
  if (!world.floor.contains(c)) fail(ErrorCode::kInvalidArgument, at + " is off the floor of " + world.name);
  const std::string robot = ": a robot of radius " + format_number(std::round(radius_m * 1000.0) / 1000.0) + " m there ";
  if (const Solid* s = overlapping_solid(world, c, radius_m))
    fail(ErrorCode::kInvalidArgument, radius_m > 0.0f ? at + robot + "overlaps " + s->name + " of " + world.name
                                                      : at + " is inside " + s->name + " of " + world.name);
  if (collides(world, c, radius_m))  // no solid: the floor's edge within the radius
    fail(ErrorCode::kInvalidArgument, at + robot + "reaches off the floor of " + world.name);
  world.start = start;
}

}  // namespace duet::sim
