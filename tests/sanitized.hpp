#pragma once
/// @file sanitized.hpp
/// kSanitized: the tests are built with a sanitizer (DUET_SANITIZE, DUET_SANITIZE_THREAD). A
/// simulated exploration runs ~5x slower there; the longest tests then run fewer repetitions of
/// what their first run already covered (more seeds of the same world, a second variant of the
/// same code path). The Release pass runs them all.
namespace duet_test {
#if defined(DUET_TEST_SANITIZED) && DUET_TEST_SANITIZED
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif
}  // namespace duet_test
