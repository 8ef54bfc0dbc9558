#pragma once
// Shared helpers of the kernel tests: real data loading (../shared/data), thread-count runs,
// bitwise comparison, seeded random clouds, PCL conversion.
#include <duet/kernels/back_projection.hpp>
#include <duet/kernels/error.hpp>
#include <duet/kernels/grid_view.hpp>
#include <duet/kernels/types.hpp>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#ifdef DUET_HAVE_PCL
#include <pcl/io/pcd_io.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#endif

namespace duet::test {

inline constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

/// A log-odds grid owned by a test (row-major, NaN = never observed), viewed as the kernels read it.
struct LogOddsTestGrid {
  std::vector<float> l;
  int w = 0, h = 0;
  float res = 0.05f;
  Eigen::Vector2f origin{0.0f, 0.0f};
  [[nodiscard]] GridView view() const { return GridView(l, w, h, res, origin); }
  void set(int x, int y, float v) { l[static_cast<std::size_t>(y * w + x)] = v; }
  void rect(int x0, int y0, int x1, int y1, float v) {  // inclusive, clipped to the grid
    for (int y = std::max(0, y0); y <= std::min(h - 1, y1); ++y)
      for (int x = std::max(0, x0); x <= std::min(w - 1, x1); ++x) set(x, y, v);
  }
};
inline constexpr float kInf = std::numeric_limits<float>::infinity();

// ---- build speed ---------------------------------------------------------------------------------

/// Unoptimised builds (Debug, typically with sanitizers, where Eigen runs 20-50x slower) run the
/// largest real-data cases on a deterministic part of the data to stay within CI's time budget;
/// optimised builds (Release, RelWithDebInfo) run them in full.
#ifdef __OPTIMIZE__
inline constexpr bool kFullSize = true;
#else
inline constexpr bool kFullSize = false;
#endif
template <class T>
constexpr T full_or(T full, T reduced) {
  return kFullSize ? full : reduced;
}

/// Indices of the organized-cloud region [u0, u0+w) x [v0, v0+h) of an image `width` wide.
inline std::vector<std::size_t> organized_roi(int width, int u0, int v0, int w, int h) {
  std::vector<std::size_t> idx;
  for (int v = v0; v < v0 + h; ++v)
    for (int u = u0; u < u0 + w; ++u) idx.push_back(static_cast<std::size_t>(v) * static_cast<std::size_t>(width) + static_cast<std::size_t>(u));
  return idx;
}

// ---- real data -------------------------------------------------------------------------------

inline std::filesystem::path data_path(const std::string& rel) {
  return std::filesystem::path(DUET_DATA_DIR) / rel;
}
inline bool have_data(const std::string& rel) { return std::filesystem::exists(data_path(rel)); }

/// Skips the current test (GTEST_SKIP) when a data file is missing.
#define DUET_REQUIRE_DATA(rel)                                                                    \
  do {                                                                                            \
    if (!::duet::test::have_data(rel))                                                            \
      GTEST_SKIP() << "real data " << ::duet::test::data_path(rel).string()                       \
                   << " not found: ../shared/data is absent, skipping this real-data test";      \
  } while (0)

/// The Willow Garage map of ../shared/data as a three-valued log-odds grid, row 0 at the lowest y
/// (the PGM's first row is the largest y); 0.10 m cells, origin (0, 0). The file is not strictly
/// trinary: besides 0 / 254 / 205 it holds grey levels (walls drawn anti-aliased, 0-204; light free
/// space 206-253). With the .yaml thresholds (occupied p > 0.65, i.e. v < 90) only 544 cells would
/// be occupied and the walls would read as unknown, so: 205 = unknown (NaN), darker = `occupied`,
/// lighter = `free`. Empty (w = h = 0) if the file cannot be decoded.
inline constexpr const char* kWillowMap = "maps/willow-2010-02-18-0.10.pgm";
struct WillowGrid {
  std::vector<float> logodds;
  int w = 0, h = 0;
};
inline WillowGrid willow_trinary(float occupied, float free) {
  const cv::Mat img = cv::imread(data_path(kWillowMap).string(), cv::IMREAD_GRAYSCALE);
  WillowGrid g;
  if (img.empty()) return g;
  g.w = img.cols;
  g.h = img.rows;
  g.logodds.resize(static_cast<std::size_t>(g.w) * static_cast<std::size_t>(g.h));
  for (int r = 0; r < img.rows; ++r)
    for (int c = 0; c < img.cols; ++c) {
      const int v = img.at<std::uint8_t>(r, c);
      g.logodds[static_cast<std::size_t>((img.rows - 1 - r) * g.w + c)] =
          v == 205 ? kNaN : v < 205 ? occupied : free;
    }
  return g;
}

#ifdef DUET_HAVE_PCL
#define DUET_REQUIRE_PCL() (void)0
#else
#define DUET_REQUIRE_PCL() GTEST_SKIP() << "built without PCL: PCL peer comparison skipped"
#endif

inline constexpr const char* kSlambookDir = "rgbd/slambook2_ch5";

/// slambook2 ch5 intrinsics (data/README.md).
inline PinholeIntrinsics slambook_intrinsics() {
  PinholeIntrinsics K;
  K.width = 640;
  K.height = 480;
  K.fx = 518.0f;
  K.fy = 519.0f;
  K.cx = 325.5f;
  K.cy = 253.5f;
  return K;
}

struct RgbdFrame {
  cv::Mat depth;  // CV_16UC1, millimetres
  cv::Mat color;  // CV_8UC3, BGR (OpenCV order)
  Eigen::Isometry3f T_world_camera = Eigen::Isometry3f::Identity();
};

/// Frame i (1..5) of slambook2 ch5. Requires the data (check with DUET_REQUIRE_DATA first).
inline RgbdFrame load_slambook_frame(int i) {
  RgbdFrame f;
  const std::string dir = data_path(kSlambookDir).string();
  f.depth = cv::imread(dir + "/depth/" + std::to_string(i) + ".pgm", cv::IMREAD_UNCHANGED);
  f.color = cv::imread(dir + "/color/" + std::to_string(i) + ".png", cv::IMREAD_COLOR);
  std::ifstream pose(dir + "/pose.txt");
  std::string line;
  for (int k = 1; k <= i && std::getline(pose, line); ++k) {
  }
  std::istringstream ss(line);
  float tx, ty, tz, qx, qy, qz, qw;
  ss >> tx >> ty >> tz >> qx >> qy >> qz >> qw;
  f.T_world_camera = Eigen::Isometry3f::Identity();
  f.T_world_camera.linear() = Eigen::Quaternionf(qw, qx, qy, qz).normalized().toRotationMatrix();
  f.T_world_camera.translation() = Eigen::Vector3f(tx, ty, tz);
  return f;
}

inline SensorFrame slambook_sensor_frame(const RgbdFrame& f, bool with_color = true) {
  SensorFrame s;
  s.depth.data = f.depth.data;
  s.depth.width = f.depth.cols;
  s.depth.height = f.depth.rows;
  s.depth.row_stride_bytes = f.depth.step[0];
  s.depth.format = DepthFormat::kU16;
  s.depth.depth_units_per_m = 1000.0f;
  if (with_color) {
    s.color.data = f.color.data;
    s.color.width = f.color.cols;
    s.color.height = f.color.rows;
    s.color.row_stride_bytes = f.color.step[0];
    s.color.channels = 3;
    s.color.bgr = true;
  }
  s.intrinsics = slambook_intrinsics();
  return s;
}

/// Back-projects slambook2 frame i in its camera frame (depth 0.1-10 m, every pixel).
inline PointCloud slambook_cloud(int i, float min_depth = 0.1f, float max_depth = 10.0f) {
  const RgbdFrame f = load_slambook_frame(i);
  const SensorFrame s = slambook_sensor_frame(f);
  BackProjectionSettings bs;
  bs.min_depth_m = min_depth;
  bs.max_depth_m = max_depth;
  PointCloud out;
  back_project(std::span<const SensorFrame>(&s, 1), bs, out);
  return out;
}

/// Back-projects the region of interest [u0, u0+w) x [v0, v0+h) of slambook2 frame i (a view into
/// the full image: row stride of the full image, principal point shifted).
inline PointCloud slambook_cloud_roi(int i, int u0, int v0, int w, int h, float min_depth = 0.1f, float max_depth = 10.0f) {
  const RgbdFrame f = load_slambook_frame(i);
  SensorFrame s = slambook_sensor_frame(f);
  s.depth.data = f.depth.ptr<std::uint16_t>(v0) + u0;
  s.depth.width = w;
  s.depth.height = h;
  s.color.data = f.color.ptr<std::uint8_t>(v0) + 3 * u0;
  s.color.width = w;
  s.color.height = h;
  s.intrinsics.cx -= static_cast<float>(u0);
  s.intrinsics.cy -= static_cast<float>(v0);
  BackProjectionSettings bs;
  bs.min_depth_m = min_depth;
  bs.max_depth_m = max_depth;
  PointCloud out;
  back_project(std::span<const SensorFrame>(&s, 1), bs, out);
  return out;
}

// ---- paper geometry --------------------------------------------------------------------------

/// Eq. (6): sensor pose (x, y, z, theta = yaw about z, phi = pitch about y, psi = roll about x,
/// ZYX Euler) in the robot base frame, composed with the fixed optical-frame rotation (REP 103:
/// optical z forward = base x, optical x right = base -y, optical y down = base -z).
inline Eigen::Isometry3f eq6_T_robot_camera(float x, float y, float z, float theta, float phi = 0.0f,
                                            float psi = 0.0f) {
  const Eigen::Matrix3f R_robot_sensor = (Eigen::AngleAxisf(theta, Eigen::Vector3f::UnitZ()) *
                                          Eigen::AngleAxisf(phi, Eigen::Vector3f::UnitY()) *
                                          Eigen::AngleAxisf(psi, Eigen::Vector3f::UnitX()))
                                             .toRotationMatrix();
  Eigen::Matrix3f R_sensor_optical;
  R_sensor_optical.col(0) = Eigen::Vector3f(0, -1, 0);
  R_sensor_optical.col(1) = Eigen::Vector3f(0, 0, -1);
  R_sensor_optical.col(2) = Eigen::Vector3f(1, 0, 0);
  Eigen::Isometry3f T = Eigen::Isometry3f::Identity();
  T.linear() = R_robot_sensor * R_sensor_optical;
  T.translation() = Eigen::Vector3f(x, y, z);
  return T;
}
inline Eigen::Isometry3f paper_sensor1() { return eq6_T_robot_camera(-0.118f, 0.0f, 0.271f, 0.0f); }
inline Eigen::Isometry3f paper_sensor2() {
  return eq6_T_robot_camera(-0.118f, 0.0f, 0.481f, -std::numbers::pi_v<float> / 2.0f);
}

// ---- errors ------------------------------------------------------------------------------------

/// `fn` must throw duet::Error with `code` and a message containing `what`.
inline void expect_error(const std::function<void()>& fn, const std::string& what,
                         ErrorCode code = ErrorCode::kInvalidArgument) {
  try {
    fn();
    ADD_FAILURE() << "no error for " << what;
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), code) << e.what();
    EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
  }
}

