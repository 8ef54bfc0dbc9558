// Placeholder until the observation benchmarks land (issue 3); registers nothing.
#include "common.hpp"

namespace duet::bench {
void register_observation() {}
}  // namespace duet::bench
