#pragma once
/// @file entropy.hpp
/// Shannon entropy of a binary occupancy cell, paper Eq. (5), in bits, evaluated from the cell's
/// log-odds. Used by the observation model (observation.hpp) and Procedure 1 (the reward is the
/// entropy summed along the sensors' rays, paper §3.1).
///
/// Thread safety: pure functions; grid_entropy() is TBB-parallel inside the caller's arena and its
/// result does not depend on the thread count (per-cell outputs).
#include <duet/kernels/grid_view.hpp>

#include <span>

namespace duet {

/// Eq. (5) in bits: p = 1 - 1/(1+exp(l)); E = -p log2 p - (1-p) log2(1-p).
/// NaN (unknown, never observed) -> 1 bit (paper §3.1: "set the entropy value as 1").
/// E(0) = E(1) = 0: evaluated in a cancellation-free form (through log1p(exp(-|l|))), so
/// |l| large (100, +-inf) gives 0 (or a tiny positive number), never NaN. l = 0 gives 1 bit.
[[nodiscard]] float entropy_bits(float logodds) noexcept;

/// out[i] = entropy_bits(grid.logodds[i]) for every cell [bits].
/// Throws duet::Error(kInvalidArgument) if the grid view is inconsistent or out.size() !=
/// grid.cell_count(). TBB-parallel over fixed blocks; the result does not depend on the thread count.
void grid_entropy(const GridView& grid, std::span<float> out);

}  // namespace duet
