// Inputs of duet_bench: real RGB-D frames from ../shared/data (or a synthetic room), the dual
// frame and the accumulated cloud, their labels and grids. Nothing here is timed.
#include "common.hpp"

#include <duet/kernels/normals.hpp>
#include <duet/kernels/voxel_filter.hpp>

#include <Eigen/Eigenvalues>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <random>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

#ifndef DUET_BENCH_DATA_DIR
#define DUET_BENCH_DATA_DIR "../shared/data"
#endif

namespace duet::bench {
namespace {

namespace fs = std::filesystem;

Data g_data;
bool g_initialised = false;

// ---------------------------------------------------------------------------------------
// Frames

/// Rotation from the camera optical frame (z fwd, x right, y down) to the camera body frame
/// (x fwd, y left, z up), REP 103.
Eigen::Matrix3f R_body_optical() {
  Eigen::Matrix3f R;
  R << 0, 0, 1,  //
      -1, 0, 0,  //
      0, -1, 0;
  return R;
}

/// Paper Eq. (6): sensor pose on the robot (x y z [m], ZYX Euler yaw theta, pitch phi, roll psi),
/// returned as T_robot_optical.
Eigen::Isometry3f sensor_extrinsics(float x, float y, float z, float yaw_deg, float pitch_deg,
                                    float roll_deg) {
  constexpr float rad_per_deg = 3.14159265358979f / 180.0f;
  Eigen::Isometry3f T = Eigen::Isometry3f::Identity();
  T.linear() = (Eigen::AngleAxisf(yaw_deg * rad_per_deg, Eigen::Vector3f::UnitZ()) *
                Eigen::AngleAxisf(pitch_deg * rad_per_deg, Eigen::Vector3f::UnitY()) *
                Eigen::AngleAxisf(roll_deg * rad_per_deg, Eigen::Vector3f::UnitX()))
                   .toRotationMatrix() *
               R_body_optical();
  T.translation() = Eigen::Vector3f(x, y, z);
  return T;
}

struct RawFrame {
  cv::Mat depth;  // CV_16UC1, millimetres
  cv::Mat color;  // CV_8UC3, BGR
  PinholeIntrinsics K;
  Eigen::Isometry3f T_world_camera = Eigen::Isometry3f::Identity();
};

SensorFrame make_sensor_frame(const RawFrame& f, const Eigen::Isometry3f& T) {
  SensorFrame s;
  s.depth.data = f.depth.data;
  s.depth.width = f.depth.cols;
  s.depth.height = f.depth.rows;
  s.depth.row_stride_bytes = f.depth.step[0];
  s.depth.format = DepthFormat::kU16;
  s.depth.depth_units_per_m = 1000.0f;
  if (!f.color.empty()) {
    s.color.data = f.color.data;
    s.color.width = f.color.cols;
    s.color.height = f.color.rows;
    s.color.row_stride_bytes = f.color.step[0];
    s.color.channels = 3;
    s.color.bgr = true;
  }
  s.intrinsics = f.K;
  s.intrinsics.width = f.depth.cols;
  s.intrinsics.height = f.depth.rows;
  s.T_robot_camera = T;
  return s;
}

cv::Mat read_image(const fs::path& p, int flags, int expected_type) {
  cv::Mat m = cv::imread(p.string(), flags);
  if (m.empty()) throw std::runtime_error("duet_bench: cannot read " + p.string());
  if (m.type() != expected_type) throw std::runtime_error("duet_bench: unexpected pixel type in " + p.string());
  return m;
}

/// slambook2 ch5: color/N.png, depth/N.pgm (16-bit mm), pose.txt: tx ty tz qx qy qz qw (camera->world).
std::vector<RawFrame> load_slambook(const fs::path& dir, const std::vector<int>& ids) {
  std::ifstream pf(dir / "pose.txt");
  if (!pf) throw std::runtime_error("duet_bench: cannot read " + (dir / "pose.txt").string());
  std::vector<Eigen::Isometry3f> poses;
  double tx, ty, tz, qx, qy, qz, qw;
  while (pf >> tx >> ty >> tz >> qx >> qy >> qz >> qw) {
    Eigen::Isometry3f T = Eigen::Isometry3f::Identity();
    T.linear() = Eigen::Quaternionf(float(qw), float(qx), float(qy), float(qz)).normalized().toRotationMatrix();
    T.translation() = Eigen::Vector3f(float(tx), float(ty), float(tz));
    poses.push_back(T);
  }
  std::vector<RawFrame> out;
  for (int id : ids) {
    RawFrame f;
    f.depth = read_image(dir / "depth" / (std::to_string(id) + ".pgm"), cv::IMREAD_UNCHANGED, CV_16UC1);
    f.color = read_image(dir / "color" / (std::to_string(id) + ".png"), cv::IMREAD_COLOR, CV_8UC3);
    f.K = PinholeIntrinsics{640, 480, 518.0f, 519.0f, 325.5f, 253.5f};
    if (id < 1 || std::size_t(id) > poses.size()) throw std::runtime_error("duet_bench: no pose for slambook frame");
    f.T_world_camera = poses[std::size_t(id - 1)];
    out.push_back(std::move(f));
  }
  return out;
}

/// 3dmatch (SUN3D): frame-NNNNNN.{color,depth}.png, .pose.txt (4x4 camera->world),
/// camera-intrinsics.txt (3x3).
std::vector<RawFrame> load_3dmatch(const fs::path& dir, const std::vector<std::string>& ids) {
  std::ifstream kf(dir / "camera-intrinsics.txt");
  std::array<float, 9> k{};
  for (auto& v : k) kf >> v;
  if (!kf) throw std::runtime_error("duet_bench: cannot read 3dmatch intrinsics");
  std::vector<RawFrame> out;
  for (const auto& id : ids) {
    RawFrame f;
    const std::string stem = "frame-" + id;
    f.depth = read_image(dir / (stem + ".depth.png"), cv::IMREAD_UNCHANGED, CV_16UC1);
    f.color = read_image(dir / (stem + ".color.png"), cv::IMREAD_COLOR, CV_8UC3);
    f.K = PinholeIntrinsics{640, 480, k[0], k[4], k[2], k[5]};
    std::ifstream pf(dir / (stem + ".pose.txt"));
    Eigen::Matrix4f M;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) pf >> M(r, c);
    if (!pf) throw std::runtime_error("duet_bench: cannot read 3dmatch pose " + stem);
    f.T_world_camera.matrix() = M;
    out.push_back(std::move(f));
  }
  return out;
}

// ---------------------------------------------------------------------------------------
// Synthetic fallback: a box room with a table, ray-cast analytically.

struct Box {
  Eigen::Vector3f lo, hi;
};

void render_synthetic(RawFrame& f, const std::vector<Box>& obstacles, const Box& room, unsigned seed) {
  f.K = PinholeIntrinsics{};
  f.depth.create(480, 640, CV_16UC1);
  f.color.create(480, 640, CV_8UC3);
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.0f, 1.0f);
  const Eigen::Matrix3f R = f.T_world_camera.linear();
  const Eigen::Vector3f o = f.T_world_camera.translation();
  for (int v = 0; v < 480; ++v) {
    for (int u = 0; u < 640; ++u) {
      const Eigen::Vector3f dc((float(u) - f.K.cx) / f.K.fx, (float(v) - f.K.cy) / f.K.fy, 1.0f);
      const Eigen::Vector3f d = R * dc;
      float t = 1e9f;
      int surface = 0;
      for (int a = 0; a < 3; ++a) {  // room walls from inside
        if (std::abs(d[a]) < 1e-9f) continue;
        const float ta = ((d[a] > 0 ? room.hi[a] : room.lo[a]) - o[a]) / d[a];
        if (ta > 0 && ta < t) {
          t = ta;
          surface = a;
        }
      }
      for (std::size_t b = 0; b < obstacles.size(); ++b) {  // slab test
        float t0 = 0.0f, t1 = 1e9f;
        for (int a = 0; a < 3; ++a) {
          const float inv = 1.0f / d[a];
          float ta = (obstacles[b].lo[a] - o[a]) * inv, tb = (obstacles[b].hi[a] - o[a]) * inv;
          if (ta > tb) std::swap(ta, tb);
          t0 = std::max(t0, ta);
          t1 = std::min(t1, tb);
        }
        if (t0 <= t1 && t0 > 0 && t0 < t) {
          t = t0;
          surface = 3 + int(b);
        }
      }
      const float z = t * (1.0f + 0.001f * t * noise(rng));  // Kinect-like noise growing with range
      f.depth.at<std::uint16_t>(v, u) = static_cast<std::uint16_t>(std::clamp(z * 1000.0f, 0.0f, 65535.0f));
      const std::uint8_t c = static_cast<std::uint8_t>(60 + 40 * surface);
      f.color.at<cv::Vec3b>(v, u) = cv::Vec3b(c, static_cast<std::uint8_t>(255 - c), 128);
    }
  }
}

