// Occupancy grid files: the real Willow Garage map read, written and read back; map_server
// semantics (flip, origin, negate, thresholds, trinary/scale/raw, P2/P5/PNG) against a plain
// reference; errors naming the file and key; corrupt images; the PNG picture and its overlays.
#include <duet/kernels/error.hpp>
#include <duet/runtime/io/grid_io.hpp>

#include <gtest/gtest.h>

#include "runtime_test_util.hpp"
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>

namespace fs = std::filesystem;
using duet::ErrorCode;
using duet::OccupancyGrid;

namespace {

const fs::path kMaps = fs::path(DUET_DATA_DIR) / "maps";
const fs::path kWillow = kMaps / "willow-2010-02-18-0.10.yaml";
constexpr float kOcc = 3.5f, kFree = -2.0f;

using duet_test::slurp;
using duet_test::spit;
using duet_test::TempDir;

// Reference PGM P5 reader for well-formed 8-bit files (header tokens and comments).
struct Pgm {
  int w = 0, h = 0;
  std::vector<std::uint8_t> px;
};
Pgm reference_pgm(const fs::path& p) {
  const std::string s = slurp(p);
  std::size_t pos = 2;
  std::vector<long> nums;
  while (nums.size() < 3) {
    while (std::isspace(static_cast<unsigned char>(s[pos]))) ++pos;
    if (s[pos] == '#') {
      while (s[pos] != '\n') ++pos;
      continue;
    }
    std::size_t end = pos;
    while (std::isdigit(static_cast<unsigned char>(s[end]))) ++end;
    nums.push_back(std::stol(s.substr(pos, end - pos)));
    pos = end;
  }
  ++pos;
  Pgm out{static_cast<int>(nums[0]), static_cast<int>(nums[1]), {}};
  out.px.assign(s.begin() + static_cast<std::ptrdiff_t>(pos), s.end());
  return out;
}

// map_server trinary: -1 unknown, 0 free, 100 occupied, from an 8-bit value.
int reference_trinary(int v, bool negate = false, double occ_th = 0.65, double free_th = 0.196) {
  const double c = negate ? 255.0 - v : v;
  const double occ = (255.0 - c) / 255.0;
  if (occ > occ_th) return 100;
  if (occ < free_th) return 0;
  return -1;
}

int trinary_of_cell(float l) {
  if (std::isnan(l)) return -1;
  if (l == kOcc) return 100;
  if (l == kFree) return 0;
  return 50;  // anything else: wrong for a trinary map
}

bool same_cells(const OccupancyGrid& a, const OccupancyGrid& b) {
  if (a.width() != b.width() || a.height() != b.height()) return false;
  for (std::size_t i = 0; i < a.cell_count(); ++i) {
    const float x = a.logodds()[i], y = b.logodds()[i];
    if (std::isnan(x) != std::isnan(y) || (!std::isnan(x) && x != y)) return false;
  }
  return true;
}

using duet_test::expect_error;

// A small grid with every kind of cell: unknown, free, occupied, and in between.
OccupancyGrid pattern_grid() {
  OccupancyGrid g(0.05f, Eigen::Vector2f(-3.25f, 1.5f), 7, 5);
  auto c = g.logodds();
  for (int iy = 0; iy < 5; ++iy) {
    for (int ix = 0; ix < 7; ++ix) {
      const int k = (ix + 2 * iy) % 5;
      c[g.index(ix, iy)] = k == 0 ? OccupancyGrid::kUnknown : k == 1 ? kFree : k == 2 ? kOcc : k == 3 ? 0.0f : -0.5f;
    }
  }
  c[g.index(0, 0)] = kOcc;  // lower-left corner occupied: the PGM's bottom-left pixel
  c[g.index(6, 4)] = kFree; // upper-right corner free: the PGM's top-right pixel
  return g;
}

// ------------------------------------------------------------------------------------------

TEST(GridIoRealData, WillowMapReadWriteReadBack) {
  if (!fs::exists(kWillow)) GTEST_SKIP() << "real data not found at " << kWillow << " (../shared/data is absent)";
  TempDir dir;
  const OccupancyGrid g = duet::read_map_server(kWillow);
  ASSERT_EQ(g.width(), 566);
  ASSERT_EQ(g.height(), 608);
  EXPECT_FLOAT_EQ(g.resolution(), 0.1f);
  EXPECT_EQ(g.origin(), Eigen::Vector2f(0.0f, 0.0f));

  // Cell by cell against map_server's rule applied to the raw image (row 0 = highest y).
  const Pgm pgm = reference_pgm(kMaps / "willow-2010-02-18-0.10.pgm");
  ASSERT_EQ(pgm.w, 566);
  ASSERT_EQ(pgm.h, 608);
  std::size_t occupied = 0, free = 0, unknown = 0;
  for (int row = 0; row < pgm.h; ++row) {
    for (int ix = 0; ix < pgm.w; ++ix) {
      const int expected = reference_trinary(pgm.px[static_cast<std::size_t>(row) * 566 + static_cast<std::size_t>(ix)]);
      ASSERT_EQ(trinary_of_cell(g.at(ix, pgm.h - 1 - row)), expected) << "cell " << ix << ", " << pgm.h - 1 - row;
      (expected == 100 ? occupied : expected == 0 ? free : unknown)++;
    }
  }
  EXPECT_GT(occupied, 300u);
  EXPECT_GT(free, 50000u);
  EXPECT_GT(unknown, 100000u);

  const fs::path out = dir / "willow_copy.yaml";
  duet::write_map_server(g, out);
  ASSERT_TRUE(fs::exists(dir / "willow_copy.pgm"));
  const Pgm written = reference_pgm(dir / "willow_copy.pgm");
  ASSERT_EQ(written.w, 566);
  ASSERT_EQ(written.h, 608);
  ASSERT_EQ(written.px.size(), pgm.px.size());
  for (std::size_t i = 0; i < pgm.px.size(); ++i) {
    const int t = reference_trinary(pgm.px[i]);
    ASSERT_EQ(written.px[i], t == 100 ? 0 : t == 0 ? 254 : 205) << "pixel " << i;
  }
  const OccupancyGrid back = duet::read_map_server(out);
  EXPECT_TRUE(same_cells(g, back));
  EXPECT_EQ(back.resolution(), g.resolution());
  EXPECT_EQ(back.origin(), g.origin());
}

TEST(GridIo, WriteFlipsRowsAndWritesTheYaml) {
  TempDir dir;
  const OccupancyGrid g = pattern_grid();
  duet::write_map_server(g, dir / "m.yaml");
  const std::string yaml = slurp(dir / "m.yaml");
  EXPECT_NE(yaml.find("image: m.pgm\n"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("resolution: 0.05\n"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("origin: [-3.25, 1.5, 0.0]\n"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("negate: 0\n"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("occupied_thresh: 0.65\n"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("free_thresh: 0.196\n"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("mode: trinary\n"), std::string::npos) << yaml;
  const std::string pgm_bytes = slurp(dir / "m.pgm");
  EXPECT_EQ(pgm_bytes.rfind("P5\n", 0), 0u);
  const Pgm pgm = reference_pgm(dir / "m.pgm");
  ASSERT_EQ(pgm.w, 7);
  ASSERT_EQ(pgm.h, 5);
  EXPECT_EQ(pgm.px[4 * 7 + 0], 0) << "cell (0, 0) is the bottom-left pixel";
  EXPECT_EQ(pgm.px[0 * 7 + 6], 254) << "cell (6, 4) is the top-right pixel";
  for (int iy = 0; iy < 5; ++iy) {
    for (int ix = 0; ix < 7; ++ix) {
      const float l = g.at(ix, iy);
      const int v = pgm.px[static_cast<std::size_t>(4 - iy) * 7 + static_cast<std::size_t>(ix)];
      // Classified with MapServerOptions' classify_*_p (0.65, 0.45): log-odds 0 (p 0.5) is
      // neither occupied nor free, -0.5 (p 0.38) is free.
      const int expected = std::isnan(l) ? 205 : l >= 1.0f ? 0 : l <= -0.2f ? 254 : 205;
      EXPECT_EQ(v, expected) << ix << ", " << iy;
    }
  }
  const OccupancyGrid back = duet::read_map_server(dir / "m.yaml");
  EXPECT_EQ(back.resolution(), 0.05f);
  EXPECT_EQ(back.origin(), Eigen::Vector2f(-3.25f, 1.5f));
  for (int iy = 0; iy < 5; ++iy) {
    for (int ix = 0; ix < 7; ++ix) {
      const float l = g.at(ix, iy);
      const int expected = std::isnan(l) ? -1 : l >= 1.0f ? 100 : l <= -0.2f ? 0 : -1;
      EXPECT_EQ(trinary_of_cell(back.at(ix, iy)), expected) << ix << ", " << iy;
    }
  }
  // Writing over an existing map replaces it; no temporary files stay behind.
  duet::write_map_server(back, dir / "m.yaml");
  std::size_t files = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir / "")) ++files;
  EXPECT_EQ(files, 2u);
}

TEST(GridIo, ImageNamesThatNeedYamlQuoting) {
  TempDir dir;
  const OccupancyGrid g = pattern_grid();
  for (const std::string stem : {"my map: v2", "#1 \"quoted\"", "-dash", "tab\there"}) {
    SCOPED_TRACE(stem);
    duet::write_map_server(g, dir / (stem + ".yaml"));
    EXPECT_TRUE(fs::exists(dir / (stem + ".pgm")));
    const OccupancyGrid back = duet::read_map_server(dir / (stem + ".yaml"));
    EXPECT_EQ(back.width(), 7);
    EXPECT_EQ(trinary_of_cell(back.at(0, 0)), 100);
  }
}

TEST(GridIo, OriginAndResolutionRoundTripExactly) {
  TempDir dir;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> o(-1000.0f, 1000.0f), r(0.001f, 2.0f);
  for (int i = 0; i < 50; ++i) {
    OccupancyGrid g(r(rng), Eigen::Vector2f(o(rng), o(rng)), 3, 2);
    g.logodds()[1] = kOcc;
    duet::write_map_server(g, dir / "r.yaml");
    const OccupancyGrid back = duet::read_map_server(dir / "r.yaml");
    ASSERT_EQ(back.resolution(), g.resolution());
    ASSERT_EQ(back.origin(), g.origin());
    ASSERT_TRUE(same_cells(g, back));
  }
}

TEST(GridIo, ReadsP2NegateScaleRawAndAbsoluteImagePath) {
  TempDir dir;
  // 3x2 P2 with comments; row 0 is the top (y = 1).
  spit(dir / "a.pgm", "P2\n# a comment\n3 2\n# another\n255\n0 100 205\n254 255 30\n");
  spit(dir / "a.yaml", "image: a.pgm\nresolution: 0.5\norigin: [1.0, -2.0, 0.0]\nnegate: 0\n"
                       "occupied_thresh: 0.65\nfree_thresh: 0.196\n");
  OccupancyGrid g = duet::read_map_server(dir / "a.yaml");
  ASSERT_EQ(g.width(), 3);
  ASSERT_EQ(g.height(), 2);
  EXPECT_EQ(g.origin(), Eigen::Vector2f(1.0f, -2.0f));
  const int rows[2][3] = {{0, 100, 205}, {254, 255, 30}};
  for (int row = 0; row < 2; ++row) {
    for (int ix = 0; ix < 3; ++ix) {
      EXPECT_EQ(trinary_of_cell(g.at(ix, 1 - row)), reference_trinary(rows[row][ix])) << row << ", " << ix;
    }
  }
  // negate: dark is free.
  spit(dir / "n.yaml", "image: a.pgm\nresolution: 0.5\norigin: [0, 0, 0]\nnegate: 1\n");
  g = duet::read_map_server(dir / "n.yaml");
  for (int row = 0; row < 2; ++row) {
    for (int ix = 0; ix < 3; ++ix) {
      EXPECT_EQ(trinary_of_cell(g.at(ix, 1 - row)), reference_trinary(rows[row][ix], true)) << row << ", " << ix;
    }
  }
  // scale: in-between values get log-odds in between (map_server: 1 + 98 * ratio percent).
  spit(dir / "s.yaml", "image: a.pgm\nresolution: 0.5\norigin: [0, 0, 0]\nmode: scale\n");
  g = duet::read_map_server(dir / "s.yaml");
  EXPECT_EQ(g.at(0, 1), kOcc);
  EXPECT_EQ(g.at(0, 0), kFree);
  const double occ = 155.0 / 255.0, ratio = (occ - 0.196) / (0.65 - 0.196);
  const double p = (1.0 + 98.0 * ratio) / 100.0;
  EXPECT_NEAR(g.at(1, 1), std::log(p / (1.0 - p)), 1e-5);  // value 100
  // raw: 0..100 percent, above unknown.
  spit(dir / "r.yaml", "image: a.pgm\nresolution: 0.5\norigin: [0, 0, 0]\nmode: raw\n");
  g = duet::read_map_server(dir / "r.yaml");
  EXPECT_EQ(g.at(0, 1), kFree);   // 0 -> p 0, clamped
  EXPECT_EQ(g.at(1, 1), kOcc);    // 100 -> p 1, clamped
  EXPECT_TRUE(std::isnan(g.at(2, 1)));  // 205
  EXPECT_NEAR(g.at(2, 0), std::log(0.3 / 0.7), 1e-5);  // 30
  // an absolute image path
  spit(dir / "abs.yaml", "image: " + (dir / "a.pgm").string() + "\nresolution: 0.5\norigin: [0, 0, 0]\n");
  EXPECT_EQ(duet::read_map_server(dir / "abs.yaml").width(), 3);
}

TEST(GridIo, Reads16BitPgmAndPngWithAlpha) {
  TempDir dir;
  // 16-bit P5, big endian: 0 and 65535.
  spit(dir / "b.pgm", std::string("P5\n2 1\n65535\n") + std::string("\x00\x00\xff\xff", 4));
  spit(dir / "b.yaml", "image: b.pgm\nresolution: 1\norigin: [0, 0, 0]\n");
  OccupancyGrid g = duet::read_map_server(dir / "b.yaml");
  EXPECT_EQ(g.at(0, 0), kOcc);
  EXPECT_EQ(g.at(1, 0), kFree);
  // PNG, grey: decoded by OpenCV.
  cv::Mat grey(2, 2, CV_8UC1);
  grey.at<std::uint8_t>(0, 0) = 0;
  grey.at<std::uint8_t>(0, 1) = 254;
  grey.at<std::uint8_t>(1, 0) = 205;
  grey.at<std::uint8_t>(1, 1) = 50;
  ASSERT_TRUE(cv::imwrite((dir / "c.png").string(), grey));
  spit(dir / "c.yaml", "image: c.png\nresolution: 0.1\norigin: [0, 0, 0]\n");
  g = duet::read_map_server(dir / "c.yaml");
  EXPECT_EQ(g.at(0, 1), kOcc);
  EXPECT_EQ(g.at(1, 1), kFree);
  EXPECT_TRUE(std::isnan(g.at(0, 0)));
  EXPECT_EQ(g.at(1, 0), kOcc);
  // RGBA: channels averaged; alpha 0 is unknown in mode scale.
  cv::Mat rgba(1, 2, CV_8UC4);
  rgba.at<cv::Vec4b>(0, 0) = cv::Vec4b(128, 128, 128, 0);
  rgba.at<cv::Vec4b>(0, 1) = cv::Vec4b(0, 255, 255, 255);  // average 170: p 0.33
  ASSERT_TRUE(cv::imwrite((dir / "d.png").string(), rgba));
  spit(dir / "d.yaml", "image: d.png\nresolution: 0.1\norigin: [0, 0, 0]\nmode: scale\n");
  g = duet::read_map_server(dir / "d.yaml");
  EXPECT_TRUE(std::isnan(g.at(0, 0)));
  EXPECT_FALSE(std::isnan(g.at(1, 0)));
  EXPECT_GT(g.at(1, 0), kFree);
  EXPECT_LT(g.at(1, 0), kOcc);
}

TEST(GridIo, YamlErrorsNameFileAndKey) {
  TempDir dir;
  spit(dir / "a.pgm", "P2\n1 1\n255\n0\n");
  const fs::path y = dir / "map.yaml";
  const auto with = [&](const std::string& text) {
    spit(y, text);
    return [y] { (void)duet::read_map_server(y); };
  };
  expect_error([&] { (void)duet::read_map_server(dir / "none.yaml"); }, ErrorCode::kIo, {"none.yaml"});
  expect_error(with("image: a.pgm\norigin: [0, 0, 0]\n"), ErrorCode::kParse, {"map.yaml", "'resolution' is missing"});
  expect_error(with("resolution: 1\norigin: [0, 0, 0]\n"), ErrorCode::kParse, {"'image' is missing"});
  expect_error(with("image: a.pgm\nresolution: 1\n"), ErrorCode::kParse, {"'origin' is missing"});
  expect_error(with("image: a.pgm\nresolution: abc\norigin: [0, 0, 0]\n"), ErrorCode::kParse,
               {"map.yaml", "key 'resolution' (line 2)", "expected a number, got 'abc'"});
  expect_error(with("image: a.pgm\nresolution: -1\norigin: [0, 0, 0]\n"), ErrorCode::kParse,
               {"key 'resolution'", "must be in [0.001, 100]"});
  expect_error(with("image: a.pgm\nresolution: 1\norigin: [0, 0]\n"), ErrorCode::kParse, {"key 'origin'", "[x, y, yaw]"});
  expect_error(with("image: a.pgm\nresolution: 1\norigin: [0, 0, 0.5]\n"), ErrorCode::kUnsupported,
               {"key 'origin'", "yaw"});
  expect_error(with("image: a.pgm\nresolution: 1\norigin: [0, 0, 0]\nnegate: 2\n"), ErrorCode::kParse,
               {"key 'negate'", "must be 0 or 1"});
  expect_error(with("image: a.pgm\nresolution: 1\norigin: [0, 0, 0]\nfree_thresh: 1.5\n"), ErrorCode::kParse,
               {"key 'free_thresh'", "[0, 1]"});
  expect_error(with("image: a.pgm\nresolution: 1\norigin: [0, 0, 0]\nmode: fancy\n"), ErrorCode::kParse,
               {"key 'mode'", "'fancy'"});
  expect_error(with("image: a.pgm\nresolution: 1\norigin: [0, 0, 0]\ncolour: red\n"), ErrorCode::kParse,
               {"key 'colour'", "unknown key"});
  expect_error(with("image: a.pgm\nresolution: [1\norigin: [0, 0, 0]\n"), ErrorCode::kParse, {"map.yaml", "line"});
  expect_error(with("- a\n- b\n"), ErrorCode::kParse, {"not a YAML map"});
  expect_error(with("image: missing.pgm\nresolution: 1\norigin: [0, 0, 0]\n"), ErrorCode::kIo,
               {"missing.pgm", "map.yaml"});
  // negate accepts booleans too
  spit(y, "image: a.pgm\nresolution: 1\norigin: [0, 0, 0]\nnegate: false\n");
  EXPECT_EQ(duet::read_map_server(y).at(0, 0), kOcc);
}

TEST(GridIo, CorruptImagesAreErrorsNeverCrashes) {
  TempDir dir;
  const fs::path y = dir / "m.yaml";
  spit(y, "image: m.pgm\nresolution: 0.1\norigin: [0, 0, 0]\n");
  const auto read_image = [&](const std::string& bytes) {
    spit(dir / "m.pgm", bytes);
    return [y] { (void)duet::read_map_server(y); };
  };
  expect_error(read_image("P5\n640 480\n255\n" + std::string(1200, '\xfe')), ErrorCode::kParse,
               {"m.pgm", "data truncated: expected 307200 pixels, got 1200", "m.yaml"});
  expect_error(read_image("P5\n4000000000 4000000000\n255\n"), ErrorCode::kParse, {"m.pgm", "2^28"});
  expect_error(read_image("P5\n2 2\n0\n    "), ErrorCode::kParse, {"maxval is 0"});
  expect_error(read_image("P2\n2 1\n255\n0 300\n"), ErrorCode::kParse, {"exceeds maxval"});
  expect_error(read_image("P2\n2 1\n255\n0 x\n"), ErrorCode::kParse, {"is not a number"});
  expect_error(read_image("P2\n3 1\n255\n0 1\n"), ErrorCode::kParse, {"data truncated"});
  expect_error(read_image("not an image at all"), ErrorCode::kParse, {"cannot decode"});
  expect_error(read_image(""), ErrorCode::kParse, {"empty"});

  // Every truncation and random flips of a small map: a duet::Error or a grid, nothing else.
  OccupancyGrid g = pattern_grid();
  duet::write_map_server(g, dir / "full.yaml");
  const std::string pgm = slurp(dir / "full.pgm");
  const auto survives = [&](const std::string& bytes) {
    spit(dir / "m.pgm", bytes);
    try {
      (void)duet::read_map_server(y);
    } catch (const duet::Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::kParse) << e.what();
    } catch (const std::exception& e) {
      ADD_FAILURE() << "not a duet::Error: " << e.what();
    }
  };
  for (std::size_t len = 0; len < pgm.size(); ++len) survives(pgm.substr(0, len));
  std::mt19937 rng(99);
  std::uniform_int_distribution<std::size_t> where(0, pgm.size() - 1);
  std::uniform_int_distribution<int> what(0, 255);
  for (int i = 0; i < 500; ++i) {
    std::string b = pgm;
    for (int k = 0; k < 3; ++k) b[where(rng)] = static_cast<char>(what(rng));
    survives(b);
  }
}

TEST(GridIo, WriteErrors) {
  TempDir dir;
  const OccupancyGrid empty(0.05f);
  expect_error([&] { duet::write_map_server(empty, dir / "e.yaml"); }, ErrorCode::kInvalidArgument, {"e.yaml", "empty"});
  expect_error([&] { duet::write_grid_png(empty, dir / "e.png"); }, ErrorCode::kInvalidArgument, {"e.png", "empty"});
  const OccupancyGrid g = pattern_grid();
  duet::MapServerOptions bad;
  bad.free_thresh = 0.3f;  // 205 (p 0.196) would read back free
  expect_error([&] { duet::write_map_server(g, dir / "t.yaml", bad); }, ErrorCode::kInvalidArgument, {"free_thresh"});
  expect_error([&] { duet::write_map_server(g, dir / "nodir" / "t.yaml"); }, ErrorCode::kIo, {"t.pgm"});
  duet::GridPngOptions png;
  png.scale = 0;
  expect_error([&] { duet::write_grid_png(g, dir / "s.png", png); }, ErrorCode::kInvalidArgument, {"scale"});
  png.scale = 64;
  const OccupancyGrid big(0.05f, Eigen::Vector2f::Zero(), 4000, 4000);
  expect_error([&] { duet::write_grid_png(big, dir / "s.png", png); }, ErrorCode::kInvalidArgument, {"2^28"});
  expect_error([&] { duet::write_grid_png(g, dir / "nodir" / "s.png"); }, ErrorCode::kIo, {"s.png"});
}

TEST(GridIo, PngPictureShadesAndOverlays) {
  TempDir dir;
  // 10 x 6 cells at 0.5 m from (-1, -1): rows of unknown, free, occupied and p = 0.5.
  OccupancyGrid g(0.5f, Eigen::Vector2f(-1.0f, -1.0f), 10, 6);
  auto c = g.logodds();
  for (int ix = 0; ix < 10; ++ix) {
    c[g.index(ix, 0)] = kOcc;
    c[g.index(ix, 1)] = kFree;
    c[g.index(ix, 2)] = 0.0f;  // p 0.5
    // rows 3..5 unknown
  }
  duet::GridPngOptions o;
  o.scale = 4;
  o.polyline = {{-0.9f, 1.6f}, {3.9f, 1.6f}};  // along row iy = 5 (y in [1.5, 2)), at its centre-ish
  o.dots = {{0.25f, 1.25f}};                   // centre of cell (2, 4)
  o.dot_radius_px = 2;
  duet::write_grid_png(g, dir / "g.png", o);
  const cv::Mat img = cv::imread((dir / "g.png").string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty());
  ASSERT_EQ(img.cols, 40);
  ASSERT_EQ(img.rows, 24);
  const auto at = [&](int ix, int iy) {  // BGR at the centre of cell (ix, iy)
    return img.at<cv::Vec3b>((6 - 1 - iy) * 4 + 2, ix * 4 + 2);
  };
  EXPECT_EQ(at(7, 0), cv::Vec3b(0, 0, 0)) << "occupied is black, at the bottom";
  EXPECT_EQ(at(7, 1), cv::Vec3b(255, 255, 255)) << "free is white";
  const cv::Vec3b mid = at(7, 2);
  EXPECT_EQ(mid[0], mid[1]);
  EXPECT_GT(mid[0], 40);
  EXPECT_LT(mid[0], 215);
  const duet::Rgb8 u = o.unknown_color;
  EXPECT_EQ(at(7, 3), cv::Vec3b(u.b, u.g, u.r)) << "unknown";
  const duet::Rgb8 d = o.dot_color;
  EXPECT_EQ(at(2, 4), cv::Vec3b(d.b, d.g, d.r)) << "dot";
  // The polyline at y = 1.6 m: pixel row (3 m - 1.6 m + ... ) = (6 - 5.2) * 4 = 3.2.
  const duet::Rgb8 l = o.polyline_color;
  EXPECT_EQ(img.at<cv::Vec3b>(3, 20), cv::Vec3b(l.b, l.g, l.r)) << "polyline";
  // Non-finite overlay points are skipped, not drawn at a garbage place.
  o.polyline.insert(o.polyline.begin() + 1, Eigen::Vector2f(NAN, 0.0f));
  o.dots.emplace_back(INFINITY, 0.0f);
  EXPECT_NO_THROW(duet::write_grid_png(g, dir / "g2.png", o));
}

}  // namespace
