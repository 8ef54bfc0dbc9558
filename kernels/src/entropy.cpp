// Paper Eq. (5): entropy of a binary cell from its log-odds.
#include <duet/kernels/entropy.hpp>

#include <duet/kernels/error.hpp>

#include "parallel.hpp"

#include <cmath>
#include <string>

namespace duet {

float entropy_bits(float logodds) noexcept {
  if (std::isnan(logodds)) return 1.0f;  // §3.1: unknown cells count 1 bit
  // Symmetric in l: with a = |l|, q = 1/(1+e^a) (the smaller of p, 1-p),
  //   -ln q = log1p(e^a) = a + log1p(e^-a),   -ln(1-q) = log1p(e^-a)
  //   E ln2 = q (a + s) + (1-q) s = q a + s,   s = log1p(e^-a)
  // which has no 0 * inf and no 1 - (1 - tiny) cancellation.
  const double a = std::fabs(static_cast<double>(logodds));
  if (std::isinf(a)) return 0.0f;
  const double e = std::exp(-a);           // in (0, 1]
  const double q = e / (1.0 + e);          // 1/(1+e^a)
  const double s = std::log1p(e);
  constexpr double kInvLn2 = 1.4426950408889634;
  return static_cast<float>((q * a + s) * kInvLn2);
}

void grid_entropy(const GridView& grid, std::span<float> out) {
  validate(grid, "grid_entropy: grid");
  if (out.size() != grid.cell_count())
    fail(ErrorCode::kInvalidArgument, "grid_entropy: out has " + std::to_string(out.size()) +
                                          " elements, must be grid.cell_count() = " + std::to_string(grid.cell_count()));
  const float* in = grid.logodds.data();
  float* o = out.data();
  detail::for_blocks(grid.cell_count(), 16384, [&](std::size_t, std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) o[i] = entropy_bits(in[i]);
  });
}

}  // namespace duet
