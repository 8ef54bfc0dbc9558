// Placeholder until the partial_sim benchmarks land (issue 3); registers nothing.
#include "common.hpp"

namespace duet::bench {
void register_partial_sim() {}
}  // namespace duet::bench
