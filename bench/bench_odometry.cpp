// Odometry/{duet,duet_1t,opencv,open3d}/{7scenes,3dmatch,slambook2}: RGB-D odometry from one
// (3dmatch: its consecutive frames 0, 1, 2)
// frame to the next on real Kinect frames (../shared/data/rgbd), as a tracking loop runs it: the
// previous frame's work is cached, each iteration processes one new frame and estimates its motion.
//  - duet: VisualOdometer::track (runtime/localization/visual_odometer.hpp, default settings, no
//    guess): make_visual_frame (ORB, 3D points) of the new frame + estimate_motion against the
//    last location point;
//  - opencv: OpenCV contrib's cv::rgbd::RgbdOdometry (photometric, default settings), the new
//    frame's OdometryFrame cache prepared + compute against the cached previous one;
//  - open3d: Open3D's ComputeRGBDOdometry (hybrid photometric + geometric term, default
//    OdometryOption), which takes both RGBDImages per call (no cache in its API).
// Inputs are converted to what each library takes before timing (duet: RGB + uint16 depth as a
// Kinect gives them; OpenCV: grey + float metres; Open3D: RGBDImage).
// Counters (accuracy over every consecutive pair of the sequence, against its recorded poses,
// computed once outside the timing): rpe_mean_cm, rpe_max_cm, rpe_max_deg, fails (pairs the
// method reported as failed), and ate_cm (7scenes: the chained trajectory of 150 frames, ATE
// RMSE after rigid alignment).
// Odometry/duet/dual_640x480: two cameras (7-Scenes frames i and i + 75 as camera 0 and 1) - the
// paper robot's per-frame work.
#include "bench_util.hpp"

#include <duet/kernels/trajectory_eval.hpp>
#include <duet/kernels/visual_odometry.hpp>
#include <duet/runtime/io/rgbd_dataset.hpp>
#include <duet/runtime/localization/visual_odometer.hpp>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#ifdef DUET_HAVE_OPENCV_RGBD
#include <opencv2/rgbd.hpp>
#endif

#ifdef DUET_HAVE_OPEN3D
#include <open3d/camera/PinholeCameraIntrinsic.h>
#include <open3d/geometry/Image.h>
#include <open3d/geometry/RGBDImage.h>
#include <open3d/pipelines/odometry/Odometry.h>
#endif

#include <cstring>
#include <filesystem>
#include <map>
#include <memory>

namespace duet::bench {
namespace {

struct Frame {
  RgbdFrame raw;        // RGB + uint16 depth (duet's input)
  cv::Mat gray, depth;  // OpenCV's: CV_8UC1, CV_32FC1 metres (0 = none)
  Eigen::Isometry3d T_world_camera;
#ifdef DUET_HAVE_OPEN3D
  std::shared_ptr<open3d::geometry::RGBDImage> o3d;
#endif
};

struct Sequence {
  std::string name;
  std::vector<Frame> frames;
  PinholeIntrinsics K;
};

std::vector<Sequence>& sequences() {
  static std::vector<Sequence> seqs = [] {
    std::vector<Sequence> out;
    const std::filesystem::path root(DUET_BENCH_DATA_DIR);
    const std::pair<const char*, const char*> sets[] = {
        {"7scenes", "rgbd/7scenes_redkitchen"}, {"3dmatch", "rgbd/3dmatch_seq01"}, {"slambook2", "rgbd/slambook2_ch5"}};
    for (const auto& [name, dir] : sets) {
      if (!std::filesystem::exists(root / dir)) continue;
      const auto ds = RgbdDataset::open(root / dir);
      Sequence s;
      s.name = name;
      s.K = ds.intrinsics();
      // 3dmatch_seq01 holds frames 0, 1, 2, 116 and 422: only 0-1 and 1-2 are consecutive.
      const std::size_t n = std::string(name) == "3dmatch" ? std::min<std::size_t>(3, ds.size()) : ds.size();
      for (std::size_t i = 0; i < n; ++i) {
        Frame f;
        f.raw = ds.load(i);
        f.T_world_camera = f.raw.T_world_camera.cast<double>();
        const cv::Mat rgb(f.raw.height, f.raw.width, CV_8UC3, f.raw.color.data());
        cv::cvtColor(rgb, f.gray, cv::COLOR_RGB2GRAY);
        const cv::Mat d16(f.raw.height, f.raw.width, CV_16UC1, f.raw.depth.data());
        d16.convertTo(f.depth, CV_32FC1, 1.0 / f.raw.depth_units_per_m);
#ifdef DUET_HAVE_OPEN3D
        open3d::geometry::Image color, depth;
        color.Prepare(f.raw.width, f.raw.height, 3, 1);
        std::memcpy(color.data_.data(), f.raw.color.data(), color.data_.size());
        depth.Prepare(f.raw.width, f.raw.height, 1, 2);
        std::memcpy(depth.data_.data(), f.raw.depth.data(), depth.data_.size());
        f.o3d = open3d::geometry::RGBDImage::CreateFromColorAndDepth(color, depth, f.raw.depth_units_per_m, 4.0);
#endif
        s.frames.push_back(std::move(f));
      }
      out.push_back(std::move(s));
    }
    return out;
  }();
  return seqs;
}

/// One tracker per library: start(frame) caches the first frame, step(frame) returns T_prev_curr
/// (ok = false when the library reports failure) and caches the new frame.
class Tracker {
 public:
  virtual ~Tracker() = default;
  virtual void start(const Frame& f) = 0;
  virtual Eigen::Isometry3d step(const Frame& f, bool& ok) = 0;
};

/// duet as the runtime runs it: VisualOdometer (location points, default settings).
class DuetTracker final : public Tracker {
 public:
  void start(const Frame& f) override {
    vo_.reset();
    const SensorFrame s = f.raw.sensor_frame();
    (void)vo_.track(std::span(&s, 1));
  }
  Eigen::Isometry3d step(const Frame& f, bool& ok) override {
    const SensorFrame s = f.raw.sensor_frame();
    const auto r = vo_.track(std::span(&s, 1));
    ok = r.result.status == VisualOdometryStatus::kOk;
    return r.increment;
  }