Eigen::Isometry3f camera_pose(float x, float y, float z, float yaw_deg) {
  return sensor_extrinsics(x, y, z, yaw_deg, 0.0f, 0.0f);
}

// ---------------------------------------------------------------------------------------
// Levelling: the floor plane by RANSAC, then a transform that puts it at z = 0.

struct Plane {
  Eigen::Vector3f n;  // unit, pointing up
  float d;            // n.p + d = 0
  std::size_t inliers;
};

std::optional<Plane> find_floor(const std::vector<Eigen::Vector3f>& pts, const Eigen::Vector3f& up) {
  if (pts.size() < 100) return std::nullopt;
  // Candidates: the lowest 30 % of a subsample along the guessed up axis.
  const std::size_t step = std::max<std::size_t>(1, pts.size() / 60000);
  std::vector<Eigen::Vector3f> sub;
  for (std::size_t i = 0; i < pts.size(); i += step)
    if (is_finite(pts[i])) sub.push_back(pts[i]);
  std::vector<float> h(sub.size());
  for (std::size_t i = 0; i < sub.size(); ++i) h[i] = up.dot(sub[i]);
  std::vector<float> hs = h;
  const std::size_t q = hs.size() * 3 / 10;
  std::nth_element(hs.begin(), hs.begin() + std::ptrdiff_t(q), hs.end());
  const float h_max = hs[q];
  std::vector<Eigen::Vector3f> cand;
  for (std::size_t i = 0; i < sub.size(); ++i)
    if (h[i] <= h_max) cand.push_back(sub[i]);
  if (cand.size() < 50) return std::nullopt;

  std::mt19937 rng(12345);
  std::uniform_int_distribution<std::size_t> pick(0, cand.size() - 1);
  const float cos_max_tilt = std::cos(35.0f * 3.14159265f / 180.0f);
  std::optional<Plane> best;
  for (int it = 0; it < 400; ++it) {
    const Eigen::Vector3f a = cand[pick(rng)], b = cand[pick(rng)], c = cand[pick(rng)];
    Eigen::Vector3f n = (b - a).cross(c - a);
    if (n.norm() < 1e-6f) continue;
    n.normalize();
    if (n.dot(up) < 0) n = -n;
    if (n.dot(up) < cos_max_tilt) continue;
    const float d = -n.dot(a);
    std::size_t in = 0;
    for (const auto& p : cand) in += std::abs(n.dot(p) + d) < 0.03f ? 1u : 0u;
    if (!best || in > best->inliers) best = Plane{n, d, in};
  }
  if (!best || best->inliers < cand.size() / 5) return std::nullopt;
  // Least-squares refinement on the inliers (normal = smallest eigenvector).
  Eigen::Vector3f mean = Eigen::Vector3f::Zero();
  std::size_t m = 0;
  for (const auto& p : cand)
    if (std::abs(best->n.dot(p) + best->d) < 0.03f) {
      mean += p;
      ++m;
    }
  mean /= float(m);
  Eigen::Matrix3f C = Eigen::Matrix3f::Zero();
  for (const auto& p : cand)
    if (std::abs(best->n.dot(p) + best->d) < 0.03f) C += (p - mean) * (p - mean).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3f> es(C);
  Eigen::Vector3f n = es.eigenvectors().col(0).normalized();
  if (n.dot(up) < 0) n = -n;
  return Plane{n, -n.dot(mean), m};
}

