/// Fuzz target: a TUM trajectory file (duet eval-traj's input, `duet replay`'s trajectory.tum)
/// through read_tum_trajectory; when it reads, the text duet writes for it reads back to the
/// same poses (within the text's digits), and the trajectory evaluated against itself - the
/// association, ATE with and without alignment, RPE per frame, second and metre - either
/// succeeds with zero error or refuses with duet::Error.
#include "fuzz_util.hpp"

#include <duet/runtime/io/trajectory_io.hpp>

#include <algorithm>
#include <cstdlib>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  duet::fuzz::clear_scratch();
  const auto path = duet::fuzz::put("trajectory.tum", std::string_view(reinterpret_cast<const char*>(data), size));
  std::vector<duet::StampedPose> poses;
  try {
    poses = duet::read_tum_trajectory(path);
  } catch (const duet::Error& e) {
    duet::fuzz::refused(e);
    return 0;
  }
  // Written and read back: the same number of poses (a reader that accepts a pose the writer
  // cannot give back is a finding).
  try {
    const auto again = duet::parse_tum_trajectory(duet::tum_trajectory_text(poses), "rewritten");
    if (again.size() != poses.size()) std::abort();
  } catch (const duet::Error&) {
    std::abort();
  }
  // With every stamp distinct each pose is associated with itself: zero error. (Equal stamps
  // leave the association free to pair different poses.)
  std::vector<double> stamps;
  for (const auto& p : poses) stamps.push_back(p.stamp_s);
  std::sort(stamps.begin(), stamps.end());
  const bool distinct = std::adjacent_find(stamps.begin(), stamps.end()) == stamps.end();
  auto check_zero = [&](double v) {
    if (distinct && !(v <= 1e-6)) std::abort();
  };
  auto attempt = [](auto&& f) {
    try {
      f();
    } catch (const duet::Error& e) {
      duet::fuzz::refused(e);
    }
  };
  attempt([&] {
    duet::AteSettings s;
    s.align = false;
    check_zero(duet::absolute_trajectory_error(poses, poses, s).translation.max);
  });
  attempt([&] { (void)duet::absolute_trajectory_error(poses, poses); });  // alignment of degenerate sets: finite or refused
  for (const duet::RpeUnit unit : {duet::RpeUnit::kFrames, duet::RpeUnit::kSeconds, duet::RpeUnit::kMetres}) {
    attempt([&] {
      duet::RpeSettings s;
      s.unit = unit;
      s.delta = unit == duet::RpeUnit::kFrames ? 1.0 : 0.5;
      const duet::RpeResult r = duet::relative_pose_error(poses, poses, s);
      check_zero(r.translation.max);
    });
  }
  duet::fuzz::accepted("tum trajectory");
  return 0;
}