 private:
  VisualOdometer vo_;
};

#ifdef DUET_HAVE_OPENCV_RGBD
class OpenCvTracker final : public Tracker {
 public:
  explicit OpenCvTracker(const PinholeIntrinsics& K) {
    const cv::Mat cam = (cv::Mat_<float>(3, 3) << K.fx, 0, K.cx, 0, K.fy, K.cy, 0, 0, 1);
    odo_ = cv::rgbd::RgbdOdometry::create(cam);
  }
  void start(const Frame& f) override { prev_ = make(f); }
  Eigen::Isometry3d step(const Frame& f, bool& ok) override {
    cv::Ptr<cv::rgbd::OdometryFrame> curr = make(f);
    cv::Mat Rt;
    ok = odo_->compute(prev_, curr, Rt);  // curr_p = Rt * prev_p: Rt = T_curr_prev
    prev_ = curr;
    Eigen::Matrix4d M = Eigen::Matrix4d::Identity();
    if (ok)
      for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) M(r, c) = Rt.at<double>(r, c);
    Eigen::Isometry3d T(M);
    return T.inverse();
  }

 private:
  cv::Ptr<cv::rgbd::OdometryFrame> make(const Frame& f) {
    auto frame = cv::rgbd::OdometryFrame::create(f.gray, f.depth);
    odo_->prepareFrameCache(frame, cv::rgbd::OdometryFrame::CACHE_ALL);
    return frame;
  }
  cv::Ptr<cv::rgbd::RgbdOdometry> odo_;
  cv::Ptr<cv::rgbd::OdometryFrame> prev_;
};
#endif

#ifdef DUET_HAVE_OPEN3D
class Open3dTracker final : public Tracker {
 public:
  explicit Open3dTracker(const PinholeIntrinsics& K) : K_(K.width, K.height, K.fx, K.fy, K.cx, K.cy) {}
  void start(const Frame& f) override { prev_ = &f; }
  Eigen::Isometry3d step(const Frame& f, bool& ok) override {
    // source = current, target = previous: the result maps current points into the previous frame.
    const auto [success, T, info] = open3d::pipelines::odometry::ComputeRGBDOdometry(*f.o3d, *prev_->o3d, K_);
    (void)info;
    ok = success;
    prev_ = &f;
    return Eigen::Isometry3d(T);
  }

