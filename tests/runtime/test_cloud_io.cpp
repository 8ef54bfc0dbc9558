// Point cloud files (1/3): round trips of every encoding and every attribute set, dispatch on the
// extension, atomic overwrites, and hand-made files with unusual fields (padding, unknown fields of
// any size, packed colour as integer or float, version 0.6 headers, PLY lists and extra elements).
#include "cloud_io_test_util.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <iomanip>
#include <sstream>
#include <string>
#include <vector>

namespace test_cloud_io {

using namespace duet_test::cloud;

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

}  // namespace test_cloud_io
