#pragma once
// summary.json's blocks shared by every writer of a run's summary (`duet explore`, `duet run`,
// `duet replay`, the C API's duet_runtime_save): one set of keys for the same figures. Internal
// (not installed): nlohmann_json stays out of the public headers.
#include <duet/runtime/robot/exploration_runtime.hpp>

#include <nlohmann/json.hpp>

namespace duet::detail {

/// The timing of a run: the nominal control period and the latencies (p50/p99/max/mean, ms), late and missed periods.
[[nodiscard]] nlohmann::json timing_json(const RuntimeTiming& timing);
/// What the runtime's input guard did (input_guard.hpp) and its reactions.
[[nodiscard]] nlohmann::json input_json(const InputStats& input, std::uint64_t sets_with_missing, std::uint64_t blind_holds,
                                        std::size_t relocalizations);

/// What the explorer left unexplored (unexplored.hpp): one object per region, largest first.
[[nodiscard]] nlohmann::json left_json(const std::vector<UnexploredRegion>& left);

}  // namespace duet::detail
