/// @file rgbd_dataset.cpp
/// RGB-D sequences on disk -> RgbdFrame (see rgbd_dataset.hpp for the layouts).
#include <duet/kernels/error.hpp>
#include <duet/kernels/grid.hpp>
#include <duet/runtime/io/rgbd_dataset.hpp>
#include <duet/runtime/io/input_limits.hpp>

#include "io/file_util.hpp"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <Eigen/SVD>

#include <algorithm>
#include <cstdio>
#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>

namespace duet {
namespace fs = std::filesystem;
namespace {

// Known intrinsics of the slambook2 ch5 Kinect (not stored in the folder).
PinholeIntrinsics slambook2_intrinsics() {
  PinholeIntrinsics k;
  k.width = 640;
  k.height = 480;
  k.fx = 518.0f;
  k.fy = 519.0f;
  k.cx = 325.5f;
  k.cy = 253.5f;
  return k;
}
constexpr float kMillimetres = 1000.0f;

bool is_dir(const fs::path& p) {
  std::error_code ec;
  return fs::is_directory(p, ec);
}
bool is_file(const fs::path& p) {
  std::error_code ec;
  return fs::is_regular_file(p, ec);
}

// A file the folder must have: "<path>: <missing>" when it is absent; a FIFO, a device, a folder
// or a file over the limit is refused naming what it is (check_input_file, input_limits.hpp).
void require_file(const fs::path& p, const std::string& missing, std::uintmax_t max_bytes, const char* what) {
  std::error_code ec;
  if (!fs::exists(p, ec)) fail(ErrorCode::kIo, p.string() + ": " + missing);
  (void)detail::check_input_file(p, max_bytes, what);
}

std::string read_text(const fs::path& p) { return detail::read_whole_file(p, input_limits::kTextBytes, "text file"); }

std::vector<std::string> split_ws(std::string_view line) {
  std::vector<std::string> out;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    const std::size_t b = i;
    while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    if (i > b) out.emplace_back(line.substr(b, i - b));
  }
  return out;
}

/// Parses `tok` as a finite number; `where` names the file (and line) for the message.
double parse_number(const std::string& tok, const std::string& where, std::size_t index) {
  std::string_view s = tok;
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  double v = 0.0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || end != s.data() + s.size() || s.empty())
    fail(ErrorCode::kParse, where + ": value " + std::to_string(index + 1) + " '" + tok + "' is not a number");
  if (!std::isfinite(v))
    fail(ErrorCode::kParse, where + ": value " + std::to_string(index + 1) + " '" + tok + "' is not finite");
  return v;
}

/// All whitespace-separated numbers of a small text file (3dmatch matrices).
std::vector<double> read_numbers(const fs::path& p, std::size_t expected, const char* what) {
  const std::vector<std::string> toks = split_ws(read_text(p));
  if (toks.size() != expected)
    fail(ErrorCode::kParse, p.string() + ": expected " + std::to_string(expected) + " numbers (" + what +
                                "), got " + std::to_string(toks.size()));
  std::vector<double> v(toks.size());
  for (std::size_t i = 0; i < toks.size(); ++i) v[i] = parse_number(toks[i], p.string(), i);
  return v;
}

std::string fmt(double v) {
  std::ostringstream os;
  os.imbue(std::locale::classic());
  os.precision(6);
  os << v;
  return os.str();
}

/// A camera position within the map frame's limits (grid.hpp: +-10 km); else a parse error
/// naming the file and line - not a kernel's error far downstream.
void check_translation(const Eigen::Vector3d& t, const std::string& where) {
  for (int i = 0; i < 3; ++i)
    if (!(std::fabs(t[i]) <= static_cast<double>(kMaxCoordinateM)))
      fail(ErrorCode::kParse, where + ": the camera position (" + fmt(t.x()) + ", " + fmt(t.y()) + ", " + fmt(t.z()) +
                                  ") m is beyond the map frame's limit of +-" + fmt(kMaxCoordinateM) + " m");
}

