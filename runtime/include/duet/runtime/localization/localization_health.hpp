#pragma once
/// @file localization_health.hpp
/// The visual localisation's health (visual_localization.hpp), as the summary, the C API, the
/// log and the controller's feature seeking (navigation/feature_seek.hpp) see it.
namespace duet {

/// good: vision updates the pose; degraded: no accepted visual update for degraded_after_s
/// (the wheels carry the pose); lost: ... for lost_after_s.
enum class LocalizationHealth { kGood = 0, kDegraded = 1, kLost = 2 };
[[nodiscard]] const char* to_string(LocalizationHealth h) noexcept;

}  // namespace duet
