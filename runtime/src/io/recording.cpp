/// @file recording.cpp
/// Recording and replaying a robot's input streams (see recording.hpp, docs/recording.md).
#include <duet/kernels/error.hpp>
#include <duet/runtime/io/input_limits.hpp>
#include <duet/runtime/io/output.hpp>
#include <duet/runtime/io/recording.hpp>

#include "io/file_util.hpp"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <yaml-cpp/yaml.h>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <utility>
#include <sstream>

namespace duet {
namespace fs = std::filesystem;
namespace {

constexpr const char* kFormat = "duet-recording";
constexpr int kVersion = 1;

/// The shortest decimal that reads back to exactly `v`.
template <class T>
std::string exact(T v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

std::string sensor_folder(const SensorProfile& s, std::size_t i) {
  std::string name;
  for (const char c : s.name) name += (std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-') ? c : '_';
  return name.empty() ? "sensor" + std::to_string(i) : name;
}

}  // namespace

// ---- Recorder -----------------------------------------------------------------------------

struct Recorder::Job {
  std::size_t sensor = 0;
  std::uint64_t index = 0;
  double stamp = 0.0, arrival = 0.0;
  RgbdImage image;
};

Recorder::Recorder(const fs::path& dir, const Profile& profile, const RecorderSettings& settings)
    : dir_(dir), profile_(profile), settings_(settings), next_index_(profile.sensors.size(), 0) {
  if (settings.queue_frames < 1 || settings.queue_frames > 4096)
    fail(ErrorCode::kInvalidArgument, "RecorderSettings::queue_frames must be in [1, 4096], got " + std::to_string(settings.queue_frames));
  if (settings.png_compression < 0 || settings.png_compression > 9)
    fail(ErrorCode::kInvalidArgument, "RecorderSettings::png_compression must be in [0, 9], got " + std::to_string(settings.png_compression));
  std::error_code ec;
  if (fs::exists(dir, ec) && !(fs::is_directory(dir, ec) && fs::is_empty(dir, ec)))
    fail(ErrorCode::kIo, dir.string() + ": a recording needs an empty or new folder (this one is not empty, or is a file)");
  prepare_output_dir(dir);
  for (std::size_t i = 0; i < profile.sensors.size(); ++i) {
    const fs::path s = dir / sensor_folder(profile.sensors[i], i);
    fs::create_directories(s / "rgb", ec);
    fs::create_directories(s / "depth", ec);
    if (ec) fail(ErrorCode::kIo, (s / "depth").string() + ": cannot create the folder: " + ec.message());
    for (const char* list : {"depth.txt", "rgb.txt"}) {
      std::ofstream& f = (list[0] == 'd' ? depth_lists_ : rgb_lists_).emplace_back(s / list);
      if (!f) fail(ErrorCode::kIo, (s / list).string() + ": cannot be created");
      f << "# stamp file arrival (duet recording: the runtime's time line [s])\n";
    }
  }
  write_text_file(dir / "profile.yaml", to_yaml(profile));
  odometry_.open(dir / "odometry.txt");
  if (!odometry_) fail(ErrorCode::kIo, (dir / "odometry.txt").string() + ": cannot be created");
  odometry_ << "# stamp x y theta v omega arrival (duet recording: [s, m, rad, m/s, rad/s, s])\n";
  thread_ = std::thread([this] { writer(); });
}

Recorder::~Recorder() {
  try {
    close();
  } catch (...) {
    // The error was in stats(); a destructor cannot throw.
  }
}

void Recorder::frame(std::size_t sensor, const StampedRgbd& f, double arrival_s) {
  if (sensor >= next_index_.size()) fail(ErrorCode::kInvalidArgument, "Recorder: sensor " + std::to_string(sensor) + " out of range");
  std::unique_lock lock(mutex_);
  if (closing_) return;
  if (jobs_.size() >= settings_.queue_frames) {
    if (!settings_.block_when_full) {
      ++stats_.frames_dropped;
      return;
    }
    space_cv_.wait(lock, [&] { return jobs_.size() < settings_.queue_frames || closing_; });
  }
  Job j;
  j.sensor = sensor;
  j.index = next_index_[sensor]++;
  j.stamp = f.stamp_s;
  j.arrival = arrival_s;
  j.image = f.image;  // the copy (outside the runtime's buffers)
  jobs_.push_back(std::move(j));
  cv_.notify_one();
}

void Recorder::odometry(const OdometryMsg& m, double arrival_s) {
  std::lock_guard lock(mutex_);
  if (closing_) return;
  odometry_ << exact(m.stamp_s) << ' ' << exact(m.pose.x) << ' ' << exact(m.pose.y) << ' ' << exact(m.pose.theta) << ' '
            << exact(m.twist.v) << ' ' << exact(m.twist.omega) << ' ' << exact(arrival_s) << '\n';
  ++stats_.odometry_recorded;
}

void Recorder::writer() {
  const std::vector<int> png{cv::IMWRITE_PNG_COMPRESSION, settings_.png_compression};
  for (;;) {
    Job j;
    {
      std::unique_lock lock(mutex_);
      cv_.wait(lock, [&] { return !jobs_.empty() || closing_; });
      if (jobs_.empty()) return;
      j = std::move(jobs_.front());
      jobs_.pop_front();
      space_cv_.notify_all();
    }
    const SensorProfile& s = profile_.sensors[j.sensor];
    const fs::path folder = dir_ / sensor_folder(s, j.sensor);
    char name[32];
    std::snprintf(name, sizeof name, "%06llu.png", static_cast<unsigned long long>(j.index));
    std::string err;
    try {
      const int w = j.image.width, h = j.image.height;
      const bool has_depth = j.image.depth.size() == static_cast<std::size_t>(w) * h && w > 0;
      cv::Mat depth = has_depth ? cv::Mat(h, w, CV_16UC1, j.image.depth.data()) : cv::Mat(std::max(h, 1), std::max(w, 1), CV_16UC1, cv::Scalar(0));
      if (!cv::imwrite((folder / "depth" / name).string(), depth, png)) err = (folder / "depth" / name).string() + ": cannot be written";
      const bool has_rgb = has_depth && j.image.rgb.size() == static_cast<std::size_t>(w) * h * 3;
      if (err.empty() && has_rgb) {
        cv::Mat rgb(h, w, CV_8UC3, j.image.rgb.data()), bgr;
        cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
        if (!cv::imwrite((folder / "rgb" / name).string(), bgr, png)) err = (folder / "rgb" / name).string() + ": cannot be written";
      }
      if (err.empty()) {
        std::ofstream& d = depth_lists_[j.sensor];
        std::ofstream& c = rgb_lists_[j.sensor];
        d << exact(j.stamp) << " depth/" << name << ' ' << exact(j.arrival) << '\n';
        if (has_rgb) c << exact(j.stamp) << " rgb/" << name << ' ' << exact(j.arrival) << '\n';
        if (!d || !c) err = folder.string() + ": cannot append to depth.txt / rgb.txt";
      }
    } catch (const std::exception& e) {
      err = e.what();
    }
    std::lock_guard lock(mutex_);
    if (err.empty()) ++stats_.frames_recorded;
    else if (stats_.error.empty()) stats_.error = err;
  }
}

void Recorder::close() {
  {
    std::lock_guard lock(mutex_);
    if (closed_) return;
    closing_ = true;
    cv_.notify_all();
    space_cv_.notify_all();
  }
  if (thread_.joinable()) thread_.join();
  std::lock_guard lock(mutex_);
  closed_ = true;
  odometry_.flush();
  if (!odometry_ && stats_.error.empty()) stats_.error = (dir_ / "odometry.txt").string() + ": write failed";
  odometry_.close();
  for (auto* lists : {&depth_lists_, &rgb_lists_})
    for (std::ofstream& f : *lists) {
      f.flush();
      if (!f && stats_.error.empty()) stats_.error = dir_.string() + ": a frame list could not be written";
      f.close();
    }
  YAML::Emitter y;
  y << YAML::BeginMap << YAML::Key << "format" << YAML::Value << kFormat << YAML::Key << "version" << YAML::Value << kVersion;
  y << YAML::Key << "profile" << YAML::Value << "profile.yaml" << YAML::Key << "odometry" << YAML::Value << "odometry.txt";
  y << YAML::Key << "sensors" << YAML::Value << YAML::BeginSeq;
  for (std::size_t i = 0; i < profile_.sensors.size(); ++i) {
    const SensorProfile& s = profile_.sensors[i];
    y << YAML::BeginMap << YAML::Key << "name" << YAML::Value << s.name << YAML::Key << "folder" << YAML::Value << sensor_folder(s, i)
      << YAML::Key << "width" << YAML::Value << s.intrinsics.width << YAML::Key << "height" << YAML::Value << s.intrinsics.height
      << YAML::Key << "depth_units_per_m" << YAML::Value << s.depth_units_per_m << YAML::EndMap;
  }
  y << YAML::EndSeq << YAML::Key << "frames_recorded" << YAML::Value << stats_.frames_recorded << YAML::Key << "frames_dropped"
    << YAML::Value << stats_.frames_dropped << YAML::Key << "odometry_recorded" << YAML::Value << stats_.odometry_recorded << YAML::EndMap;
  write_text_file(dir_ / "recording.yaml", std::string(y.c_str()) + "\n");
  if (!stats_.error.empty()) fail(ErrorCode::kIo, "recording " + dir_.string() + ": " + stats_.error);
}

RecorderStats Recorder::stats() const {
  std::lock_guard lock(mutex_);
  return stats_;
}

// ---- RecordingSource ----------------------------------------------------------------------

class RecordingSource::Chassis final : public ChassisInterface {
 public:
  Chassis(RecordingSource& s) : s_(s) {}
  void command(const Twist& cmd) override { s_.inner_.chassis().command(cmd); }
  std::vector<OdometryMsg> take_odometry() override {
    std::vector<OdometryMsg> out = s_.inner_.chassis().take_odometry();
    for (const OdometryMsg& m : out) s_.recorder_.odometry(m, s_.now_);
    return out;
  }

 private:
  RecordingSource& s_;
};

class RecordingSource::Sensor final : public RgbdSensorInterface {
 public:
  Sensor(RecordingSource& s, std::size_t i) : s_(s), i_(i) {}
  std::vector<StampedRgbd> take_frames() override {
    std::vector<StampedRgbd> out = s_.inner_.sensors()[i_]->take_frames();
    for (const StampedRgbd& f : out) s_.recorder_.frame(i_, f, s_.now_);
    return out;
  }
  void recycle(RgbdImage&& image) override { s_.inner_.sensors()[i_]->recycle(std::move(image)); }

 private:
  RecordingSource& s_;
  std::size_t i_;
};

RecordingSource::RecordingSource(RobotSource& inner, Recorder& recorder)
    : inner_(inner), recorder_(recorder), chassis_(std::make_unique<Chassis>(*this)) {
  for (std::size_t i = 0; i < inner.sensors().size(); ++i) {
    sensors_.push_back(std::make_unique<Sensor>(*this, i));
    ifaces_.push_back(sensors_.back().get());
  }
}

RecordingSource::~RecordingSource() = default;

ChassisInterface& RecordingSource::chassis() { return *chassis_; }

void RecordingSource::advance(double now_s) {
  now_ = now_s;
  inner_.advance(now_s);
}

// ---- reading ------------------------------------------------------------------------------

namespace {

/// The numbers of one line; fails naming file:line.
std::vector<std::string> fields(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> out;
  for (std::string f; in >> f;) out.push_back(f);
  return out;
}

/// A finite number of type T (double for stamps, float for poses and twists); fails naming file:line.
template <class T = double>
T number(const std::string& text, const fs::path& file, std::size_t line, const char* what) {
  T v{};
  const auto r = std::from_chars(text.data(), text.data() + text.size(), v);
  if (r.ec != std::errc() || r.ptr != text.data() + text.size() || !std::isfinite(v))
    fail(ErrorCode::kParse, file.string() + ":" + std::to_string(line) + ": " + what + " '" + text + "' is not a finite number");
  return v;
}

/// One line of a frame list: "stamp file [arrival]" (without arrival: the stamp).
struct ListLine {
  double stamp = 0.0, arrival = 0.0;
  std::string file;
};
ListLine list_line(const std::vector<std::string>& f, const fs::path& list, std::size_t line) {
  if (f.size() != 2 && f.size() != 3)
    fail(ErrorCode::kParse, list.string() + ":" + std::to_string(line) + ": expected 'stamp file [arrival]', got " + std::to_string(f.size()) + " fields");
  ListLine l;
  l.stamp = number(f[0], list, line, "stamp");
  l.arrival = f.size() == 3 ? number(f[2], list, line, "arrival") : l.stamp;
  l.file = f[1];
  return l;
}

template <class F>
void for_lines(const fs::path& file, F&& body) {
  const std::string text = detail::read_whole_file(file, input_limits::kTextBytes, "recording list");
  std::istringstream in(text);
  std::size_t n = 0;
  for (std::string line; std::getline(in, line);) {
    ++n;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    body(fields(line), n);
  }
}

}  // namespace

double Recording::end_s() const {
  double t = odometry.empty() ? 0.0 : odometry.back().second;
  for (const auto& s : frames)
    if (!s.empty()) t = std::max(t, s.back().arrival_s);
  return t;
}

Recording read_recording(const fs::path& dir) {
  Recording rec;
  rec.dir = dir;
  const fs::path meta = dir / "recording.yaml";
  const std::string text = detail::read_whole_file(meta, input_limits::kYamlBytes, "recording.yaml");
  YAML::Node y;
  try {
    y = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    fail(ErrorCode::kParse, meta.string() + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  if (!y.IsMap() || !y["format"] || y["format"].as<std::string>("") != kFormat)
    fail(ErrorCode::kParse, meta.string() + ": not a duet recording (format: " + std::string(kFormat) + " expected)");
  if (y["version"].as<int>(0) != kVersion)
    fail(ErrorCode::kParse, meta.string() + ": version " + y["version"].as<std::string>("?") + " (this duet reads version " + std::to_string(kVersion) + ")");
  rec.profile = load_profile(dir / y["profile"].as<std::string>("profile.yaml"));
  const YAML::Node sensors = y["sensors"];
  if (!sensors.IsSequence() || sensors.size() != rec.profile.sensors.size())
    fail(ErrorCode::kParse, meta.string() + ": sensors must list the profile's " + std::to_string(rec.profile.sensors.size()) + " sensors");
  // Odometry.
  const fs::path odom = dir / y["odometry"].as<std::string>("odometry.txt");
  double last_arrival = -1e300;
  for_lines(odom, [&](const std::vector<std::string>& f, std::size_t line) {
    if (f.size() != 6 && f.size() != 7)
      fail(ErrorCode::kParse, odom.string() + ":" + std::to_string(line) + ": expected 'stamp x y theta v omega [arrival]', got " + std::to_string(f.size()) + " fields");
    OdometryMsg m;
    m.stamp_s = number(f[0], odom, line, "stamp");
    m.pose = Pose2{number<float>(f[1], odom, line, "x"), number<float>(f[2], odom, line, "y"), number<float>(f[3], odom, line, "theta")};
    m.twist = Twist{number<float>(f[4], odom, line, "v"), number<float>(f[5], odom, line, "omega")};
    const double arrival = f.size() == 7 ? number(f[6], odom, line, "arrival") : m.stamp_s;
    if (arrival < last_arrival)
      fail(ErrorCode::kParse, odom.string() + ":" + std::to_string(line) + ": " + (f.size() == 7 ? "arrival" : "stamp") +
                                  " goes back in time (the lines must be in arrival order)");
    last_arrival = arrival;
    rec.odometry.emplace_back(m, arrival);
  });
  // Frames.
  for (std::size_t i = 0; i < sensors.size(); ++i) {
    const fs::path folder = dir / sensors[i]["folder"].as<std::string>("");
    const fs::path depth_list = folder / "depth.txt", rgb_list = folder / "rgb.txt";
    std::vector<RecordedFrameRef> frames;
    double last = -1e300;
    for_lines(depth_list, [&](const std::vector<std::string>& f, std::size_t line) {
      const ListLine l = list_line(f, depth_list, line);
      if (l.arrival < last)
        fail(ErrorCode::kParse, depth_list.string() + ":" + std::to_string(line) + ": " + (f.size() == 3 ? "arrival" : "stamp") +
                                    " goes back in time (the lines must be in arrival order)");
      last = l.arrival;
      RecordedFrameRef r;
      r.stamp_s = l.stamp;
      r.arrival_s = l.arrival;
      r.depth = folder / l.file;
      frames.push_back(std::move(r));
    });
    // Colour by (stamp, arrival): a frame without colour has no rgb line.
    std::size_t k = 0;
    for_lines(rgb_list, [&](const std::vector<std::string>& f, std::size_t line) {
      const ListLine l = list_line(f, rgb_list, line);
      while (k < frames.size() && !(frames[k].stamp_s == l.stamp && frames[k].arrival_s == l.arrival)) ++k;
      if (k == frames.size())
        fail(ErrorCode::kParse, rgb_list.string() + ":" + std::to_string(line) + ": no depth frame with stamp " + f[0] + " in depth.txt (in order)");
      frames[k++].rgb = folder / l.file;
    });
    rec.frames.push_back(std::move(frames));
  }
  return rec;
}

// ---- ReplaySource -------------------------------------------------------------------------

class ReplaySource::Chassis final : public ChassisInterface {
 public:
  void command(const Twist& cmd) override {
    (void)cmd;
    ++commands;
  }
  std::vector<OdometryMsg> take_odometry() override { return std::exchange(out, {}); }
  std::vector<OdometryMsg> out;
  std::size_t commands = 0;
};

class ReplaySource::Sensor final : public RgbdSensorInterface {
 public:
  Sensor(const SensorProfile& s) : sensor(s) {}
  std::vector<StampedRgbd> take_frames() override { return std::exchange(out, {}); }
  void deliver(const RecordedFrameRef& r) {
    StampedRgbd f;
    f.stamp_s = r.stamp_s;
    (void)detail::check_input_file(r.depth, input_limits::kImageBytes, "depth image");
    const cv::Mat d = cv::imread(r.depth.string(), cv::IMREAD_UNCHANGED);
    if (d.empty()) fail(ErrorCode::kIo, r.depth.string() + ": cannot decode the depth image");
    if (d.type() != CV_16UC1) fail(ErrorCode::kParse, r.depth.string() + ": depth must be a 16-bit single-channel PNG");
    const int w = sensor.intrinsics.width, h = sensor.intrinsics.height;
    if (d.cols != w || d.rows != h)
      fail(ErrorCode::kParse, r.depth.string() + ": " + std::to_string(d.cols) + "x" + std::to_string(d.rows) + " px, sensor '" + sensor.name +
                                  "' is " + std::to_string(w) + "x" + std::to_string(h));
    f.image.width = w;
    f.image.height = h;
    f.image.depth.resize(static_cast<std::size_t>(w) * h);
    for (int y = 0; y < h; ++y) std::memcpy(f.image.depth.data() + static_cast<std::size_t>(y) * w, d.ptr<std::uint16_t>(y), 2 * static_cast<std::size_t>(w));
    if (!r.rgb.empty()) {
      (void)detail::check_input_file(r.rgb, input_limits::kImageBytes, "colour image");
      const cv::Mat c = cv::imread(r.rgb.string(), cv::IMREAD_COLOR);
      if (c.empty()) fail(ErrorCode::kIo, r.rgb.string() + ": cannot decode the colour image");
      if (c.cols != w || c.rows != h) fail(ErrorCode::kParse, r.rgb.string() + ": colour size differs from the depth's");
      cv::Mat rgb;
      cv::cvtColor(c, rgb, cv::COLOR_BGR2RGB);
      f.image.rgb.resize(static_cast<std::size_t>(w) * h * 3);
      for (int y = 0; y < h; ++y) std::memcpy(f.image.rgb.data() + static_cast<std::size_t>(y) * w * 3, rgb.ptr<std::uint8_t>(y), 3 * static_cast<std::size_t>(w));
    }
    out.push_back(std::move(f));
  }
  const SensorProfile& sensor;
  std::vector<StampedRgbd> out;
};

ReplaySource::ReplaySource(const Recording& recording)
    : rec_(recording), chassis_(std::make_unique<Chassis>()), next_frame_(recording.frames.size(), 0) {
  for (std::size_t i = 0; i < recording.profile.sensors.size(); ++i) {
    sensors_.push_back(std::make_unique<Sensor>(recording.profile.sensors[i]));
    ifaces_.push_back(sensors_.back().get());
  }
}

ReplaySource::~ReplaySource() = default;

ChassisInterface& ReplaySource::chassis() { return *chassis_; }

void ReplaySource::advance(double now_s) {
  while (next_odom_ < rec_.odometry.size() && rec_.odometry[next_odom_].second <= now_s)
    chassis_->out.push_back(rec_.odometry[next_odom_++].first);
  for (std::size_t i = 0; i < rec_.frames.size(); ++i)
    while (next_frame_[i] < rec_.frames[i].size() && rec_.frames[i][next_frame_[i]].arrival_s <= now_s)
      sensors_[i]->deliver(rec_.frames[i][next_frame_[i]++]);
}

bool ReplaySource::finished() const noexcept {
  if (next_odom_ < rec_.odometry.size()) return false;
  for (std::size_t i = 0; i < rec_.frames.size(); ++i)
    if (next_frame_[i] < rec_.frames[i].size()) return false;
  return true;
}

std::size_t ReplaySource::commands() const noexcept { return chassis_->commands; }

}  // namespace duet