 private:
  open3d::camera::PinholeCameraIntrinsic K_;
  const Frame* prev_ = nullptr;
};
#endif

std::unique_ptr<Tracker> make_tracker(const std::string& impl, const Sequence& s) {
#ifdef DUET_HAVE_OPENCV_RGBD
  if (impl == "opencv") return std::make_unique<OpenCvTracker>(s.K);
#endif
#ifdef DUET_HAVE_OPEN3D
  if (impl == "open3d") return std::make_unique<Open3dTracker>(s.K);
#endif
  return std::make_unique<DuetTracker>();
}

struct Accuracy {
  double rpe_mean_cm = 0, rpe_max_cm = 0, rpe_max_deg = 0, ate_cm = -1;
  int fails = 0;
};

/// Every consecutive pair of the sequence, chained; once per (impl, sequence).
const Accuracy& accuracy(const std::string& impl, int threads, const Sequence& s) {
  static std::map<std::string, Accuracy> cache;
  const std::string key = impl + "/" + s.name;
  if (auto it = cache.find(key); it != cache.end()) return it->second;
  Accuracy a;
  arena(threads).execute([&] {
    auto tracker = make_tracker(impl, s);
    tracker->start(s.frames[0]);
    std::vector<StampedPose> est{{0.0, Eigen::Isometry3d::Identity()}}, gt{{0.0, s.frames[0].T_world_camera}};
    double sum = 0.0;
    for (std::size_t i = 1; i < s.frames.size(); ++i) {
      bool ok = false;
      const Eigen::Isometry3d m = tracker->step(s.frames[i], ok);
      a.fails += ok ? 0 : 1;
      const Eigen::Isometry3d truth = s.frames[i - 1].T_world_camera.inverse() * s.frames[i].T_world_camera;
      const Eigen::Isometry3d E = truth.inverse() * (ok ? m : Eigen::Isometry3d::Identity());
      const double cm = 100.0 * E.translation().norm();
      sum += cm;
      a.rpe_max_cm = std::max(a.rpe_max_cm, cm);
      a.rpe_max_deg = std::max(a.rpe_max_deg, Eigen::AngleAxisd(E.linear()).angle() * 180.0 / 3.141592653589793);
      est.push_back({static_cast<double>(i), est.back().pose * (ok ? m : Eigen::Isometry3d::Identity())});
      gt.push_back({static_cast<double>(i), s.frames[i].T_world_camera});
    }
    a.rpe_mean_cm = sum / static_cast<double>(s.frames.size() - 1);
    if (s.frames.size() >= 10) a.ate_cm = 100.0 * absolute_trajectory_error(est, gt).translation.rmse;
  });
  return cache[key] = a;
}

void run(benchmark::State& state, const std::string& impl, int threads, const Sequence& s) {
  run_guarded(state, [&] {
    const Accuracy& a = accuracy(impl, threads, s);
    auto tracker = make_tracker(impl, s);
    arena(threads).execute([&] {
      std::size_t i = 0;
      tracker->start(s.frames[0]);
      for (auto _ : state) {
        i = (i + 1) % s.frames.size();
        if (i == 0) {  // wrap: restart outside the timing
          state.PauseTiming();
          tracker->start(s.frames[0]);
          state.ResumeTiming();
          i = 1;
        }
        bool ok = false;
        benchmark::DoNotOptimize(tracker->step(s.frames[i], ok));
      }
    });
    state.counters["rpe_mean_cm"] = a.rpe_mean_cm;
    state.counters["rpe_max_cm"] = a.rpe_max_cm;
    state.counters["rpe_max_deg"] = a.rpe_max_deg;
    state.counters["fails"] = a.fails;
    if (a.ate_cm >= 0) state.counters["ate_cm"] = a.ate_cm;
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
    state.SetLabel(std::to_string(s.frames.size()) + " real frames");
  });
}

}  // namespace

void register_odometry() {
  for (const Sequence& s : sequences()) {
    const Sequence* sp = &s;
    for (const DuetImpl impl : kDuetImpls)
      benchmark::RegisterBenchmark(bench_name("Odometry", impl.name, s.name).c_str(),
                                   [sp, impl](benchmark::State& st) { run(st, "duet", impl.threads, *sp); })
          ->UseRealTime();
#ifdef DUET_HAVE_OPENCV_RGBD
    benchmark::RegisterBenchmark(bench_name("Odometry", "opencv", s.name).c_str(),
                                 [sp](benchmark::State& st) { run(st, "opencv", 2, *sp); })
        ->UseRealTime();
#endif
#ifdef DUET_HAVE_OPEN3D
    benchmark::RegisterBenchmark(bench_name("Odometry", "open3d", s.name).c_str(),
                                 [sp](benchmark::State& st) { run(st, "open3d", 2, *sp); })
        ->UseRealTime();
#endif
  }
  // Two cameras per robot frame: 7-Scenes frame i as camera 0 and frame i + 75 as camera 1.
  const Sequence* kitchen = nullptr;
  for (const Sequence& s : sequences())
    if (s.name == "7scenes") kitchen = &s;
  if (kitchen == nullptr) return;
  benchmark::RegisterBenchmark("Odometry/duet/dual_640x480", [kitchen](benchmark::State& state) {
    run_guarded(state, [&] {
      const std::size_t n = kitchen->frames.size() / 2;
      auto pair = [&](std::size_t i) {
        std::array<SensorFrame, 2> f{kitchen->frames[i].raw.sensor_frame(), kitchen->frames[i + n].raw.sensor_frame()};
        f[1].T_robot_camera.linear() = Eigen::AngleAxisf(-1.5707963f, Eigen::Vector3f::UnitY()).toRotationMatrix();
        return f;
      };
      VisualFrame prev, curr;
      std::size_t inliers = 0;
      arena(2).execute([&] {
        make_visual_frame(pair(0), {}, prev);
        std::size_t i = 0;
        for (auto _ : state) {
          i = i + 1 < n ? i + 1 : 1;
          make_visual_frame(pair(i), {}, curr);
          const auto r = estimate_motion(prev, curr, Eigen::Isometry3d::Identity(), {});
          inliers = r.inliers;
          std::swap(prev, curr);
        }
      });
      state.counters["inliers"] = static_cast<double>(inliers);
      state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
      state.SetLabel("2 cameras x 640x480, real frames");
    });
  })->UseRealTime();
}

}  // namespace duet::bench
