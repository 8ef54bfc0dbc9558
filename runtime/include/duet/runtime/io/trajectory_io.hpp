#pragma once
/// @file trajectory_io.hpp
/// TUM trajectory files (the TUM RGB-D benchmark's format, also evo's "tum"): one pose per line,
/// "timestamp tx ty tz qx qy qz qw" (seconds, metres, unit quaternion; the pose maps the
/// trajectory's frame to the world), '#' comments and blank lines ignored. `duet explore`
/// writes trajectory.tum in this format; `duet eval-traj` reads it.
///
/// Errors are duet::Error naming the file and line: kIo (missing, not a regular file, over
/// input_limits::kTextBytes), kParse (a line without 8 numbers, a non-finite number, a
/// quaternion whose norm is not within 1e-2 of 1 - within it, it is re-normalised - or a file
/// with no pose).
///
/// Thread safety: reentrant.
#include <duet/kernels/trajectory_eval.hpp>

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace duet {

[[nodiscard]] std::vector<StampedPose> read_tum_trajectory(const std::filesystem::path& path);

/// The same from text; `name` names it in errors.
[[nodiscard]] std::vector<StampedPose> parse_tum_trajectory(std::string_view text, const std::string& name);

/// The TUM text of `poses` (9 significant digits for positions, stamps to the microsecond).
[[nodiscard]] std::string tum_trajectory_text(const std::vector<StampedPose>& poses);

}  // namespace duet