/// T such that the floor plane maps to z = 0 with its normal along +z (identity if none found).
Eigen::Isometry3f levelling(const std::vector<Eigen::Vector3f>& pts, const Eigen::Vector3f& up,
                            std::string& note) {
  Eigen::Isometry3f T = Eigen::Isometry3f::Identity();
  const auto plane = find_floor(pts, up);
  if (!plane) {
    note = "no floor found, not levelled";
    T.linear() = Eigen::Quaternionf::FromTwoVectors(up, Eigen::Vector3f::UnitZ()).toRotationMatrix();
    return T;
  }
  T.linear() = Eigen::Quaternionf::FromTwoVectors(plane->n, Eigen::Vector3f::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3f(0, 0, plane->d);
  char buf[128];
  std::snprintf(buf, sizeof buf, "floor tilt %.1f deg from the guessed up axis",
                std::acos(std::clamp(plane->n.dot(up.normalized()), -1.0f, 1.0f)) * 57.29578f);
  note = buf;
  return T;
}

// ---------------------------------------------------------------------------------------
// Derived inputs

void finish_input(Input& in, const Eigen::Isometry3f& T_level_for_labels, const Eigen::Vector3f& viewpoint) {
  arena(2).execute([&] { back_project(in.frames, in.bp_settings, in.cloud, &in.offsets); });
  in.scans.clear();
  for (std::size_t i = 0; i < in.frames.size(); ++i) {
    Scan s;
    s.begin = in.offsets[i];
    s.end = in.offsets[i + 1];
    s.sensor_xy = in.frames[i].T_robot_camera.translation().head<2>();
    in.scans.push_back(s);
  }
  // Labels as the mapper makes them (paper §2.2, Fig. 4): voxel filter (0.05 m) -> normals (k = 10)
  // -> segmentation, on a levelled copy; every raw point then takes the label of its voxel.
  // (k = 10 normals straight on the raw cloud span ~1 cm, below the Kinect's depth noise, and
  // would mark most of the floor as obstacle.)
  VoxelFilterSettings vs;
  vs.leaf_size_m = kLeafSize;
  PointCloud lev;
  std::vector<PointLabel> voxel_labels;
  arena(2).execute([&] {
    voxel_filter(in.cloud.points_view(), in.cloud.colors_view(), vs, in.voxel);
    lev.points.resize(in.voxel.size());
    for (std::size_t i = 0; i < in.voxel.size(); ++i) lev.points[i] = T_level_for_labels * in.voxel.points[i];
    NormalSettings ns;
    ns.k = kNormalK;
    ns.viewpoint = T_level_for_labels * viewpoint;
    estimate_normals(lev, ns);
    voxel_labels.assign(lev.size(), PointLabel::kIgnored);
    segment(lev.points_view(), lev.normals, SegmentationSettings{}, voxel_labels);
  });
  const float inv_leaf = 1.0f / kLeafSize;
  auto voxel_key = [inv_leaf](const Eigen::Vector3f& p) {
    std::uint64_t k = 0;
    for (int a = 0; a < 3; ++a)
      k = (k << 21) | (static_cast<std::uint64_t>(static_cast<std::int64_t>(std::floor(p[a] * inv_leaf)) + (1 << 20)) &
                       0x1FFFFFu);
    return k;
  };
  std::unordered_map<std::uint64_t, PointLabel> label_of_voxel;
  label_of_voxel.reserve(in.voxel.size() * 2);
  for (std::size_t i = 0; i < in.voxel.size(); ++i) label_of_voxel.emplace(voxel_key(in.voxel.points[i]), voxel_labels[i]);
  in.labels.assign(in.cloud.size(), PointLabel::kIgnored);
  for (std::size_t i = 0; i < in.cloud.size(); ++i) {
    const auto it = label_of_voxel.find(voxel_key(in.cloud.points[i]));
    if (it != label_of_voxel.end()) in.labels[i] = it->second;
  }
  // A grid covering every labelled point and sensor, so no contender grows it in the loop.
  Eigen::Vector2f lo(1e30f, 1e30f), hi(-1e30f, -1e30f);
  for (std::size_t i = 0; i < in.cloud.size(); ++i) {
    if (in.labels[i] == PointLabel::kIgnored) continue;
    lo = lo.cwiseMin(in.cloud.points[i].head<2>());
    hi = hi.cwiseMax(in.cloud.points[i].head<2>());
  }
  for (const auto& s : in.scans) {
    lo = lo.cwiseMin(s.sensor_xy);
    hi = hi.cwiseMax(s.sensor_xy);
  }
  in.grid_template = OccupancyGrid(0.05f);
  if (lo.x() <= hi.x()) in.grid_template.ensure_contains(lo, hi, GridUpdateSettings{}.grow_margin_cells);
}

void build_real(const fs::path& root) {
  const fs::path slam = root / "rgbd" / "slambook2_ch5";
  const fs::path tdm = root / "rgbd" / "3dmatch_seq01";
  auto keep = [](const std::vector<RawFrame>& fr) {  // the frames' views point into these images
    for (const auto& f : fr) {
      g_data.images.push_back(std::make_shared<cv::Mat>(f.depth));
      g_data.images.push_back(std::make_shared<cv::Mat>(f.color));
    }
  };
  static std::vector<RawFrame> dual_raw, slam_raw, tdm_raw;
  dual_raw = load_slambook(slam, {1, 3});
  slam_raw = load_slambook(slam, {1, 2, 3, 4, 5});
  tdm_raw = load_3dmatch(tdm, {"000000", "000422"});
  keep(dual_raw);
  keep(slam_raw);
  keep(tdm_raw);

  // ---- dual: Eq. (6) extrinsics, robot frame.
  Input& d = g_data.dual;
  d.name = "dual";
  d.frames_desc = "slambook2_ch5 frames 1 (sensor 1, forward) and 3 (sensor 2, right), Eq. (6) extrinsics";
  const Eigen::Isometry3f T1 = sensor_extrinsics(-0.118f, 0.0f, 0.271f, 0, 0, 0);
  const Eigen::Isometry3f T2 = sensor_extrinsics(-0.118f, 0.0f, 0.481f, -90.0f, 0, 0);
  d.frames = {make_sensor_frame(dual_raw[0], T1), make_sensor_frame(dual_raw[1], T2)};
  {
    PointCloud tmp;
    naive_back_project(d.frames, d.bp_settings, tmp);
    std::string note;
    const Eigen::Isometry3f L = levelling(tmp.points, Eigen::Vector3f::UnitZ(), note);
    d.frames_desc += "; labels from a levelled copy (" + note + ")";
    finish_input(d, L, Eigen::Vector3f(-0.118f, 0.0f, 0.4f));
  }

  // ---- accum: each data set levelled in its own world frame; 3dmatch placed beside slambook.
  Input& a = g_data.accum;
  a.name = "accum";
  auto level_set = [&](const std::vector<RawFrame>& fr, std::string& note) {
    std::vector<SensorFrame> sf;
    for (const auto& f : fr) sf.push_back(make_sensor_frame(f, f.T_world_camera));
    PointCloud tmp;
    BackProjectionSettings bs;
    bs.pixel_step = 2;
    naive_back_project(sf, bs, tmp);
    const Eigen::Vector3f up = -fr.front().T_world_camera.linear().col(1);  // camera -y = up
    const Eigen::Isometry3f L = levelling(tmp.points, up, note);
    Eigen::Vector3f lo(1e30f, 1e30f, 1e30f), hi = -lo;
    for (const auto& p : tmp.points) {
      lo = lo.cwiseMin(L * p);
      hi = hi.cwiseMax(L * p);
    }
    return std::tuple{L, lo, hi};
  };
  std::string note_s, note_t;
  auto [Ls, los, his] = level_set(slam_raw, note_s);
  auto [Lt, lot, hit] = level_set(tdm_raw, note_t);
  Eigen::Isometry3f shift = Eigen::Isometry3f::Identity();
  shift.translation() = Eigen::Vector3f(his.x() - lot.x() + 1.0f, los.y() - lot.y(), 0.0f);
  a.frames.clear();
  for (const auto& f : slam_raw) a.frames.push_back(make_sensor_frame(f, Ls * f.T_world_camera));
  for (const auto& f : tdm_raw) a.frames.push_back(make_sensor_frame(f, shift * Lt * f.T_world_camera));
  a.frames_desc = "slambook2_ch5 frames 1-5 (" + note_s + ") + 3dmatch_seq01 frames 000000 and 000422 (" +
                  note_t + ") as a second room 1 m beside the first; world poses, floor at z = 0";
  Eigen::Vector3f vp = Eigen::Vector3f::Zero();
  for (const auto& f : a.frames) vp += f.T_robot_camera.translation();
  vp /= float(a.frames.size());
  vp.z() = std::max(vp.z(), 1.0f);
  finish_input(a, Eigen::Isometry3f::Identity(), vp);
}

void build_synthetic() {
  const Box room{{-3.0f, -2.5f, 0.0f}, {5.0f, 2.5f, 2.6f}};
  const std::vector<Box> obstacles{{{1.0f, -0.5f, 0.0f}, {1.8f, 0.5f, 0.75f}},
                                   {{-1.5f, -2.5f, 0.0f}, {-0.5f, -2.0f, 1.8f}},
                                   {{3.0f, 1.5f, 0.0f}, {3.6f, 2.1f, 0.45f}}};
  static std::vector<RawFrame> frames(9);
  // dual: the robot at the world origin; world = robot frame.
  const Eigen::Isometry3f T1 = sensor_extrinsics(-0.118f, 0.0f, 0.271f, 0, 0, 0);
  const Eigen::Isometry3f T2 = sensor_extrinsics(-0.118f, 0.0f, 0.481f, -90.0f, 0, 0);
  frames[0].T_world_camera = T1;
  frames[1].T_world_camera = T2;
  const std::array<std::array<float, 4>, 7> poses{{{0.0f, 0.0f, 0.3f, 0.0f},
                                                   {0.5f, 0.3f, 0.3f, 40.0f},
                                                   {1.0f, -0.8f, 0.5f, 90.0f},
                                                   {2.5f, 0.0f, 0.5f, 180.0f},
                                                   {-1.0f, 1.0f, 0.3f, -60.0f},
                                                   {3.0f, -1.0f, 0.3f, 135.0f},
                                                   {-2.0f, 0.0f, 0.4f, -150.0f}}};
  for (std::size_t i = 0; i < poses.size(); ++i)
    frames[2 + i].T_world_camera = camera_pose(poses[i][0], poses[i][1], poses[i][2], poses[i][3]);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    render_synthetic(frames[i], obstacles, room, unsigned(i + 1));
    g_data.images.push_back(std::make_shared<cv::Mat>(frames[i].depth));
    g_data.images.push_back(std::make_shared<cv::Mat>(frames[i].color));
  }
  Input& d = g_data.dual;
  d.name = "dual";
  d.frames_desc = "SYNTHETIC box room (data folder absent), 2 sensors with Eq. (6) extrinsics";
  d.frames = {make_sensor_frame(frames[0], frames[0].T_world_camera),
              make_sensor_frame(frames[1], frames[1].T_world_camera)};
  finish_input(d, Eigen::Isometry3f::Identity(), Eigen::Vector3f(-0.118f, 0.0f, 0.4f));
  Input& a = g_data.accum;
  a.name = "accum";
  a.frames_desc = "SYNTHETIC box room (data folder absent), 7 frames";
  for (std::size_t i = 2; i < frames.size(); ++i)
    a.frames.push_back(make_sensor_frame(frames[i], frames[i].T_world_camera));
  finish_input(a, Eigen::Isometry3f::Identity(), Eigen::Vector3f(0.5f, 0.0f, 1.0f));
}