/// "tx ty tz qx qy qz qw" (camera -> world) as in TUM / slambook2.
Eigen::Isometry3f pose_from_tum_line(const std::vector<std::string>& toks, const std::string& where, float tol) {
  if (toks.size() != 7)
    fail(ErrorCode::kParse, where + ": expected 7 numbers 'tx ty tz qx qy qz qw', got " + std::to_string(toks.size()));
  double v[7];
  for (std::size_t i = 0; i < 7; ++i) v[i] = parse_number(toks[i], where, i);
  Eigen::Quaterniond q(v[6], v[3], v[4], v[5]);  // (w, x, y, z)
  const double n = q.norm();
  if (!(std::fabs(n - 1.0) <= tol))
    fail(ErrorCode::kParse, where + ": quaternion (qx qy qz qw) has norm " + fmt(n) +
                                ", expected 1 (tolerance " + fmt(tol) + ")");
  q.normalize();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = q.toRotationMatrix();
  T.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
  check_translation(T.translation(), where);
  return T.cast<float>();
}

/// A 4x4 row-major camera -> world matrix (3dmatch).
Eigen::Isometry3f pose_from_matrix_file(const fs::path& p, float tol) {
  const std::vector<double> v = read_numbers(p, 16, "a 4x4 camera-to-world matrix");
  Eigen::Matrix4d M;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) M(r, c) = v[static_cast<std::size_t>(r * 4 + c)];
  if (std::fabs(M(3, 0)) > 1e-6 || std::fabs(M(3, 1)) > 1e-6 || std::fabs(M(3, 2)) > 1e-6 ||
      std::fabs(M(3, 3) - 1.0) > 1e-6)
    fail(ErrorCode::kParse, p.string() + ": the last row of the pose must be 0 0 0 1, got " + fmt(M(3, 0)) + " " +
                                fmt(M(3, 1)) + " " + fmt(M(3, 2)) + " " + fmt(M(3, 3)));
  const Eigen::Matrix3d R = M.topLeftCorner<3, 3>();
  const double err = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (!(err <= tol) || R.determinant() <= 0.0)
    fail(ErrorCode::kParse, p.string() + ": the rotation part is not a rotation (max |R^T R - I| = " + fmt(err) +
                                ", det = " + fmt(R.determinant()) + "; tolerance " + fmt(tol) + ")");
  // Re-orthonormalise: the nearest rotation U V^T.
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(R, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = svd.matrixU() * svd.matrixV().transpose();
  T.translation() = M.topRightCorner<3, 1>();
  check_translation(T.translation(), p.string());
  return T.cast<float>();
}

PinholeIntrinsics intrinsics_from_file(const fs::path& p) {
  const std::vector<double> v = read_numbers(p, 9, "a 3x3 camera matrix K");
  if (std::fabs(v[1]) > 1e-6 || std::fabs(v[3]) > 1e-6 || std::fabs(v[6]) > 1e-6 || std::fabs(v[7]) > 1e-6 ||
      std::fabs(v[8] - 1.0) > 1e-6)
    fail(ErrorCode::kParse, p.string() + ": expected K = [fx 0 cx; 0 fy cy; 0 0 1] (no skew)");
  if (!(v[0] > 0.0) || !(v[4] > 0.0))
    fail(ErrorCode::kParse, p.string() + ": focal lengths must be > 0, got fx = " + fmt(v[0]) + ", fy = " + fmt(v[4]));
  PinholeIntrinsics k;
  k.fx = static_cast<float>(v[0]);
  k.cx = static_cast<float>(v[2]);
  k.fy = static_cast<float>(v[4]);
  k.cy = static_cast<float>(v[5]);
  k.width = 0;  // from the images
  k.height = 0;
  return k;
}

