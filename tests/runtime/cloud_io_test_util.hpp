#pragma once
// Helpers shared by the point cloud file tests (test_cloud_io*.cpp): bit-exact cloud comparison,
// random and special-valued clouds, every format's reader and writer, and error expectations.
#include <duet/kernels/error.hpp>
#include <duet/runtime/io/cloud_io.hpp>

#include <gtest/gtest.h>

#include "runtime_test_util.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <initializer_list>
#include <limits>
#include <random>
#include <string>
#include <vector>

namespace duet_test::cloud {

namespace fs = std::filesystem;
using duet::ErrorCode;
using duet::PcdEncoding;
using duet::PlyEncoding;
using duet::PointCloud;

inline const fs::path kPclData = fs::path(DUET_DATA_DIR) / "pcl";

using duet_test::slurp;
using duet_test::spit;
using duet_test::TempDir;

// Same float, bit for bit, except that any NaN equals any NaN (text formats drop payloads).
inline bool same_float(float a, float b) {
  if (std::isnan(a) || std::isnan(b)) return std::isnan(a) && std::isnan(b);
  return std::bit_cast<std::uint32_t>(a) == std::bit_cast<std::uint32_t>(b);
}

inline ::testing::AssertionResult same_cloud(const PointCloud& a, const PointCloud& b) {
  if (a.size() != b.size()) return ::testing::AssertionFailure() << "sizes " << a.size() << " vs " << b.size();
  if (a.colors.size() != b.colors.size()) return ::testing::AssertionFailure() << "colour counts differ";
  if (a.normals.size() != b.normals.size()) return ::testing::AssertionFailure() << "normal counts differ";
  if (a.curvature.size() != b.curvature.size()) return ::testing::AssertionFailure() << "curvature counts differ";
  for (std::size_t i = 0; i < a.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      if (!same_float(a.points[i][k], b.points[i][k])) {
        return ::testing::AssertionFailure() << "point " << i << "[" << k << "]: " << a.points[i][k] << " vs "
                                             << b.points[i][k];
      }
      if (!a.normals.empty() && !same_float(a.normals[i][k], b.normals[i][k])) {
        return ::testing::AssertionFailure() << "normal " << i << "[" << k << "]: " << a.normals[i][k] << " vs "
                                             << b.normals[i][k];
      }
    }
    if (!a.colors.empty() && !(a.colors[i] == b.colors[i])) return ::testing::AssertionFailure() << "colour " << i;
    if (!a.curvature.empty() && !same_float(a.curvature[i], b.curvature[i])) {
      return ::testing::AssertionFailure() << "curvature " << i;
    }
  }
  return ::testing::AssertionSuccess();
}

struct Attrs {
  bool colors = false, normals = false, curvature = false;
};

inline PointCloud random_cloud(std::size_t n, Attrs attrs, std::uint32_t seed, double nan_fraction = 0.0) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> coord(-50.0f, 50.0f), unit(-1.0f, 1.0f), chance(0.0f, 1.0f);
  std::uniform_int_distribution<int> byte(0, 255);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  PointCloud c;
  for (std::size_t i = 0; i < n; ++i) {
    if (chance(rng) < nan_fraction) {
      c.points.emplace_back(nan, nan, nan);
    } else {
      c.points.emplace_back(coord(rng), coord(rng), coord(rng));
    }
    if (attrs.colors) {
      c.colors.push_back({static_cast<std::uint8_t>(byte(rng)), static_cast<std::uint8_t>(byte(rng)),
                          static_cast<std::uint8_t>(byte(rng))});
    }
    if (attrs.normals) c.normals.push_back(Eigen::Vector3f(unit(rng), unit(rng), unit(rng)).normalized());
    if (attrs.curvature) c.curvature.push_back(chance(rng) / 3.0f);
  }
  return c;
}

/// Values that stress text round trips: signed zero, denormals, extremes, infinities.
inline PointCloud special_cloud() {
  PointCloud c;
  const float inf = std::numeric_limits<float>::infinity();
  const std::vector<float> v = {0.0f, -0.0f, 1e-45f, -1.17549435e-38f, 3.4028235e38f, -3.4028235e38f,
                                0.1f, 1.0f / 3.0f, 123456.789f, -inf, inf, 7e-39f};
  for (std::size_t i = 0; i + 2 < v.size(); ++i) {
    c.points.emplace_back(v[i], v[i + 1], v[i + 2]);
    c.colors.push_back({static_cast<std::uint8_t>(i * 20), 255, 0});
    c.normals.emplace_back(v[i + 2], v[i], v[i + 1]);
    c.curvature.push_back(v[i + 1]);
  }
  return c;
}

struct Format {
  const char* name;
  std::function<void(const fs::path&, const PointCloud&)> write;
  std::function<PointCloud(const fs::path&)> read;
  const char* ext;
};

inline std::vector<Format> all_formats() {
  return {
      {"pcd_ascii", [](const fs::path& p, const PointCloud& c) { duet::write_pcd(p, c, PcdEncoding::kAscii); },
       [](const fs::path& p) { return duet::read_pcd(p); }, ".pcd"},
      {"pcd_binary", [](const fs::path& p, const PointCloud& c) { duet::write_pcd(p, c, PcdEncoding::kBinary); },
       [](const fs::path& p) { return duet::read_pcd(p); }, ".pcd"},
      {"pcd_binary_compressed",
       [](const fs::path& p, const PointCloud& c) { duet::write_pcd(p, c, PcdEncoding::kBinaryCompressed); },
       [](const fs::path& p) { return duet::read_pcd(p); }, ".pcd"},
      {"ply_ascii", [](const fs::path& p, const PointCloud& c) { duet::write_ply(p, c, PlyEncoding::kAscii); },
       [](const fs::path& p) { return duet::read_ply(p); }, ".ply"},
      {"ply_binary_le",
       [](const fs::path& p, const PointCloud& c) { duet::write_ply(p, c, PlyEncoding::kBinaryLittleEndian); },
       [](const fs::path& p) { return duet::read_ply(p); }, ".ply"},
  };
}

using duet_test::expect_error;

// Reads a possibly corrupt file: either a duet::Error (kParse or kOutOfMemory) or a cloud.
// Anything else (another exception, a crash) is a failure. Returns true when it read.
inline bool read_survives(const Format& f, const fs::path& p, PointCloud* out, std::string* message = nullptr) {
  try {
    PointCloud c = f.read(p);
    c.check_consistent();
    if (out != nullptr) *out = std::move(c);
    return true;
  } catch (const duet::Error& e) {
    EXPECT_TRUE(e.code() == ErrorCode::kParse || e.code() == ErrorCode::kOutOfMemory) << e.what();
    EXPECT_NE(std::string(e.what()).find(p.string()), std::string::npos) << "error does not name the file: " << e.what();
    if (message != nullptr) *message = e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << f.name << ": not a duet::Error: " << e.what();
  }
  return false;
}

// Bytes of a value as stored in a little-endian (raw) or big-endian (raw_be) file.
inline std::string f32(float v) { return std::string(reinterpret_cast<const char*>(&v), 4); }
template <class T>
inline std::string raw(T v) {
  return std::string(reinterpret_cast<const char*>(&v), sizeof(T));
}
template <class T>
inline std::string raw_be(T v) {
  std::string s = raw(v);
  std::reverse(s.begin(), s.end());
  return s;
}

}  // namespace duet_test::cloud
