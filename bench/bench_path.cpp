// Placeholder until the path benchmarks land (issue 3); registers nothing.
#include "common.hpp"

namespace duet::bench {
void register_path() {}
}  // namespace duet::bench
