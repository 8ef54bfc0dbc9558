// Point cloud files: round trips of every encoding, the real PCL test files compared field by
// field with PCL's own reader, our files loaded by PCL, hand-made files with unusual fields,
// and corrupt files (every truncation, random byte flips, huge declared sizes) that must give
// a duet::Error naming the problem, never a crash.
#include <duet/kernels/error.hpp>
#include <duet/runtime/io/cloud_io.hpp>

#include <gtest/gtest.h>

#include "runtime_test_util.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>

#ifdef DUET_HAVE_PCL
#include <pcl/PCLPointCloud2.h>
#include <pcl/console/print.h>
#include <pcl/conversions.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_types.h>
#endif

namespace fs = std::filesystem;
using duet::ErrorCode;
using duet::PcdEncoding;
using duet::PlyEncoding;
using duet::PointCloud;

namespace {

const fs::path kPclData = fs::path(DUET_DATA_DIR) / "pcl";

using duet_test::slurp;
using duet_test::spit;
using duet_test::TempDir;

// Same float, bit for bit, except that any NaN equals any NaN (text formats drop payloads).
bool same_float(float a, float b) {
  if (std::isnan(a) || std::isnan(b)) return std::isnan(a) && std::isnan(b);
  return std::bit_cast<std::uint32_t>(a) == std::bit_cast<std::uint32_t>(b);
}

::testing::AssertionResult same_cloud(const PointCloud& a, const PointCloud& b) {
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

PointCloud random_cloud(std::size_t n, Attrs attrs, std::uint32_t seed, double nan_fraction = 0.0) {
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
PointCloud special_cloud() {
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

std::vector<Format> all_formats() {
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

// Expects `fn` to throw duet::Error with `code` and a message containing every `parts`.
template <class Fn>
void expect_error(Fn&& fn, ErrorCode code, std::initializer_list<std::string> parts) {
  try {
    fn();
    ADD_FAILURE() << "no duet::Error thrown";
  } catch (const duet::Error& e) {
    EXPECT_EQ(static_cast<int>(e.code()), static_cast<int>(code)) << e.what();
    for (const std::string& part : parts) EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "not a duet::Error: " << e.what();
  }
}

// Reads a possibly corrupt file: either a duet::Error (kParse or kOutOfMemory) or a cloud.
// Anything else (another exception, a crash) is a failure. Returns true when it read.
bool read_survives(const Format& f, const fs::path& p, PointCloud* out, std::string* message = nullptr) {
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

// ------------------------------------------------------------------------------------------
// Round trips

TEST(CloudIo, RoundTripEveryEncoding) {
  TempDir dir;
  struct Case {
    const char* name;
    PointCloud cloud;
  };
  std::vector<Case> cases;
  cases.push_back({"empty", PointCloud{}});
  cases.push_back({"empty_with_attributes", PointCloud{}});
  cases.push_back({"one_point", random_cloud(1, {}, 1)});
  cases.push_back({"one_point_all", random_cloud(1, {true, true, true}, 2)});
  cases.push_back({"nan_points", random_cloud(500, {true, false, false}, 3, 0.3)});
  cases.push_back({"nan_points_normals", random_cloud(500, {false, true, true}, 4, 0.5)});
  cases.push_back({"xyz_100k", random_cloud(100000, {}, 5)});
  cases.push_back({"rgb_100k", random_cloud(100000, {true, false, false}, 6)});
  cases.push_back({"normals_100k", random_cloud(100000, {false, true, false}, 7)});
  cases.push_back({"all_100k", random_cloud(100000, {true, true, true}, 8, 0.01)});
  cases.push_back({"special_values", special_cloud()});
  for (const Format& f : all_formats()) {
    for (const Case& c : cases) {
      SCOPED_TRACE(std::string(f.name) + " / " + c.name);
      const fs::path p = dir / (std::string(c.name) + f.ext);
      f.write(p, c.cloud);
      const PointCloud back = f.read(p);
      EXPECT_TRUE(same_cloud(c.cloud, back));
    }
  }
}

TEST(CloudIo, ReadWriteCloudDispatchOnExtension) {
  TempDir dir;
  const PointCloud c = random_cloud(1000, {true, true, true}, 11);
  for (const std::string name : {"a.pcd", "b.PCD", "c.ply", "d.Ply"}) {
    SCOPED_TRACE(name);
    duet::write_cloud(dir / name, c);
    EXPECT_TRUE(same_cloud(c, duet::read_cloud(dir / name)));
  }
  EXPECT_NE(slurp(dir / "a.pcd").find("DATA binary_compressed\n"), std::string::npos);
  EXPECT_NE(slurp(dir / "c.ply").find("format binary_little_endian 1.0\n"), std::string::npos);
  expect_error([&] { duet::write_cloud(dir / "e.xyz", c); }, ErrorCode::kUnsupported, {"e.xyz", ".xyz"});
  expect_error([&] { (void)duet::read_cloud(dir / "e.las"); }, ErrorCode::kUnsupported, {"e.las"});
}

TEST(CloudIo, WritesExactlyTheAttributesTheCloudHas) {
  TempDir dir;
  duet::write_pcd(dir / "x.pcd", random_cloud(3, {}, 1), PcdEncoding::kAscii);
  EXPECT_NE(slurp(dir / "x.pcd").find("FIELDS x y z\n"), std::string::npos);
  duet::write_pcd(dir / "all.pcd", random_cloud(3, {true, true, true}, 1), PcdEncoding::kBinary);
  EXPECT_NE(slurp(dir / "all.pcd").find("FIELDS x y z rgb normal_x normal_y normal_z curvature\n"), std::string::npos);
  duet::write_ply(dir / "x.ply", random_cloud(3, {true, false, false}, 1), PlyEncoding::kAscii);
  const std::string ply = slurp(dir / "x.ply");
  EXPECT_NE(ply.find("property uchar red\n"), std::string::npos);
  EXPECT_EQ(ply.find("property float nx"), std::string::npos);
  const PointCloud back = duet::read_ply(dir / "x.ply");
  EXPECT_TRUE(back.has_colors());
  EXPECT_FALSE(back.has_normals());
  EXPECT_TRUE(back.curvature.empty());
}

TEST(CloudIo, WriteRejectsInconsistentCloudAndUnwritablePath) {
  TempDir dir;
  PointCloud c = random_cloud(10, {true, false, false}, 1);
  c.colors.pop_back();
  expect_error([&] { duet::write_pcd(dir / "bad.pcd", c); }, ErrorCode::kInvalidArgument, {"bad.pcd", "colors"});
  expect_error([&] { duet::write_ply(dir / "bad.ply", c); }, ErrorCode::kInvalidArgument, {"bad.ply", "colors"});
  EXPECT_FALSE(fs::exists(dir / "bad.pcd"));
  const PointCloud ok = random_cloud(10, {}, 1);
  expect_error([&] { duet::write_pcd(dir / "no_such_dir" / "x.pcd", ok); }, ErrorCode::kIo, {"x.pcd"});
  expect_error([&] { duet::write_ply(dir / "no_such_dir" / "x.ply", ok); }, ErrorCode::kIo, {"x.ply"});
}

TEST(CloudIo, OverwriteReplacesWholeFileAndLeavesNoTemporaries) {
  TempDir dir;
  duet::write_pcd(dir / "m.pcd", random_cloud(5000, {true, true, true}, 1), PcdEncoding::kAscii);
  const PointCloud small = random_cloud(3, {}, 2);
  duet::write_pcd(dir / "m.pcd", small, PcdEncoding::kAscii);
  EXPECT_TRUE(same_cloud(small, duet::read_pcd(dir / "m.pcd")));
  std::size_t files = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir / "")) ++files;
  EXPECT_EQ(files, 1u);
}

TEST(CloudIo, MissingFileIsIoErrorNamingIt) {
  TempDir dir;
  expect_error([&] { (void)duet::read_pcd(dir / "nope.pcd"); }, ErrorCode::kIo, {"nope.pcd"});
  expect_error([&] { (void)duet::read_ply(dir / "nope.ply"); }, ErrorCode::kIo, {"nope.ply"});
  expect_error([&] { (void)duet::read_pcd(dir / ""); }, ErrorCode::kIo, {"directory"});
}

// ------------------------------------------------------------------------------------------
// Hand-made files

std::string f32(float v) { return std::string(reinterpret_cast<const char*>(&v), 4); }
template <class T>
std::string raw(T v) {
  return std::string(reinterpret_cast<const char*>(&v), sizeof(T));
}
template <class T>
std::string raw_be(T v) {
  std::string s = raw(v);
  std::reverse(s.begin(), s.end());
  return s;
}

// A valid LZF stream made of literal runs only (control byte = run length - 1, runs <= 32).
std::string lzf_literals(const std::string& data) {
  std::string out;
  for (std::size_t i = 0; i < data.size(); i += 32) {
    const std::size_t n = std::min<std::size_t>(32, data.size() - i);
    out += static_cast<char>(n - 1);
    out += data.substr(i, n);
  }
  return out;
}

// Fields: x(F4) _(padding, 1 byte x3) intensity(U2) rgba(U4) y(F8) fpfh(F4 x 4) z(I2)
// normal_x normal_y normal_z(F4) curvature(F4).
const char* kOddHeader =
    "# .PCD v0.7 - Point Cloud Data file format\n"
    "VERSION 0.7\n"
    "FIELDS x _ intensity rgba y fpfh z normal_x normal_y normal_z curvature\n"
    "SIZE 4 1 2 4 8 4 2 4 4 4 4\n"
    "TYPE F U U U F F I F F F F\n"
    "COUNT 1 3 1 1 1 4 1 1 1 1 1\n"
    "WIDTH 2\n"
    "HEIGHT 2\n"
    "VIEWPOINT 1 2 3 0 1 0 0\n"
    "POINTS 4\n";

struct OddPoint {
  float x;
  std::uint16_t intensity;
  std::uint32_t rgba;
  double y;
  float fpfh[4];
  std::int16_t z;
  float n[3];
  float curv;
};

std::vector<OddPoint> odd_points() {
  return {{1.5f, 7, 0xff102030u, -2.25, {1, 2, 3, 4}, -3, {0.0f, 0.0f, 1.0f}, 0.01f},
          {std::numeric_limits<float>::quiet_NaN(), 8, 0x00a0b0c0u, 1e10, {5, 6, 7, 8}, 32767, {1.0f, 0.0f, 0.0f}, 0.5f},
          {-0.0f, 9, 0x12345678u, 0.0, {0, 0, 0, 0}, 0, {0.6f, 0.8f, 0.0f}, 0.0f},
          {100.0f, 10, 0xffffffffu, 3.0, {9, 9, 9, 9}, -32768, {0.0f, -1.0f, 0.0f}, 0.25f}};
}

void expect_odd_values(const PointCloud& c) {
  const auto pts = odd_points();
  ASSERT_EQ(c.size(), pts.size());
  ASSERT_TRUE(c.has_colors());
  ASSERT_TRUE(c.has_normals());
  ASSERT_EQ(c.curvature.size(), pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) {
    SCOPED_TRACE(i);
    EXPECT_TRUE(same_float(c.points[i].x(), pts[i].x));
    EXPECT_TRUE(same_float(c.points[i].y(), static_cast<float>(pts[i].y)));
    EXPECT_TRUE(same_float(c.points[i].z(), static_cast<float>(pts[i].z)));
    EXPECT_EQ(c.colors[i].r, (pts[i].rgba >> 16) & 0xff);
    EXPECT_EQ(c.colors[i].g, (pts[i].rgba >> 8) & 0xff);
    EXPECT_EQ(c.colors[i].b, pts[i].rgba & 0xff);
    for (int k = 0; k < 3; ++k) EXPECT_TRUE(same_float(c.normals[i][k], pts[i].n[k]));
    EXPECT_TRUE(same_float(c.curvature[i], pts[i].curv));
  }
}

TEST(CloudIo, PcdSkipsPaddingAndUnknownFieldsOfAnySizeInEveryEncoding) {
  TempDir dir;
  const auto pts = odd_points();
  // binary: array of records
  std::string records;
  for (const OddPoint& p : pts) {
    records += f32(p.x) + std::string("\x01\x02\x03", 3) + raw(p.intensity) + raw(p.rgba) + raw(p.y);
    for (float v : p.fpfh) records += f32(v);
    records += raw(p.z) + f32(p.n[0]) + f32(p.n[1]) + f32(p.n[2]) + f32(p.curv);
  }
  spit(dir / "odd_binary.pcd", std::string(kOddHeader) + "DATA binary\n" + records);
  duet::PcdInfo info;
  const PointCloud b = duet::read_pcd(dir / "odd_binary.pcd", &info);
  expect_odd_values(b);
  EXPECT_EQ(info.width, 2u);
  EXPECT_EQ(info.height, 2u);
  EXPECT_EQ(info.encoding, PcdEncoding::kBinary);
  EXPECT_DOUBLE_EQ(info.viewpoint[0], 1.0);
  EXPECT_DOUBLE_EQ(info.viewpoint[4], 1.0);

  // binary_compressed: planes field by field (PCL's layout), LZF literal runs.
  std::string planes;
  for (const OddPoint& p : pts) planes += f32(p.x);
  for (std::size_t i = 0; i < pts.size(); ++i) planes += std::string("\x01\x02\x03", 3);
  for (const OddPoint& p : pts) planes += raw(p.intensity);
  for (const OddPoint& p : pts) planes += raw(p.rgba);
  for (const OddPoint& p : pts) planes += raw(p.y);
  for (const OddPoint& p : pts) {
    for (float v : p.fpfh) planes += f32(v);
  }
  for (const OddPoint& p : pts) planes += raw(p.z);
  for (int k = 0; k < 3; ++k) {
    for (const OddPoint& p : pts) planes += f32(p.n[k]);
  }
  for (const OddPoint& p : pts) planes += f32(p.curv);
  ASSERT_EQ(planes.size(), records.size());
  const std::string lzf = lzf_literals(planes);
  spit(dir / "odd_compressed.pcd", std::string(kOddHeader) + "DATA binary_compressed\n" +
                                       raw(static_cast<std::uint32_t>(lzf.size())) +
                                       raw(static_cast<std::uint32_t>(planes.size())) + lzf);
  expect_odd_values(duet::read_pcd(dir / "odd_compressed.pcd", &info));
  EXPECT_EQ(info.encoding, PcdEncoding::kBinaryCompressed);

  // ascii, with CRLF line ends, blank lines and extra spaces
  std::string text = std::string(kOddHeader) + "DATA ascii\r\n";
  for (const OddPoint& p : pts) {
    std::ostringstream s;
    s << std::setprecision(9);
    if (std::isnan(p.x)) {
      s << "nan";
    } else {
      s << p.x;
    }
    s << "  1 2 3 " << p.intensity << ' ' << p.rgba << ' ' << std::setprecision(17) << p.y << std::setprecision(9);
    for (float v : p.fpfh) s << ' ' << v;
    s << ' ' << p.z << ' ' << p.n[0] << ' ' << p.n[1] << ' ' << p.n[2] << ' ' << p.curv << " \r\n\n";
    text += s.str();
  }
  spit(dir / "odd_ascii.pcd", text);
  expect_odd_values(duet::read_pcd(dir / "odd_ascii.pcd"));
}

TEST(CloudIo, PcdAsciiPackedRgbAsIntegerOrAsFloat) {
  TempDir dir;
  const std::uint32_t packed = 0x00c08040u;  // r 0xc0, g 0x80, b 0x40
  const float as_float = std::bit_cast<float>(packed);
  std::ostringstream s;
  s << std::setprecision(9) << as_float;
  const std::string header =
      "VERSION .7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\nWIDTH 2\nHEIGHT 1\n"
      "POINTS 2\nDATA ascii\n";
  spit(dir / "rgb.pcd", header + "1 2 3 " + std::to_string(packed) + "\n4 5 6 " + s.str() + "\n");
  const PointCloud c = duet::read_pcd(dir / "rgb.pcd");
  ASSERT_EQ(c.colors.size(), 2u);
  for (const duet::Rgb8& col : c.colors) {
    EXPECT_EQ(col.r, 0xc0);
    EXPECT_EQ(col.g, 0x80);
    EXPECT_EQ(col.b, 0x40);
  }
}

TEST(CloudIo, PcdVersion6HeaderWithoutWidthHeightViewpoint) {
  TempDir dir;
  spit(dir / "old.pcd", "COLUMNS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 2\nDATA ascii\n1 2 3\n4 5 6\n");
  const PointCloud c = duet::read_pcd(dir / "old.pcd");
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c.points[1], Eigen::Vector3f(4, 5, 6));
}

const char* kPlyFaceFirst =
    "ply\r\n"
    "format %s 1.0\r\n"
    "comment a face element before the vertices, with a list, and vertex properties to skip\r\n"
    "obj_info nothing\r\n"
    "element face 2\r\n"
    "property list uchar int vertex_indices\r\n"
    "property float quality\r\n"
    "element vertex 3\r\n"
    "property double x\r\n"
    "property double y\r\n"
    "property float z\r\n"
    "property list ushort float weights\r\n"
    "property uchar red\r\n"
    "property uchar green\r\n"
    "property uchar blue\r\n"
    "property uchar alpha\r\n"
    "property float nx\r\n"
    "property float ny\r\n"
    "property float nz\r\n"
    "property short flags\r\n"
    "element edge 1\r\n"
    "property int vertex1\r\n"
    "property int vertex2\r\n"
    "end_header\r\n";

std::string ply_header(const char* format) {
  char buf[2048];
  std::snprintf(buf, sizeof buf, kPlyFaceFirst, format);
  return buf;
}

void expect_ply_vertices(const PointCloud& c) {
  ASSERT_EQ(c.size(), 3u);
  ASSERT_TRUE(c.has_colors());
  ASSERT_TRUE(c.has_normals());
  EXPECT_TRUE(c.curvature.empty());
  EXPECT_EQ(c.points[0], Eigen::Vector3f(0.5f, -1.25f, 2.0f));
  EXPECT_EQ(c.points[2], Eigen::Vector3f(10.0f, 20.0f, 30.0f));
  EXPECT_EQ(c.colors[1], (duet::Rgb8{1, 2, 3}));
  EXPECT_EQ(c.normals[2], Eigen::Vector3f(0.0f, 0.0f, 1.0f));
}

TEST(CloudIo, PlySkipsElementsListsAndUnknownPropertiesInEveryEncoding) {
  TempDir dir;
  const std::string ascii = ply_header("ascii") +
                            "3 0 1 2 0.5\n4 0 1 2 3 0.25\n"
                            "0.5 -1.25 2 0 255 255 255 255 1 0 0 7\n"
                            "1 2 3 2 0.5 0.5 1 2 3 255 0 1 0 -1\n"
                            "10 20 30 1 9 0 0 0 0 0 0 1 0\n"
                            "0 1\n";
  spit(dir / "a.ply", ascii);
  expect_ply_vertices(duet::read_ply(dir / "a.ply"));

  const auto binary = [](bool be) {
    const auto u8 = [](int v) { return std::string(1, static_cast<char>(v)); };
    const auto put = [&](auto v) { return be ? raw_be(v) : raw(v); };
    std::string d;
    d += u8(3) + put(std::int32_t{0}) + put(std::int32_t{1}) + put(std::int32_t{2}) + put(0.5f);
    d += u8(4) + put(std::int32_t{0}) + put(std::int32_t{1}) + put(std::int32_t{2}) + put(std::int32_t{3}) + put(0.25f);
    const auto vertex = [&](double x, double y, float z, std::uint16_t nw, int r, int g, int b, float nx, float ny,
                            float nz) {
      std::string v = put(x) + put(y) + put(z) + put(nw);
      for (std::uint16_t i = 0; i < nw; ++i) v += put(0.5f);
      v += u8(r) + u8(g) + u8(b) + u8(255) + put(nx) + put(ny) + put(nz) + put(std::int16_t{-1});
      return v;
    };
    d += vertex(0.5, -1.25, 2.0f, 0, 255, 255, 255, 1, 0, 0);
    d += vertex(1, 2, 3, 2, 1, 2, 3, 0, 1, 0);
    d += vertex(10, 20, 30, 1, 9, 0, 0, 0, 0, 1);
    d += put(std::int32_t{0}) + put(std::int32_t{1});
    return d;
  };
  spit(dir / "le.ply", ply_header("binary_little_endian") + binary(false));
  expect_ply_vertices(duet::read_ply(dir / "le.ply"));
  spit(dir / "be.ply", ply_header("binary_big_endian") + binary(true));
  expect_ply_vertices(duet::read_ply(dir / "be.ply"));
}

// ------------------------------------------------------------------------------------------
// Error messages

TEST(CloudIo, PcdHeaderErrorsNameFileLineAndProblem) {
  TempDir dir;
  const fs::path p = dir / "office.pcd";
  const auto with = [&](const std::string& text) {
    spit(p, text);
    return [p] { (void)duet::read_pcd(p); };
  };
  expect_error(with("# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F\nCOUNT 1 1 1 1\nWIDTH 1\nHEIGHT 1\n"
                    "POINTS 1\nDATA ascii\n1 2 3 4\n"),
               ErrorCode::kParse, {"office.pcd", "header line 5: TYPE has 3 entries, FIELDS has 4"});
  expect_error(with("FIELDS x y z\nSIZE 4 4 3\nTYPE F F F\nPOINTS 1\nDATA ascii\n1 2 3\n"), ErrorCode::kParse,
               {"header line 2", "SIZE entry 3"});
  expect_error(with("FIELDS x y z\nSIZE 4 4 2\nTYPE F F F\nPOINTS 1\nDATA ascii\n1 2 3\n"), ErrorCode::kParse,
               {"TYPE F with SIZE 2"});
  expect_error(with("FIELDS x y w\nSIZE 4 4 4\nTYPE F F F\nPOINTS 1\nDATA ascii\n1 2 3\n"), ErrorCode::kParse,
               {"lacks x, y or z"});
  expect_error(with("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 640\nHEIGHT 480\nPOINTS 1200\nDATA ascii\n"),
               ErrorCode::kParse, {"header line 6", "640 x 480 = 307200, POINTS is 1200"});
  expect_error(with("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 1\nDATA zip\n"), ErrorCode::kParse,
               {"header line 5", "DATA is 'zip'"});
  expect_error(with("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nBOGUS 1\nPOINTS 1\nDATA ascii\n"), ErrorCode::kParse,
               {"header line 4", "unknown keyword 'BOGUS'"});
  expect_error(with("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 1\n"), ErrorCode::kParse, {"no DATA line"});
  expect_error(with(""), ErrorCode::kParse, {"empty file"});
  expect_error(with("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 3\nDATA ascii\n1 2 3\n4 5\n"), ErrorCode::kParse,
               {"line 7", "expected 3 values, got 2"});
  expect_error(with("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 2\nDATA ascii\n1 2 zz\n"), ErrorCode::kParse,
               {"line 6", "'zz' is not a number"});
  expect_error(with("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 3\nDATA ascii\n1 2 3\n"), ErrorCode::kParse,
               {"data truncated: expected 3 points, got 1"});
}

std::string xyz_header(std::uint64_t points, const char* data, std::uint64_t width = 0) {
  const std::uint64_t w = width == 0 ? points : width;
  return "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH " + std::to_string(w) + "\nHEIGHT " +
         std::to_string(points / w) + "\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " + std::to_string(points) + "\nDATA " + data +
         "\n";
}

TEST(CloudIo, HugeDeclaredSizesAreErrorsNotAllocations) {
  TempDir dir;
  const fs::path p = dir / "x.pcd";
  spit(p, xyz_header(307200, "binary", 640) + std::string(1200 * 12, '\0'));
  expect_error([&] { (void)duet::read_pcd(p); }, ErrorCode::kParse,
               {"x.pcd", "data truncated: expected 307200 points, got 1200"});
  spit(p, xyz_header(4000000000000ull, "binary") + std::string(12, '\0'));
  expect_error([&] { (void)duet::read_pcd(p); }, ErrorCode::kParse, {"data truncated"});
  spit(p, xyz_header(4000000000000ull, "ascii") + "1 2 3\n");
  expect_error([&] { (void)duet::read_pcd(p); }, ErrorCode::kParse, {"data truncated"});
  // binary_compressed: sizes are checked against the file and against POINTS.
  spit(p, xyz_header(10, "binary_compressed") + raw(std::uint32_t{99999}) + raw(std::uint32_t{120}) + "abc");
  expect_error([&] { (void)duet::read_pcd(p); }, ErrorCode::kParse, {"compressed size 99999 exceeds file size"});
  spit(p, xyz_header(10, "binary_compressed") + raw(std::uint32_t{3}) + raw(std::uint32_t{4000000000u}) + "abc");
  expect_error([&] { (void)duet::read_pcd(p); }, ErrorCode::kParse, {"uncompressed size 4000000000 does not match"});
  spit(p, xyz_header(300000000, "binary_compressed") + raw(std::uint32_t{3}) + raw(std::uint32_t{3600000000u}) + "abc");
  expect_error([&] { (void)duet::read_pcd(p); }, ErrorCode::kParse, {"cannot come from 3 LZF bytes"});
  spit(p, xyz_header(400000000, "binary_compressed") + raw(std::uint32_t{3}) + raw(std::uint32_t{0}) + "abc");
  expect_error([&] { (void)duet::read_pcd(p); }, ErrorCode::kParse, {"4 GiB"});
  spit(p, xyz_header(2, "binary_compressed") + raw(std::uint32_t{3}) + raw(std::uint32_t{24}) + "\x05" "ab");
  expect_error([&] { (void)duet::read_pcd(p); }, ErrorCode::kParse, {"corrupt LZF data"});
  spit(p, "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1073741825\nPOINTS 1\nDATA binary\n");
  expect_error([&] { (void)duet::read_pcd(p); }, ErrorCode::kParse, {"COUNT"});

  const fs::path q = dir / "x.ply";
  spit(q, "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000000000000\nproperty float x\n"
          "property float y\nproperty float z\nend_header\n" + std::string(24, '\0'));
  expect_error([&] { (void)duet::read_ply(q); }, ErrorCode::kParse, {"x.ply", "data truncated: expected 1000000000000000000 vertex elements, got 2"});
  spit(q, "ply\nformat ascii 1.0\nelement vertex 1000000000000000000\nproperty float x\n"
          "property float y\nproperty float z\nend_header\n1 2 3\n");
  expect_error([&] { (void)duet::read_ply(q); }, ErrorCode::kParse, {"data truncated", "got 1"});
  spit(q, "ply\nformat binary_little_endian 1.0\nelement face 1\nproperty list uint float v\nelement vertex 1\n"
          "property float x\nproperty float y\nproperty float z\nend_header\n" + raw(std::uint32_t{4000000000u}) +
              std::string(12, '\0'));
  expect_error([&] { (void)duet::read_ply(q); }, ErrorCode::kParse, {"data truncated", "face"});
}

TEST(CloudIo, PlyHeaderErrors) {
  TempDir dir;
  const fs::path q = dir / "m.ply";
  const auto with = [&](const std::string& text) {
    spit(q, text);
    return [q] { (void)duet::read_ply(q); };
  };
  expect_error(with("PLY\n"), ErrorCode::kParse, {"m.ply", "not a PLY file"});
  expect_error(with("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"),
               ErrorCode::kParse, {"no end_header"});
  expect_error(with("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n1 2\n"),
               ErrorCode::kParse, {"header line 3", "lacks property x, y or z"});
  expect_error(with("ply\nformat ascii 1.0\nelement vertex 1\nproperty real x\nend_header\n"), ErrorCode::kParse,
               {"header line 4", "unknown type 'real'"});
  expect_error(with("ply\nformat ascii 1.0\nelement face 1\nproperty list float int v\nend_header\n"),
               ErrorCode::kParse, {"header line 4", "not an integer type"});
  expect_error(with("ply\nformat ascii 1.0\nelement face 0\nproperty float q\nend_header\n"), ErrorCode::kParse,
               {"no 'vertex' element"});
  expect_error(with("ply\nformat ebcdic 1.0\nend_header\n"), ErrorCode::kParse, {"header line 2", "'ebcdic'"});
  expect_error(with("ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
                    "end_header\n1 2 3\n4 five 6\n"),
               ErrorCode::kParse, {"line 9", "'five' is not a number"});
  expect_error(with("ply\nformat ascii 1.0\nelement face 1\nproperty list uchar int v\nelement vertex 1\n"
                    "property float x\nproperty float y\nproperty float z\nend_header\n-2 1 2\n1 2 3\n"),
               ErrorCode::kParse, {"list 'v' has count -2"});
}

// ------------------------------------------------------------------------------------------
// Corrupt files: every truncation and random byte flips.

TEST(CloudIo, EveryTruncationIsAnErrorOrTheSameCloud) {
  TempDir dir;
  const PointCloud c = random_cloud(12, {true, true, true}, 21, 0.2);
  for (const Format& f : all_formats()) {
    SCOPED_TRACE(f.name);
    const fs::path full = dir / (std::string("full") + f.ext);
    f.write(full, c);
    const std::string bytes = slurp(full);
    const fs::path cut = dir / (std::string("cut") + f.ext);
    const bool text = std::string(f.name).find("ascii") != std::string::npos;
    std::size_t reads = 0;
    for (std::size_t len = 0; len < bytes.size(); ++len) {
      spit(cut, bytes.substr(0, len));
      PointCloud back;
      if (read_survives(f, cut, &back)) {
        ++reads;
        // Only a text file cut inside its last value (or its final newline) may still read:
        // every point is there, and all but the last are exact.
        EXPECT_TRUE(text) << "binary prefix of " << len << " bytes read";
        ASSERT_EQ(back.size(), c.size());
        PointCloud a = c, b = back;
        for (PointCloud* x : {&a, &b}) {
          x->points.pop_back();
          x->colors.pop_back();
          x->normals.pop_back();
          x->curvature.pop_back();
        }
        EXPECT_TRUE(same_cloud(a, b)) << "prefix of " << len << " bytes";
      }
    }
    EXPECT_LE(reads, text ? 16u : 0u);
  }
}

TEST(CloudIo, RandomByteFlipsNeverCrash) {
  TempDir dir;
  const PointCloud c = random_cloud(40, {true, true, true}, 31, 0.1);
  std::mt19937 rng(12345);
  for (const Format& f : all_formats()) {
    SCOPED_TRACE(f.name);
    const fs::path full = dir / (std::string("full") + f.ext);
    f.write(full, c);
    const std::string bytes = slurp(full);
    const fs::path bad = dir / (std::string("bad") + f.ext);
    std::uniform_int_distribution<std::size_t> where(0, bytes.size() - 1);
    std::uniform_int_distribution<int> what(0, 255), how_many(1, 8);
    int read_ok = 0;
    for (int iter = 0; iter < 1500; ++iter) {
      std::string b = bytes;
      const int n = how_many(rng);
      for (int k = 0; k < n; ++k) b[where(rng)] = static_cast<char>(what(rng));
      spit(bad, b);
      read_ok += read_survives(f, bad, nullptr) ? 1 : 0;
    }
    // Flips inside binary payloads only change values; the count is just informative.
    RecordProperty(std::string(f.name) + "_flips_read", read_ok);
  }
}

TEST(CloudIo, CompressedFlipsInsideLzfStream) {
  // Flips targeted at the compressed block of a real-sized cloud (the decoder's bounds checks).
  TempDir dir;
  const PointCloud c = random_cloud(2000, {true, false, false}, 41);
  const fs::path full = dir / "full.pcd";
  duet::write_pcd(full, c, PcdEncoding::kBinaryCompressed);
  const std::string bytes = slurp(full);
  const std::size_t data_start = bytes.find("DATA binary_compressed\n") + 23 + 8;
  ASSERT_LT(data_start, bytes.size());
  std::mt19937 rng(777);
  std::uniform_int_distribution<std::size_t> where(data_start, bytes.size() - 1);
  std::uniform_int_distribution<int> what(0, 255);
  const Format f = all_formats()[2];
  for (int iter = 0; iter < 300; ++iter) {
    std::string b = bytes;
    for (int k = 0; k < 3; ++k) b[where(rng)] = static_cast<char>(what(rng));
    spit(dir / "bad.pcd", b);
    (void)read_survives(f, dir / "bad.pcd", nullptr);
  }
}

// ------------------------------------------------------------------------------------------
// Real PCL files, compared with PCL's own reader.

bool have_pcl_data() { return fs::exists(kPclData / "office1.pcd"); }

#define DUET_SKIP_WITHOUT_DATA()                                                                       \
  if (!have_pcl_data()) GTEST_SKIP() << "real data not found at " << kPclData << " (../shared/data is absent)"

TEST(CloudIoRealData, Office1CompressedOrganizedXyzRgb) {
  DUET_SKIP_WITHOUT_DATA();
  duet::PcdInfo info;
  const PointCloud c = duet::read_pcd(kPclData / "office1.pcd", &info);
  EXPECT_EQ(info.encoding, PcdEncoding::kBinaryCompressed);
  EXPECT_EQ(info.width, 640u);
  EXPECT_EQ(info.height, 480u);
  ASSERT_EQ(c.size(), 307200u);
  EXPECT_TRUE(c.has_colors());
  EXPECT_FALSE(c.has_normals());
  std::size_t nan = 0;
  float zmin = 1e9f, zmax = -1e9f;
  for (const auto& p : c.points) {
    if (!duet::is_finite(p)) {
      ++nan;
      continue;
    }
    zmin = std::min(zmin, p.z());
    zmax = std::max(zmax, p.z());
  }
  EXPECT_GT(nan, 0u) << "an organized Kinect cloud keeps its NaN points";
  EXPECT_LT(nan, c.size() / 2);
  EXPECT_NEAR(zmin, 1.8f, 0.2f);
  EXPECT_NEAR(zmax, 5.4f, 0.3f);
}

TEST(CloudIoRealData, AllFilesReadAndRoundTrip) {
  DUET_SKIP_WITHOUT_DATA();
  TempDir dir;
  struct Expect {
    const char* file;
    std::size_t points;
    bool colors, normals;
    PcdEncoding encoding;
  };
  for (const Expect& e : {Expect{"office1.pcd", 307200, true, false, PcdEncoding::kBinaryCompressed},
                          Expect{"table_scene_mug_stereo_textured.pcd", 307200, true, false, PcdEncoding::kBinaryCompressed},
                          Expect{"bun0.pcd", 397, false, true, PcdEncoding::kAscii},
                          Expect{"sac_plane_test.pcd", 3283, false, true, PcdEncoding::kAscii}}) {
    SCOPED_TRACE(e.file);
    duet::PcdInfo info;
    const PointCloud c = duet::read_pcd(kPclData / e.file, &info);
    EXPECT_EQ(c.size(), e.points);
    EXPECT_EQ(c.has_colors(), e.colors);
    EXPECT_EQ(c.has_normals(), e.normals);
    EXPECT_EQ(c.curvature.empty(), !e.normals);
    EXPECT_EQ(info.encoding, e.encoding);
    for (const Format& f : all_formats()) {
      SCOPED_TRACE(f.name);
      const fs::path p = dir / (std::string("copy") + f.ext);
      f.write(p, c);
      EXPECT_TRUE(same_cloud(c, f.read(p)));
    }
  }
}

#ifdef DUET_HAVE_PCL

// Compares our cloud with the same file read by PCL into PointXYZRGBNormal (fields absent
// from the file stay at PCL's defaults and are not compared).
template <class PclPoint>
void expect_same_as_pcl(const PointCloud& ours, const pcl::PointCloud<PclPoint>& theirs) {
  ASSERT_EQ(ours.size(), theirs.size());
  for (std::size_t i = 0; i < ours.size(); ++i) {
    const PclPoint& q = theirs[i];
    ASSERT_TRUE(same_float(ours.points[i].x(), q.x) && same_float(ours.points[i].y(), q.y) &&
                same_float(ours.points[i].z(), q.z))
        << "point " << i << ": " << ours.points[i].transpose() << " vs " << q.x << " " << q.y << " " << q.z;
    if constexpr (requires { q.rgba; }) {
      if (ours.has_colors()) {
        ASSERT_EQ(ours.colors[i], (duet::Rgb8{q.r, q.g, q.b})) << "colour " << i;
      }
    }
    if constexpr (requires { q.normal_x; }) {
      if (ours.has_normals()) {
        ASSERT_TRUE(same_float(ours.normals[i].x(), q.normal_x) && same_float(ours.normals[i].y(), q.normal_y) &&
                    same_float(ours.normals[i].z(), q.normal_z))
            << "normal " << i;
      }
      if (!ours.curvature.empty()) {
        ASSERT_TRUE(same_float(ours.curvature[i], q.curvature)) << "curvature " << i;
      }
    }
  }
}

TEST(CloudIoPcl, RealFilesMatchPclFieldByField) {
  DUET_SKIP_WITHOUT_DATA();
  {
    pcl::PointCloud<pcl::PointXYZRGB> theirs;
    ASSERT_EQ(pcl::io::loadPCDFile(kPclData.string() + "/office1.pcd", theirs), 0);
    EXPECT_EQ(theirs.width, 640u);
    EXPECT_EQ(theirs.height, 480u);
    expect_same_as_pcl(duet::read_pcd(kPclData / "office1.pcd"), theirs);
  }
  {
    pcl::PointCloud<pcl::PointXYZRGBA> theirs;
    ASSERT_EQ(pcl::io::loadPCDFile(kPclData.string() + "/table_scene_mug_stereo_textured.pcd", theirs), 0);
    expect_same_as_pcl(duet::read_pcd(kPclData / "table_scene_mug_stereo_textured.pcd"), theirs);
  }
  for (const char* name : {"bun0.pcd", "sac_plane_test.pcd"}) {
    SCOPED_TRACE(name);
    pcl::PointCloud<pcl::PointNormal> theirs;
    ASSERT_EQ(pcl::io::loadPCDFile(kPclData.string() + "/" + name, theirs), 0);
    expect_same_as_pcl(duet::read_pcd(kPclData / name), theirs);
  }
  // The raw blob too: same field list as PCL sees it.
  pcl::PCLPointCloud2 blob;
  ASSERT_EQ(pcl::io::loadPCDFile(kPclData.string() + "/table_scene_mug_stereo_textured.pcd", blob), 0);
  ASSERT_EQ(blob.fields.size(), 4u);
  EXPECT_EQ(blob.fields[3].name, "rgba");
}

TEST(CloudIoPcl, OurFilesLoadInPclWithTheSameValues) {
  TempDir dir;
  // PCL's ascii PLY parser does not take "nan": the PLY files get finite values only.
  const PointCloud with_nan = random_cloud(20000, {true, true, true}, 51, 0.05);
  const PointCloud finite = random_cloud(20000, {true, true, true}, 52);
  for (const PcdEncoding enc : {PcdEncoding::kAscii, PcdEncoding::kBinary, PcdEncoding::kBinaryCompressed}) {
    SCOPED_TRACE(static_cast<int>(enc));
    const fs::path p = dir / "ours.pcd";
    duet::write_pcd(p, with_nan, enc);
    pcl::PointCloud<pcl::PointXYZRGBNormal> theirs;
    ASSERT_EQ(pcl::io::loadPCDFile(p.string(), theirs), 0);
    expect_same_as_pcl(with_nan, theirs);
    // xyz only
    duet::write_pcd(p, random_cloud(100, {}, 53, 0.1), enc);
    pcl::PointCloud<pcl::PointXYZ> xyz;
    ASSERT_EQ(pcl::io::loadPCDFile(p.string(), xyz), 0);
    expect_same_as_pcl(random_cloud(100, {}, 53, 0.1), xyz);
  }
  for (const PlyEncoding enc : {PlyEncoding::kAscii, PlyEncoding::kBinaryLittleEndian}) {
    SCOPED_TRACE(static_cast<int>(enc));
    const fs::path p = dir / "ours.ply";
    duet::write_ply(p, finite, enc);
    pcl::PointCloud<pcl::PointXYZRGBNormal> theirs;
    ASSERT_EQ(pcl::io::loadPLYFile(p.string(), theirs), 0);
    expect_same_as_pcl(finite, theirs);
  }
}

TEST(CloudIoPcl, PclFilesReadByUs) {
  TempDir dir;
  pcl::console::setVerbosityLevel(pcl::console::L_ERROR);  // PCL warns about its own camera element
  pcl::PointCloud<pcl::PointXYZRGBNormal> theirs;
  std::mt19937 rng(61);
  std::uniform_real_distribution<float> u(-10.0f, 10.0f);
  for (int i = 0; i < 5000; ++i) {
    pcl::PointXYZRGBNormal q;
    q.x = u(rng);
    q.y = u(rng);
    q.z = i % 50 == 0 ? std::numeric_limits<float>::quiet_NaN() : u(rng);
    q.r = static_cast<std::uint8_t>(i);
    q.g = static_cast<std::uint8_t>(i * 7);
    q.b = static_cast<std::uint8_t>(i * 13);
    q.normal_x = u(rng);
    q.normal_y = u(rng);
    q.normal_z = u(rng);
    q.curvature = u(rng);
    theirs.push_back(q);
  }
  pcl::PCDWriter writer;
  const std::string base = (dir / "pcl").string();
  ASSERT_EQ(writer.writeASCII(base + "_ascii.pcd", theirs), 0);
  ASSERT_EQ(writer.writeBinary(base + "_binary.pcd", theirs), 0);
  ASSERT_EQ(writer.writeBinaryCompressed(base + "_compressed.pcd", theirs), 0);
  for (const char* suffix : {"_ascii.pcd", "_binary.pcd", "_compressed.pcd"}) {
    SCOPED_TRACE(suffix);
    const PointCloud ours = duet::read_pcd(base + suffix);
    // PCL's ascii writer keeps 8 digits, not always enough for a float: compare with what PCL
    // itself reads back, and the binary files with the original too.
    pcl::PointCloud<pcl::PointXYZRGBNormal> reread;
    ASSERT_EQ(pcl::io::loadPCDFile(base + suffix, reread), 0);
    expect_same_as_pcl(ours, reread);
    if (std::string(suffix) != "_ascii.pcd") expect_same_as_pcl(ours, theirs);
  }
  theirs.erase(std::remove_if(theirs.begin(), theirs.end(), [](const auto& q) { return std::isnan(q.z); }), theirs.end());
  pcl::PLYWriter ply;
  ASSERT_EQ(ply.write(base + "_binary.ply", theirs, true), 0);
  ASSERT_EQ(ply.write(base + "_ascii.ply", theirs, false), 0);
  for (const char* suffix : {"_ascii.ply", "_binary.ply"}) {
    SCOPED_TRACE(suffix);
    const PointCloud ours = duet::read_ply(base + suffix);
    EXPECT_TRUE(ours.has_colors());
    EXPECT_TRUE(ours.has_normals());
    pcl::PointCloud<pcl::PointXYZRGBNormal> reread;
    ASSERT_EQ(pcl::io::loadPLYFile(base + suffix, reread), 0);
    expect_same_as_pcl(ours, reread);
    if (std::string(suffix) != "_ascii.ply") expect_same_as_pcl(ours, theirs);
  }
}

#endif  // DUET_HAVE_PCL

}  // namespace