// ---- threads -----------------------------------------------------------------------------------

/// Runs fn inside a task arena of `threads` threads and returns its result.
template <class Fn>
auto in_arena(int threads, Fn&& fn) -> std::invoke_result_t<Fn&> {
  tbb::task_arena arena(threads);
  return arena.execute(fn);
}

/// Bitwise equality of two trivially copyable vectors (NaN payloads compare too).
template <class T>
::testing::AssertionResult bitwise_equal(const std::vector<T>& a, const std::vector<T>& b) {
  if (a.size() != b.size())
    return ::testing::AssertionFailure() << "sizes differ: " << a.size() << " vs " << b.size();
  if (!a.empty() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) != 0) {
    for (std::size_t i = 0; i < a.size(); ++i)
      if (std::memcmp(&a[i], &b[i], sizeof(T)) != 0)
        return ::testing::AssertionFailure() << "first difference at element " << i;
  }
  return ::testing::AssertionSuccess();
}

inline ::testing::AssertionResult bitwise_equal(const PointCloud& a, const PointCloud& b) {
  if (auto r = bitwise_equal(a.points, b.points); !r) return r << " (points)";
  if (auto r = bitwise_equal(a.colors, b.colors); !r) return r << " (colors)";
  if (auto r = bitwise_equal(a.normals, b.normals); !r) return r << " (normals)";
  if (auto r = bitwise_equal(a.curvature, b.curvature); !r) return r << " (curvature)";
  return ::testing::AssertionSuccess();
}