std::string type_name(const cv::Mat& m) {
  const int depth = m.depth();
  const char* d = depth == CV_8U    ? "8-bit"
                  : depth == CV_8S  ? "8-bit signed"
                  : depth == CV_16U ? "16-bit"
                  : depth == CV_16S ? "16-bit signed"
                  : depth == CV_32S ? "32-bit integer"
                  : depth == CV_32F ? "32-bit float"
                  : depth == CV_64F ? "64-bit float"
                                    : "unknown-depth";
  return std::string(d) + " with " + std::to_string(m.channels()) + (m.channels() == 1 ? " channel" : " channels");
}

cv::Mat read_depth(const fs::path& p) {
  require_file(p, "missing frame file (depth image)", input_limits::kImageBytes, "depth image");
  cv::Mat d = cv::imread(p.string(), cv::IMREAD_UNCHANGED);
  if (d.empty()) fail(ErrorCode::kIo, p.string() + ": cannot decode the depth image");
  if (d.type() != CV_16UC1)
    fail(ErrorCode::kParse, p.string() + ": depth image is " + type_name(d) +
                                "; expected 16-bit single-channel raw depth (PNG or PGM)");
  return d;
}

std::string size_text(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

/// File stems that are all digits, mapped number -> path (e.g. color/12.png).
std::map<long long, fs::path> numbered_files(const fs::path& dir, const std::vector<std::string>& exts) {
  std::map<long long, fs::path> out;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string stem = e.path().stem().string();
    const std::string ext = e.path().extension().string();
    if (stem.empty() || stem.size() > 15 || !std::all_of(stem.begin(), stem.end(), [](char c) { return c >= '0' && c <= '9'; }))
      continue;
    const auto pos = std::find(exts.begin(), exts.end(), ext);
    if (pos == exts.end()) continue;
    const long long n = std::stoll(stem);
    // Prefer the earlier extension in `exts` when several exist.
    auto it = out.find(n);
    if (it == out.end() ||
        pos < std::find(exts.begin(), exts.end(), it->second.extension().string()))
      out[n] = e.path();
  }
  if (ec) fail(ErrorCode::kIo, dir.string() + ": cannot list the folder: " + ec.message());
  return out;
}

}  // namespace

SensorFrame RgbdFrame::sensor_frame(const Eigen::Isometry3f& T_target_camera) const {
  SensorFrame f;
  f.depth.data = depth.empty() ? nullptr : depth.data();
  f.depth.width = width;
  f.depth.height = height;
  f.depth.row_stride_bytes = 0;
  f.depth.format = DepthFormat::kU16;
  f.depth.depth_units_per_m = depth_units_per_m;
  if (!color.empty()) {
    f.color.data = &color.front().r;
    f.color.width = width;
    f.color.height = height;
    f.color.row_stride_bytes = 0;
    f.color.channels = 3;
    f.color.bgr = false;
  }
  f.intrinsics = intrinsics;
  f.T_robot_camera = T_target_camera;
  return f;
}

namespace {

/// "timestamp rest..." lines of a TUM list (comments and empty lines skipped), checked.
std::vector<std::pair<double, std::vector<std::string>>> read_tum_list(const fs::path& p, std::size_t fields, const char* what) {
  require_file(p, std::string("missing file (tum layout: ") + what + ")", input_limits::kTextBytes, what);
  std::vector<std::pair<double, std::vector<std::string>>> out;
  std::istringstream lines(read_text(p));
  std::string line;
  double last = -1e300;
  for (std::size_t ln = 1; std::getline(lines, line); ++ln) {
    const auto toks = split_ws(line);
    if (toks.empty() || toks.front().starts_with("#")) continue;
    const std::string where = p.string() + ":" + std::to_string(ln);
    if (toks.size() < fields)
      fail(ErrorCode::kParse, where + ": expected " + std::to_string(fields) + " fields, got " + std::to_string(toks.size()));
    const double t = parse_number(toks[0], where, 0);
    if (!(t > last)) fail(ErrorCode::kParse, where + ": stamp " + toks[0] + " is not after the previous line's (the list must be sorted, without duplicates)");
    last = t;
    out.emplace_back(t, std::vector<std::string>(toks.begin() + 1, toks.end()));
  }
  if (out.empty()) fail(ErrorCode::kParse, p.string() + ": no entries");
  return out;
}

/// Index of the entry of `list` nearest to t, or npos if none is within max_dt.
template <class L>
std::size_t nearest(const L& list, double t, double max_dt) {
  auto it = std::lower_bound(list.begin(), list.end(), t, [](const auto& e, double v) { return e.first < v; });
  std::size_t best = std::string::npos;
  double best_dt = max_dt;
  for (auto c : {it, it == list.begin() ? it : std::prev(it)}) {
    if (c == list.end()) continue;
    const double dt = std::abs(c->first - t);
    if (dt <= best_dt) {
      best_dt = dt;
      best = static_cast<std::size_t>(c - list.begin());
    }
  }
  return best;
}

}  // namespace