std::string summary(const Input& in) {
  std::size_t nf = 0, no = 0, ni = 0;
  for (auto l : in.labels) (l == PointLabel::kFloor ? nf : l == PointLabel::kObstacle ? no : ni)++;
  std::ostringstream os;
  os << in.cloud.size() << " points from " << in.frames.size() << " frames (depth "
     << in.bp_settings.min_depth_m << "-" << in.bp_settings.max_depth_m << " m); " << in.voxel.size()
     << " after the 0.05 m voxel filter; labels floor/obstacle/ignored " << nf << "/" << no << "/" << ni
     << "; grid " << in.grid_template.width() << "x" << in.grid_template.height() << " cells; "
     << in.frames_desc;
  return os.str();
}

}  // namespace

tbb::task_arena& arena(int threads) {
  static tbb::task_arena a1(1), a2(2);
  return threads == 1 ? a1 : a2;
}

const Data& data() {
  if (!g_initialised) throw std::logic_error("duet_bench: init_data() not called");
  return g_data;
}

void init_data() {
  if (g_initialised) return;
  arena(1).initialize();
  arena(2).initialize();
  const fs::path root = DUET_BENCH_DATA_DIR;
  const bool have = fs::exists(root / "rgbd" / "slambook2_ch5" / "pose.txt") &&
                    fs::exists(root / "rgbd" / "3dmatch_seq01" / "camera-intrinsics.txt");
  if (have) {
    build_real(root);
    g_data.real = true;
    g_data.source = "real";
  } else {
    std::fprintf(stderr, "duet_bench: %s not found: using a SYNTHETIC scene\n", root.string().c_str());
    build_synthetic();
    g_data.real = false;
    g_data.source = "SYNTHETIC (data absent)";
  }
  g_initialised = true;
  const std::string sd = summary(g_data.dual), sa = summary(g_data.accum);
  std::fprintf(stderr, "duet_bench inputs (%s):\n  dual : %s\n  accum: %s\n", g_data.source.c_str(), sd.c_str(),
               sa.c_str());
  benchmark::AddCustomContext("duet_data", g_data.real ? root.string() : "SYNTHETIC scene (data folder absent)");
  benchmark::AddCustomContext("duet_input_dual", sd);
  benchmark::AddCustomContext("duet_input_accum", sa);
}