// ---- random data -------------------------------------------------------------------------------

inline std::vector<Eigen::Vector3f> random_points(std::size_t n, std::uint32_t seed, float lo = -1.0f, float hi = 1.0f) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(lo, hi);
  std::vector<Eigen::Vector3f> p(n);
  for (auto& q : p) q = Eigen::Vector3f(u(rng), u(rng), u(rng));
  return p;
}

inline std::vector<Rgb8> random_colors(std::size_t n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> u(0, 255);
  std::vector<Rgb8> c(n);
  for (auto& x : c)
    x = Rgb8{static_cast<std::uint8_t>(u(rng)), static_cast<std::uint8_t>(u(rng)), static_cast<std::uint8_t>(u(rng))};
  return c;
}

/// Expects `stmt` to throw duet::Error with `code` and a message containing `needle`.
#define EXPECT_DUET_ERROR(stmt, want_code, needle)                                                        \
  do {                                                                                               \
    bool duet_thrown_ = false;                                                                       \
    try {                                                                                            \
      stmt;                                                                                          \
    } catch (const ::duet::Error& e) {                                                               \
      duet_thrown_ = true;                                                                           \
      EXPECT_EQ(e.code(), want_code) << "message: " << e.what();                                         \
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos)                               \
          << "message \"" << e.what() << "\" does not mention \"" << needle << "\"";                 \
    } catch (const std::exception& e) {                                                              \
      ADD_FAILURE() << #stmt << " threw a non-duet exception: " << e.what();                         \
      duet_thrown_ = true;                                                                           \
    }                                                                                                \
    EXPECT_TRUE(duet_thrown_) << #stmt << " did not throw";                                          \
  } while (0)

