#pragma once
// Shared helpers of the C API tests (tests/capi/*.cpp).
#include <duet.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <string>
#include <vector>

namespace duet_capi_test {

/// Owns a device; every test starts and ends with clean error slots.
class DeviceTest : public ::testing::Test {
 protected:
  void SetUp() override {
    (void)duet_device_get_error(nullptr);
    device_ = duet_device_new("threads=2");
    ASSERT_NE(device_, nullptr) << duet_device_get_error_message(nullptr);
  }
  void TearDown() override {
    duet_device_release(device_);
    EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_NONE) << duet_device_get_error_message(nullptr);
  }
  /// Takes (and clears) the device's pending error.
  duet_error take() { return duet_device_get_error(device_); }
  std::string message() { return duet_device_get_error_message(device_); }

  duet_device device_ = nullptr;
};

/// Random points in a box, with a few NaN/inf ones when `with_invalid`.
inline std::vector<float> random_points(std::size_t n, std::uint32_t seed, float extent,
                                        bool with_invalid = false) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-extent, extent);
  std::vector<float> xyz(3 * n);
  for (float& v : xyz) v = u(rng);
  if (with_invalid && n > 10) {
    xyz[3 * 3 + 1] = NAN;
    xyz[3 * 7 + 2] = INFINITY;
  }
  return xyz;
}

inline std::vector<std::uint8_t> random_colors(std::size_t n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> u(0, 255);
  std::vector<std::uint8_t> rgb(3 * n);
  for (auto& v : rgb) v = static_cast<std::uint8_t>(u(rng));
  return rgb;
}

/// A floor (z = 0) with noise, a wall (x = 2) and a table top (z = 0.7): realistic input for
/// normals, segmentation and the grid.
inline std::vector<float> room_points(std::size_t n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::normal_distribution<float> noise(0.0f, 0.003f);
  std::vector<float> xyz;
  xyz.reserve(3 * n);
  for (std::size_t i = 0; i < n; ++i) {
    const float r = u(rng);
    float x, y, z;
    if (r < 0.5f) {  // floor
      x = 0.3f + 1.7f * u(rng);
      y = -1.0f + 2.0f * u(rng);
      z = noise(rng);
    } else if (r < 0.8f) {  // wall
      x = 2.0f + noise(rng);
      y = -1.0f + 2.0f * u(rng);
      z = 1.1f * u(rng);
    } else {  // table top
      x = 1.0f + 0.5f * u(rng);
      y = 0.2f + 0.5f * u(rng);
      z = 0.7f + noise(rng);
    }
    xyz.push_back(x);
    xyz.push_back(y);
    xyz.push_back(z);
  }
  return xyz;
}

/// Bitwise float equality that treats every NaN as equal to every NaN.
inline bool same_float(float a, float b) {
  if (std::isnan(a) || std::isnan(b)) return std::isnan(a) && std::isnan(b);
  return std::memcmp(&a, &b, sizeof(float)) == 0;
}

inline ::testing::AssertionResult same_floats(const float* a, const float* b, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) {
    if (!same_float(a[i], b[i])) {
      return ::testing::AssertionFailure() << "differ at " << i << ": " << a[i] << " vs " << b[i];
    }
  }
  return ::testing::AssertionSuccess();
}

/// A 32-byte record a C user might keep per point: the API must read xyz and normals in place.
struct Record {
  float xyz[3];
  float normal[3];
  std::uint8_t rgb[3];
  std::uint8_t label;
  std::uint32_t cluster;
};
static_assert(sizeof(Record) == 32);

}  // namespace duet_capi_test
