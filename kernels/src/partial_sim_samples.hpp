#pragma once
// Internal: lines 10-17 and 19 of Procedure 1 (partial_sim.cpp) for one particle whose rays the walks
// stored (partial_sim_rays.hpp): its phi samples of z ~ chi and their rewards. Two implementations
// that give the same bits (partial_sim_samples.cpp): one sample at a time, and up to 8 samples at
// once in AVX2 lanes (chosen at run time where the CPU has AVX2).
#include <duet/kernels/partial_sim.hpp>

#include "partial_sim_rays.hpp"
#include "random.hpp"

#include <cstddef>
#include <cstdint>

namespace duet::detail {
/// Test hook (tests/kernels/test_partial_sim.cpp): which implementation the samples use. kAuto:
/// the lanes where the CPU has AVX2, else one at a time. Set only while no simulation runs.
enum class PartialSimSamples { kAuto, kOneAtATime, kLanes };
extern PartialSimSamples partial_sim_samples;
/// True if this build and CPU can run the lanes (AVX2).
bool partial_sim_lanes_available();
}  // namespace duet::detail

namespace duet::detail::partial_sim {

struct SampleTotals {
  double log_w = 0.0;        // log prod_j sum_t gamma^(t-H) R_tj (line 19)
  double reward_sum = 0.0;   // sum over j and t of R_tj [bits]
  double unknown_sum = 0.0;  // its part from cells whose state is unknown [bits]
  std::int64_t visits = 0;   // cells the samples processed
};

/// The phi samples of one particle's rays in ts (ts.cells, ray_end; rays_per_stage rays
/// per stage), drawing from rng in the order: per sample j, per stage k, the l_ISM noise (if any),
/// then one uniform per ray. n_cells: the window's cells (the overlay's indices).
SampleTotals simulate_samples(const PartialSimSettings& s, std::size_t rays_per_stage, int phi, Rng& rng, ThreadScratch& ts,
                              std::size_t n_cells);

}  // namespace duet::detail::partial_sim