// ---- PCL ---------------------------------------------------------------------------------------

#ifdef DUET_HAVE_PCL
inline pcl::PointCloud<pcl::PointXYZRGB>::Ptr to_pcl_rgb(const PointCloud& c) {
  pcl::PointCloud<pcl::PointXYZRGB>::Ptr p(new pcl::PointCloud<pcl::PointXYZRGB>);
  p->resize(c.size());
  bool dense = true;
  for (std::size_t i = 0; i < c.size(); ++i) {
    auto& q = (*p)[i];
    q.x = c.points[i].x();
    q.y = c.points[i].y();
    q.z = c.points[i].z();
    dense = dense && is_finite(c.points[i]);
    if (c.has_colors()) {
      q.r = c.colors[i].r;
      q.g = c.colors[i].g;
      q.b = c.colors[i].b;
    } else {
      q.r = q.g = q.b = 255;
    }
    q.a = 255;
  }
  p->width = static_cast<std::uint32_t>(c.size());
  p->height = 1;
  p->is_dense = dense;
  return p;
}

inline pcl::PointCloud<pcl::PointXYZ>::Ptr to_pcl_xyz(const std::vector<Eigen::Vector3f>& pts) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr p(new pcl::PointCloud<pcl::PointXYZ>);
  p->resize(pts.size());
  bool dense = true;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    (*p)[i].x = pts[i].x();
    (*p)[i].y = pts[i].y();
    (*p)[i].z = pts[i].z();
    dense = dense && is_finite(pts[i]);
  }
  p->width = static_cast<std::uint32_t>(pts.size());
  p->height = 1;
  p->is_dense = dense;
  return p;
}

/// Loads a PCD of ../shared/data/pcl into a duet cloud (colour when the file has rgb/rgba).
inline PointCloud load_pcd(const std::string& rel, bool with_color = true) {
  if (!with_color) {
    pcl::PointCloud<pcl::PointXYZ> c;
    if (pcl::io::loadPCDFile(data_path(rel).string(), c) != 0) throw std::runtime_error("cannot load " + rel);
    PointCloud out;
    out.points.resize(c.size());
    for (std::size_t i = 0; i < c.size(); ++i) out.points[i] = Eigen::Vector3f(c[i].x, c[i].y, c[i].z);
    return out;
  }
  pcl::PointCloud<pcl::PointXYZRGB> c;
  if (pcl::io::loadPCDFile(data_path(rel).string(), c) != 0) throw std::runtime_error("cannot load " + rel);
  PointCloud out;
  out.points.resize(c.size());
  if (with_color) out.colors.resize(c.size());
  for (std::size_t i = 0; i < c.size(); ++i) {
    out.points[i] = Eigen::Vector3f(c[i].x, c[i].y, c[i].z);
    if (with_color) out.colors[i] = Rgb8{c[i].r, c[i].g, c[i].b};
  }
  return out;
}
#endif

inline std::vector<Eigen::Vector3f> finite_only(const std::vector<Eigen::Vector3f>& p) {
  std::vector<Eigen::Vector3f> o;
  o.reserve(p.size());
  for (const auto& q : p)
    if (is_finite(q)) o.push_back(q);
  return o;
}

}  // namespace duet::test
