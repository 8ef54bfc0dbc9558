#pragma once
/// @file input_guard_settings.hpp
/// Settings of the runtime's input guard (input_guard.hpp), apart so that the settings tree
/// (runtime_settings.hpp, included by the profile) does not need the guard itself.
namespace duet {

struct InputGuardSettings {
  /// Odometry messages in a row behind the last accepted stamp (in order among themselves) that
  /// mean the clock stepped back - a new time base - rather than messages out of order, [2, 1000].
  int clock_step_messages = 3;
  double jump_speed_factor = 2.0;       ///< odometry steps beyond this x the chassis' top speeds are jumps, >= 1
  float jump_margin_m = 0.05f;          ///< ... plus this [m], >= 0
  float jump_margin_rad = 0.2f;         ///< ... and this [rad], >= 0
  float garbled_step_m = 0.10f;         ///< a depth step between neighbours this large is an edge [m], > 0
  double garbled_fraction = 0.5;        ///< more edges than this among sampled neighbours: noise, (0, 1]
  double sensor_timeout_periods = 2.5;  ///< silence longer than this many frame periods: a stopped sensor, >= 1
};
void validate(const InputGuardSettings& s);

}  // namespace duet