RgbdDataset RgbdDataset::open(const fs::path& dir, const RgbdDatasetOptions& options) {
  if (options.layout != "auto" && options.layout != "slambook2" && options.layout != "3dmatch" && options.layout != "tum")
    fail(ErrorCode::kInvalidArgument,
         "RgbdDatasetOptions::layout must be auto, slambook2, 3dmatch or tum, got '" + options.layout + "'");
  if (options.depth_units_per_m && !(*options.depth_units_per_m > 0.0f && std::isfinite(*options.depth_units_per_m)))
    fail(ErrorCode::kInvalidArgument, "RgbdDatasetOptions::depth_units_per_m must be > 0, got " +
                                          fmt(*options.depth_units_per_m));
  if (!(options.rotation_tolerance >= 0.0f && options.rotation_tolerance < 1.0f))
    fail(ErrorCode::kInvalidArgument, "RgbdDatasetOptions::rotation_tolerance must be in [0, 1), got " +
                                          fmt(options.rotation_tolerance));
  if (options.intrinsics) {
    const PinholeIntrinsics& k = *options.intrinsics;
    if (k.width <= 0 || k.height <= 0 || !(k.fx > 0.0f) || !(k.fy > 0.0f) || !std::isfinite(k.fx) ||
        !std::isfinite(k.fy) || !std::isfinite(k.cx) || !std::isfinite(k.cy))
      fail(ErrorCode::kInvalidArgument,
           "RgbdDatasetOptions::intrinsics: width, height must be > 0 and fx, fy > 0, cx, cy finite");
  }

  std::error_code ec;
  if (!fs::exists(dir, ec)) fail(ErrorCode::kIo, dir.string() + ": dataset folder not found");
  if (!is_dir(dir)) fail(ErrorCode::kIo, dir.string() + ": not a folder (expected an RGB-D dataset folder)");

  std::string layout = options.layout;
  if (layout == "auto" && is_file(dir / "rgb.txt") && is_file(dir / "depth.txt") &&
      (is_file(dir / "groundtruth.txt") || !options.require_poses))
    layout = "tum";
  if (layout == "auto") {
    const bool slambook = is_file(dir / "pose.txt") && is_dir(dir / "color") && is_dir(dir / "depth");
    bool match3d = is_file(dir / "camera-intrinsics.txt");
    if (!match3d)
      for (const auto& e : fs::directory_iterator(dir, ec)) {
        const std::string n = e.path().filename().string();
        if (n.starts_with("frame-") && (n.ends_with(".depth.png") || n.ends_with(".pose.txt"))) {
          match3d = true;
          break;
        }
      }
    if (slambook == match3d)
      fail(ErrorCode::kParse,
           dir.string() + (slambook ? ": looks like both RGB-D layouts; pass the layout explicitly"
                                    : ": not a known RGB-D dataset layout; expected slambook2 (pose.txt, "
                                      "color/N.png, depth/N.pgm) or 3dmatch (camera-intrinsics.txt, "
                                      "frame-NNNNNN.color.png, .depth.png, .pose.txt) or tum (rgb.txt, depth.txt, "
                                      "groundtruth.txt)"));
    layout = slambook ? "slambook2" : "3dmatch";
  }

  RgbdDataset ds;
  ds.root_ = dir;
  ds.layout_ = layout;
  ds.load_color_ = options.load_color;
  ds.depth_units_per_m_ = options.depth_units_per_m.value_or(kMillimetres);
  const float tol = options.rotation_tolerance;

  if (layout == "tum") {
    ds.depth_units_per_m_ = options.depth_units_per_m.value_or(5000.0f);  // TUM RGB-D: 5000 units per metre
    // rgb.txt and depth.txt ("timestamp filename"), groundtruth.txt ("timestamp tx ty tz qx qy
    // qz qw"); every depth frame is paired with the colour frame and the pose nearest in time
    // within 0.02 s (the TUM tools' associate.py default); depth frames without both are left out.
    const auto rgb = read_tum_list(dir / "rgb.txt", 2, "rgb.txt");
    const auto depth = read_tum_list(dir / "depth.txt", 2, "depth.txt");
    const bool has_poses = options.require_poses || is_file(dir / "groundtruth.txt");
    const auto gt = has_poses ? read_tum_list(dir / "groundtruth.txt", 8, "groundtruth.txt")
                                  : std::vector<std::pair<double, std::vector<std::string>>>{};
    for (const auto& [t, f] : depth) {
      const std::size_t c = nearest(rgb, t, 0.02), g = has_poses ? nearest(gt, t, 0.02) : 0;
      if (c == std::string::npos || g == std::string::npos) continue;
      char name[64];
      std::snprintf(name, sizeof name, "%.6f", t);
      Eigen::Isometry3f T = Eigen::Isometry3f::Identity();
      if (has_poses) {
        std::vector<std::string> pose(gt[g].second.begin(), gt[g].second.begin() + 7);
        T = pose_from_tum_line(pose, (dir / "groundtruth.txt").string() + " (stamp " + name + ")", tol);
      }
      ds.frames_.push_back(Entry{name, dir / rgb[c].second[0], dir / f[0], T});
      ds.frames_.back().stamp_s = t;
      require_file(ds.frames_.back().depth, "missing frame file (listed in depth.txt)", input_limits::kImageBytes, "depth image");
      require_file(ds.frames_.back().color, "missing frame file (listed in rgb.txt)", input_limits::kImageBytes, "colour image");
    }
    if (ds.frames_.empty())
      fail(ErrorCode::kParse, dir.string() + (has_poses ? ": no depth frame has a colour frame and a ground-truth pose within 0.02 s"
                                                             : ": no depth frame has a colour frame within 0.02 s"));
    if (options.intrinsics) ds.intrinsics_ = *options.intrinsics;
    else if (is_file(dir / "camera-intrinsics.txt")) ds.intrinsics_ = intrinsics_from_file(dir / "camera-intrinsics.txt");
    else ds.intrinsics_ = PinholeIntrinsics{};  // TUM's "ROS default" (525, 525, 319.5, 239.5) of 640x480
  } else if (layout == "slambook2") {
    const fs::path color_dir = dir / "color", depth_dir = dir / "depth", pose_file = dir / "pose.txt";
    if (!is_dir(color_dir)) fail(ErrorCode::kIo, color_dir.string() + ": missing folder (slambook2 layout)");
    if (!is_dir(depth_dir)) fail(ErrorCode::kIo, depth_dir.string() + ": missing folder (slambook2 layout)");
    require_file(pose_file, "missing file (slambook2 layout)", input_limits::kTextBytes, "pose list");
    const auto colors = numbered_files(color_dir, {".png", ".jpg"});
    const auto depths = numbered_files(depth_dir, {".pgm", ".png"});
    std::vector<long long> ids;
    for (const auto& [n, p] : colors) {
      if (!depths.count(n))
        fail(ErrorCode::kIo, (depth_dir / (std::to_string(n) + ".pgm")).string() + ": missing frame file (depth of " +
                                 p.string() + ")");
      ids.push_back(n);
    }
    for (const auto& [n, p] : depths)
      if (!colors.count(n))
        fail(ErrorCode::kIo, (color_dir / (std::to_string(n) + ".png")).string() + ": missing frame file (colour of " +
                                 p.string() + ")");
    if (ids.empty()) fail(ErrorCode::kParse, dir.string() + ": no frames (color/N.png + depth/N.pgm) found");
    // pose.txt pairs its k-th pose with the k-th frame: a gap in the numbers would pair every
    // later frame with the pose of another (silently wrong maps). Frames must be numbered
    // without gaps.
    for (std::size_t i = 1; i < ids.size(); ++i)
      if (ids[i] != ids[i - 1] + 1)
        fail(ErrorCode::kParse, (color_dir / (std::to_string(ids[i - 1] + 1) + ".png")).string() +
                                    ": missing frame: the frames jump from " + std::to_string(ids[i - 1]) + " to " +
                                    std::to_string(ids[i]) + "; pose.txt gives one pose per frame in order, so the frames "
                                    "must be numbered without gaps");

    // pose.txt: one line per frame; empty lines and '#' comments are skipped.
    std::vector<Eigen::Isometry3f> poses;
    std::istringstream lines(read_text(pose_file));
    std::string line;
    for (std::size_t ln = 1; std::getline(lines, line); ++ln) {
      const auto toks = split_ws(line);
      if (toks.empty() || toks.front().starts_with("#")) continue;
      poses.push_back(pose_from_tum_line(toks, pose_file.string() + ":" + std::to_string(ln), tol));
    }
    if (poses.size() != ids.size())
      fail(ErrorCode::kParse, pose_file.string() + ": has " + std::to_string(poses.size()) + " poses but the folder has " +
                                  std::to_string(ids.size()) + " frames (color/N.png + depth/N.pgm); expected one pose line per frame");
    for (std::size_t i = 0; i < ids.size(); ++i)
      ds.frames_.push_back(Entry{std::to_string(ids[i]), colors.at(ids[i]), depths.at(ids[i]), poses[i]});
    ds.intrinsics_ = options.intrinsics.value_or(slambook2_intrinsics());
  } else {
    // 3dmatch: frame-NNNNNN.{color.png, depth.png, pose.txt} + camera-intrinsics.txt.
    static const std::regex kName(R"(frame-(\d{1,15})\.(color\.png|color\.jpg|depth\.png|pose\.txt))");
    struct Files {
      fs::path color, depth, pose;
    };
    std::map<long long, Files> found;
    for (const auto& e : fs::directory_iterator(dir, ec)) {
      const std::string n = e.path().filename().string();
      std::smatch m;
      if (!std::regex_match(n, m, kName)) continue;
      Files& f = found[std::stoll(m[1].str())];
      const std::string kind = m[2].str();
      if (kind.starts_with("color")) {
        if (f.color.empty() || kind == "color.png") f.color = e.path();
      } else if (kind == "depth.png") {
        f.depth = e.path();
      } else {
        f.pose = e.path();
      }
    }
    if (ec) fail(ErrorCode::kIo, dir.string() + ": cannot list the folder: " + ec.message());
    if (found.empty()) fail(ErrorCode::kParse, dir.string() + ": no frames (frame-NNNNNN.depth.png) found");
    for (const auto& [n, f] : found) {
      // The stem as written in the folder (keeps the zero padding).
      const fs::path any = !f.depth.empty() ? f.depth : !f.color.empty() ? f.color : f.pose;
      const std::string fname = any.filename().string();
      const std::string name = fname.substr(0, fname.find('.'));
      if (f.depth.empty()) fail(ErrorCode::kIo, (dir / (name + ".depth.png")).string() + ": missing frame file");
      if (f.color.empty()) fail(ErrorCode::kIo, (dir / (name + ".color.png")).string() + ": missing frame file");
      if (f.pose.empty())
        fail(ErrorCode::kParse, (dir / (name + ".pose.txt")).string() +
                                    ": missing frame file: every frame needs a pose (pose count != frame count)");
      ds.frames_.push_back(Entry{name, f.color, f.depth, pose_from_matrix_file(f.pose, tol)});
    }
    if (options.intrinsics) {
      ds.intrinsics_ = *options.intrinsics;
    } else {
      const fs::path kfile = dir / "camera-intrinsics.txt";
      require_file(kfile, "missing file (3dmatch layout; or pass RgbdDatasetOptions::intrinsics)", input_limits::kTextBytes,
                   "intrinsics file");
      ds.intrinsics_ = intrinsics_from_file(kfile);
    }
  }

  // Image size from the first depth image; every frame must match it (load() checks).
  const cv::Mat first = read_depth(ds.frames_.front().depth);
  if (ds.intrinsics_.width == 0) {  // 3dmatch: K has no image size
    ds.intrinsics_.width = first.cols;
    ds.intrinsics_.height = first.rows;
  } else if (ds.intrinsics_.width != first.cols || ds.intrinsics_.height != first.rows) {
    fail(ErrorCode::kParse, ds.frames_.front().depth.string() + ": depth image is " + size_text(first.cols, first.rows) +
                                " but the intrinsics are for " +
                                size_text(ds.intrinsics_.width, ds.intrinsics_.height) + " images");
  }
  return ds;
}

