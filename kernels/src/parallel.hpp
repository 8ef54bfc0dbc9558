#pragma once
// Internal helpers for deterministic parallel loops: work is cut into fixed-size blocks that do
// not depend on the number of threads, so any per-block partial result (and its combination in
// block order) is the same with 1 or N threads.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstddef>

namespace duet::detail {

inline std::size_t block_count(std::size_t n, std::size_t block) { return (n + block - 1) / block; }

/// Calls fn(block_index, begin, end) for each fixed-size block of [0, n), in parallel.
template <class Fn>
void for_blocks(std::size_t n, std::size_t block, Fn&& fn) {
  const std::size_t nb = block_count(n, block);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nb, 1), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t b = r.begin(); b != r.end(); ++b) {
      const std::size_t begin = b * block;
      fn(b, begin, std::min(n, begin + block));
    }
  });
}

/// Parallel loop over [0, n) with a grain size; fn(i).
template <class Fn>
void for_each_index(std::size_t n, std::size_t grain, Fn&& fn) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, grain), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) fn(i);
  });
}

}  // namespace duet::detail
