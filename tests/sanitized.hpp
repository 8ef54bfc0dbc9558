#pragma once
/// @file sanitized.hpp
/// kSanitized: the tests are built with a sanitizer (DUET_SANITIZE, DUET_SANITIZE_THREAD). A
/// simulated exploration runs ~5x slower there.
/// short_runs(): the longest tests run a shorter variant - fewer repetitions of what their first
/// run already covered (more seeds of the same world, a second variant of the same code path), or
/// the same scenario over a shorter horizon with its assertions scaled to it. True in a sanitized
/// build, where what is checked is the memory and the undefined behaviour of the same code paths;
/// the Release pass runs the full variants. DUET_TEST_SHORT=1 selects the short variants in any
/// build (to check their assertions quickly); DUET_TEST_SHORT=0 the full ones, sanitized or not.
#include <cstdlib>
#include <string_view>

namespace duet_test {
#if defined(DUET_TEST_SANITIZED) && DUET_TEST_SANITIZED
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif

inline bool short_runs() {
  static const bool on = [] {
    const char* e = std::getenv("DUET_TEST_SHORT");
    if (e && std::string_view(e) == "1") return true;
    if (e && std::string_view(e) == "0") return false;
    return kSanitized;
  }();
  return on;
}
}  // namespace duet_test
