#include "io/file_util.hpp"

#include <duet/kernels/error.hpp>
#include <duet/runtime/io/input_limits.hpp>
#include <duet/runtime/io/trajectory_io.hpp>

#include <charconv>
#include <cmath>
#include <cstdio>

namespace duet {
namespace {

bool parse_double(std::string_view s, double& v) {
  const char* b = s.data();
  const char* e = s.data() + s.size();
  if (b != e && *b == '+') ++b;
  const auto r = std::from_chars(b, e, v);
  return r.ec == std::errc() && r.ptr == e;
}

}  // namespace

std::vector<StampedPose> parse_tum_trajectory(std::string_view text, const std::string& name) {
  std::vector<StampedPose> out;
  std::size_t line_no = 0, pos = 0;
  auto bad = [&](const std::string& what) {
    fail(ErrorCode::kParse, name + ":" + std::to_string(line_no) + ": " + what);
  };
  while (pos <= text.size()) {
    const std::size_t end = std::min(text.find('\n', pos), text.size());
    std::string_view line = text.substr(pos, end - pos);
    pos = end + 1;
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    const std::size_t first = line.find_first_not_of(" \t");
    if (first == std::string_view::npos || line[first] == '#') {
      if (end == text.size()) break;
      continue;
    }
    double v[8];
    int n = 0;
    std::size_t p = first;
    while (p < line.size()) {
      const std::size_t q = std::min(line.find_first_of(" \t,", p), line.size());
      if (q > p) {
        if (n == 8) bad("more than 8 numbers (want: timestamp tx ty tz qx qy qz qw)");
        if (!parse_double(line.substr(p, q - p), v[n])) {
          std::string what(1, '\'');
          what.append(line.substr(p, q - p)).append("' is not a number");
          bad(what);
        }
        if (!std::isfinite(v[n])) bad("a non-finite number");
        ++n;
      }
      p = q + 1;
    }
    if (n != 8) bad(std::to_string(n) + " numbers, want 8 (timestamp tx ty tz qx qy qz qw)");
    const Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
    if (std::abs(q.norm() - 1.0) > 1e-2) bad("quaternion norm " + std::to_string(q.norm()) + " is not 1");
    StampedPose sp;
    sp.stamp_s = v[0];
    sp.pose.linear() = q.normalized().toRotationMatrix();
    sp.pose.translation() = Eigen::Vector3d(v[1], v[2], v[3]);
    out.push_back(sp);
    if (end == text.size()) break;
  }
  if (out.empty()) fail(ErrorCode::kParse, name + ": no pose (want lines 'timestamp tx ty tz qx qy qz qw')");
  return out;
}

std::vector<StampedPose> read_tum_trajectory(const std::filesystem::path& path) {
  const std::string text = detail::read_whole_file(path, input_limits::kTextBytes, "TUM trajectory");
  return parse_tum_trajectory(text, path.string());
}

std::string tum_trajectory_text(const std::vector<StampedPose>& poses) {
  std::string s;
  char buf[256];
  for (const auto& p : poses) {
    const Eigen::Quaterniond q(p.pose.linear());
    const Eigen::Vector3d t = p.pose.translation();
    std::snprintf(buf, sizeof buf, "%.6f %.9g %.9g %.9g %.9g %.9g %.9g %.9g\n", p.stamp_s, t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w());
    s += buf;
  }
  return s;
}

}  // namespace duet
