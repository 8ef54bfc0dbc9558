#pragma once
/// @file resources.hpp
/// What the process uses, for run summaries and long-run health (issue 19: memory and
/// per-cycle time stay bounded over hours).
/// Thread safety: every function may be called from any thread.
#include <cstdint>

namespace duet {

/// The process's resident memory [bytes] (Linux: /proc/self/statm); -1 where it cannot be read.
[[nodiscard]] std::int64_t resident_memory_bytes() noexcept;

}  // namespace duet