// ---------------------------------------------------------------------------------------

void naive_back_project(std::span<const SensorFrame> frames, const BackProjectionSettings& settings,
                        PointCloud& out) {
  out.points.clear();
  out.colors.clear();
  out.normals.clear();
  out.curvature.clear();
  const int step = std::max(1, settings.pixel_step);
  for (const SensorFrame& f : frames) {
    const auto& K = f.intrinsics;
    const float ifx = 1.0f / K.fx, ify = 1.0f / K.fy;
    const std::size_t dstride = f.depth.row_stride_bytes
                                    ? f.depth.row_stride_bytes
                                    : std::size_t(f.depth.width) * (f.depth.format == DepthFormat::kU16 ? 2 : 4);
    const std::size_t cstride = f.color.row_stride_bytes ? f.color.row_stride_bytes
                                                         : std::size_t(f.color.width) * std::size_t(f.color.channels);
    const Eigen::Matrix3f R = f.T_robot_camera.linear();
    const Eigen::Vector3f t = f.T_robot_camera.translation();
    const auto* dbase = static_cast<const std::uint8_t*>(f.depth.data);
    for (int v = 0; v < f.depth.height; v += step) {
      const std::uint8_t* drow = dbase + std::size_t(v) * dstride;
      for (int u = 0; u < f.depth.width; u += step) {
        float z;
        if (f.depth.format == DepthFormat::kU16) {
          std::uint16_t raw;
          std::memcpy(&raw, drow + std::size_t(u) * 2, 2);
          z = float(raw) / f.depth.depth_units_per_m;
        } else {
          std::memcpy(&z, drow + std::size_t(u) * 4, 4);
        }
        if (!(z >= settings.min_depth_m && z <= settings.max_depth_m)) continue;  // also drops 0 and NaN
        const Eigen::Vector3f pc((float(u) - K.cx) * ifx * z, (float(v) - K.cy) * ify * z, z);
        out.points.push_back(R * pc + t);
        Rgb8 c{255, 255, 255};
        if (f.color.data) {
          const std::uint8_t* px = f.color.data + std::size_t(v) * cstride + std::size_t(u) * std::size_t(f.color.channels);
          c = f.color.bgr ? Rgb8{px[2], px[1], px[0]} : Rgb8{px[0], px[1], px[2]};
        }
        out.colors.push_back(c);
      }
    }
  }
}

}  // namespace duet::bench