const RgbdDataset::Entry& RgbdDataset::entry(std::size_t i) const {
  if (i >= frames_.size())
    fail(ErrorCode::kInvalidArgument, root_.string() + ": frame index " + std::to_string(i) + " out of range [0, " +
                                          std::to_string(frames_.size()) + ")");
  return frames_[i];
}

const std::string& RgbdDataset::frame_name(std::size_t i) const { return entry(i).name; }
const Eigen::Isometry3f& RgbdDataset::pose(std::size_t i) const { return entry(i).T_world_camera; }
double RgbdDataset::stamp(std::size_t i) const {
  const Entry& e = entry(i);
  return e.stamp_s >= 0.0 ? e.stamp_s : static_cast<double>(i) / 30.0;
}

RgbdFrame RgbdDataset::load(std::size_t i) const {
  const Entry& e = entry(i);
  const cv::Mat d = read_depth(e.depth);
  if (d.cols != intrinsics_.width || d.rows != intrinsics_.height)
    fail(ErrorCode::kParse, e.depth.string() + ": depth image is " + size_text(d.cols, d.rows) + ", expected " +
                                size_text(intrinsics_.width, intrinsics_.height) + " like the dataset's intrinsics");
  RgbdFrame f;
  f.name = e.name;
  f.width = d.cols;
  f.height = d.rows;
  f.depth_units_per_m = depth_units_per_m_;
  f.intrinsics = intrinsics_;
  f.T_world_camera = e.T_world_camera;
  const auto w = static_cast<std::size_t>(d.cols);
  f.depth.resize(w * static_cast<std::size_t>(d.rows));
  for (int r = 0; r < d.rows; ++r)
    std::copy_n(d.ptr<std::uint16_t>(r), w, f.depth.data() + static_cast<std::size_t>(r) * w);

  if (load_color_) {
    require_file(e.color, "missing frame file (colour image)", input_limits::kImageBytes, "colour image");
    const cv::Mat c = cv::imread(e.color.string(), cv::IMREAD_COLOR);  // 8-bit BGR
    if (c.empty()) fail(ErrorCode::kIo, e.color.string() + ": cannot decode the colour image");
    if (c.cols != d.cols || c.rows != d.rows)
      fail(ErrorCode::kParse, e.color.string() + ": colour image is " + size_text(c.cols, c.rows) + " but depth image " +
                                  e.depth.string() + " is " + size_text(d.cols, d.rows) + "; they must be registered");
    f.color.resize(f.depth.size());
    for (int r = 0; r < c.rows; ++r) {
      const auto* src = c.ptr<cv::Vec3b>(r);
      Rgb8* dst = f.color.data() + static_cast<std::size_t>(r) * w;
      for (std::size_t x = 0; x < w; ++x) dst[x] = Rgb8{src[x][2], src[x][1], src[x][0]};
    }
  }
  return f;
}

}  // namespace duet
