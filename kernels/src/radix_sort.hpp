#pragma once
// Internal: stable LSD radix sort of (uint64 key, uint32 value) pairs, parallel over fixed
// blocks (deterministic for any thread count). Only the digits below max_key are sorted.
#include "parallel.hpp"

#include <array>
#include <bit>
#include <cstdint>
#include <vector>

namespace duet::detail {

/// Sorts keys (and values alongside) ascending by key; stable. keys_tmp / values_tmp are
/// scratch (resized as needed). max_key is an upper bound of all keys.
inline void radix_sort_pairs(std::vector<std::uint64_t>& keys, std::vector<std::uint32_t>& values,
                             std::vector<std::uint64_t>& keys_tmp, std::vector<std::uint32_t>& values_tmp,
                             std::uint64_t max_key) {
  constexpr int kBits = 11;
  constexpr std::size_t kBuckets = std::size_t{1} << kBits;
  constexpr std::size_t kBlock = 1 << 16;
  const std::size_t n = keys.size();
  if (n < 2) return;
  const int total_bits = max_key == 0 ? 0 : std::bit_width(max_key);
  if (total_bits == 0) return;
  keys_tmp.resize(n);
  values_tmp.resize(n);
  const std::size_t nb = block_count(n, kBlock);
  std::vector<std::uint32_t> hist(nb * kBuckets);
  std::uint64_t* src_k = keys.data();
  std::uint32_t* src_v = values.data();
  std::uint64_t* dst_k = keys_tmp.data();
  std::uint32_t* dst_v = values_tmp.data();
  int passes = 0;
  for (int shift = 0; shift < total_bits; shift += kBits, ++passes) {
    std::fill(hist.begin(), hist.end(), 0u);
    for_blocks(n, kBlock, [&](std::size_t b, std::size_t begin, std::size_t end) {
      std::uint32_t* h = &hist[b * kBuckets];
      for (std::size_t i = begin; i < end; ++i) ++h[(src_k[i] >> shift) & (kBuckets - 1)];
    });
    // Exclusive prefix in (bucket, block) order -> stable global positions.
    std::uint32_t sum = 0;
    for (std::size_t d = 0; d < kBuckets; ++d) {
      for (std::size_t b = 0; b < nb; ++b) {
        const std::uint32_t c = hist[b * kBuckets + d];
        hist[b * kBuckets + d] = sum;
        sum += c;
      }
    }
    for_blocks(n, kBlock, [&](std::size_t b, std::size_t begin, std::size_t end) {
      std::uint32_t* h = &hist[b * kBuckets];
      for (std::size_t i = begin; i < end; ++i) {
        const std::uint32_t pos = h[(src_k[i] >> shift) & (kBuckets - 1)]++;
        dst_k[pos] = src_k[i];
        dst_v[pos] = src_v[i];
      }
    });
    std::swap(src_k, dst_k);
    std::swap(src_v, dst_v);
  }
  if (passes % 2 == 1) {
    keys.swap(keys_tmp);
    values.swap(values_tmp);
  }
}

}  // namespace duet::detail
