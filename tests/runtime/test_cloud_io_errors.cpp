// Point cloud files (2/3): header errors that name the file, the line and the problem; huge declared
// sizes that are errors, not allocations; every truncation and random byte flips (also inside an LZF
// stream) give a duet::Error, never a crash.
#include "cloud_io_test_util.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace test_cloud_io_errors {

using namespace duet_test::cloud;

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

}  // namespace test_cloud_io_errors
