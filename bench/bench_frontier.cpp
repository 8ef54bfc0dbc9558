// Placeholder until the frontier benchmarks land (issue 3); registers nothing.
#include "common.hpp"

namespace duet::bench {
void register_frontier() {}
}  // namespace duet::bench
