#pragma once
// same_grid(): two occupancy grids equal bit for bit (NaN = NaN), for test_grid.cpp and
// test_occupancy_grid.cpp.
#include <duet/kernels/grid.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <cstring>

namespace duet::test {

inline ::testing::AssertionResult same_grid(const OccupancyGrid& a, const OccupancyGrid& b) {
  if (a.width() != b.width() || a.height() != b.height() || a.origin() != b.origin() || a.resolution() != b.resolution())
    return ::testing::AssertionFailure() << "geometry differs: " << a.width() << "x" << a.height() << " at " << a.origin().transpose()
                                         << " vs " << b.width() << "x" << b.height() << " at " << b.origin().transpose();
  std::size_t diff = 0;
  auto f = ::testing::AssertionFailure();
  for (int y = 0; y < a.height(); ++y)
    for (int x = 0; x < a.width(); ++x) {
      const float u = a.at(x, y), v = b.at(x, y);
      if (std::memcmp(&u, &v, sizeof(float)) != 0 && !(std::isnan(u) && std::isnan(v))) {
        if (++diff <= 5) f << " cell (" << x << "," << y << "): " << u << " vs " << v << ";";
      }
    }
  if (diff == 0) return ::testing::AssertionSuccess();
  return f << " " << diff << " cells differ";
}

}  // namespace duet::test
