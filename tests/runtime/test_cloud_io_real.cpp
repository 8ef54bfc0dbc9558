// Point cloud files (3/3): the real PCL test files read and round-tripped, compared field by field
// with PCL's own reader, and our files loaded by PCL with the same values.
#include "cloud_io_test_util.hpp"

#include <gtest/gtest.h>

#ifdef DUET_HAVE_PCL
#include <pcl/PCLPointCloud2.h>
#include <pcl/console/print.h>
#include <pcl/conversions.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_types.h>
#endif

namespace test_cloud_io_real {

using namespace duet_test::cloud;

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

}  // namespace test_cloud_io_real
