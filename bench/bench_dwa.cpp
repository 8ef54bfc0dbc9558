// Placeholder until the dwa benchmarks land (issue 3); registers nothing.
#include "common.hpp"

namespace duet::bench {
void register_dwa() {}
}  // namespace duet::bench
