#pragma once
/// @file recording.hpp
/// Recording a robot's input streams and replaying them (issue 20, part 3). A recording is a
/// folder close to TUM RGB-D's layout (docs/recording.md):
///
///   recording.yaml        format, version, the sensors (name, folder, size, depth units), counts
///   profile.yaml          the profile the run used, every key (`duet profile` prints the same)
///   odometry.txt          "stamp x y theta v omega arrival" per message [s, m, rad, m/s, rad/s, s]
///   <sensor>/rgb.txt      "stamp file arrival" per frame (TUM's "timestamp filename" + arrival)
///   <sensor>/depth.txt    "stamp file arrival"
///   <sensor>/rgb/N.png    8-bit RGB (absent for a frame without colour)
///   <sensor>/depth/N.png  16-bit depth in the sensor's depth units (0 = no return)
///
/// Stamps are the runtime's time line; `arrival` is the runtime time of the control period that
/// took the message (a late or reordered message arrives after its stamp). Numbers are written
/// in their shortest form that reads back exactly, so a replay feeds the runtime bit-identical
/// input. Readers of plain TUM files may ignore the third column; ours, without it, deliver a
/// message at the first control period at or after its stamp.
///
/// RecordingSource records what a RobotSource delivers to the runtime (after any fault
/// injection); ReplaySource is a RobotSource that delivers a recording at its arrival times.
///
/// Thread safety: a Recorder's frame()/odometry() from one thread at a time (the control
/// thread), its writer runs on a thread of its own; stats() from any thread. ReplaySource:
/// one thread.
#include <duet/runtime/config/profile.hpp>
#include <duet/runtime/robot/robot_io.hpp>
#include <duet/runtime/robot/robot_source.hpp>

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <fstream>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace duet {

struct RecorderSettings {
  /// Frames waiting for the writer, [1, 4096]. When full: block_when_full waits for the writer
  /// (a simulation: nothing may be lost), else the frame is dropped and counted (a robot: control
  /// must not wait for the disk).
  std::size_t queue_frames = 64;
  bool block_when_full = false;
  int png_compression = 1;  ///< PNG zlib level [0, 9]: 1 is fast and still lossless
};

struct RecorderStats {
  std::uint64_t frames_recorded = 0;
  std::uint64_t frames_dropped = 0;    ///< queue full (the disk is slower than the sensors)
  std::uint64_t odometry_recorded = 0;
  std::string error;                   ///< the first write error ("" = none)
};

class Recorder {
 public:
  /// Creates `dir` (it must be empty or not exist: a recording is never mixed with another) and
  /// writes profile.yaml. Throws duet::Error(kIo) naming the folder, kInvalidArgument for bad settings.
  Recorder(const std::filesystem::path& dir, const Profile& profile, const RecorderSettings& settings = {});
  ~Recorder();
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  /// Records a frame of sensor i that arrived at runtime time `arrival_s` (copied).
  void frame(std::size_t sensor, const StampedRgbd& f, double arrival_s);
  void odometry(const OdometryMsg& m, double arrival_s);
  /// Waits for the writer, writes recording.yaml. Throws duet::Error(kIo) with the first write
  /// error. Idempotent.
  void close();
  [[nodiscard]] RecorderStats stats() const;
  [[nodiscard]] const std::filesystem::path& dir() const noexcept { return dir_; }

 private:
  struct Job;
  void writer();

  std::filesystem::path dir_;
  Profile profile_;
  RecorderSettings settings_;
  std::vector<std::uint64_t> next_index_;  ///< per sensor
  std::ofstream odometry_;
  std::vector<std::ofstream> depth_lists_, rgb_lists_;  ///< per sensor; the writer thread's
  mutable std::mutex mutex_;
  std::condition_variable cv_, space_cv_;
  std::deque<Job> jobs_;
  bool closing_ = false, closed_ = false;
  RecorderStats stats_;
  std::thread thread_;
};

/// A RobotSource that records what `inner` delivers (the runtime's view: stamps, order, arrival).
class RecordingSource final : public RobotSource {
 public:
  RecordingSource(RobotSource& inner, Recorder& recorder);
  ~RecordingSource() override;
  [[nodiscard]] ChassisInterface& chassis() override;
  [[nodiscard]] std::span<RgbdSensorInterface* const> sensors() override { return ifaces_; }
  /// Remembers now_s as the arrival time of what is taken next, and moves `inner` on.
  void advance(double now_s) override;

 private:
  class Chassis;
  class Sensor;
  RobotSource& inner_;
  Recorder& recorder_;
  double now_ = 0.0;
  std::unique_ptr<Chassis> chassis_;
  std::vector<std::unique_ptr<Sensor>> sensors_;
  std::vector<RgbdSensorInterface*> ifaces_;
};

/// One recorded message's place in the replay.
struct RecordedFrameRef {
  double stamp_s = 0.0, arrival_s = 0.0;
  std::filesystem::path depth, rgb;  ///< rgb empty: no colour
};

/// A recording read from disk: its profile, odometry and frame lists (images are read when
/// delivered). Throws duet::Error naming the file and line: kIo (missing file or folder, an
/// image that cannot be decoded), kParse (malformed line, a stamp that is not finite, depth
/// not 16-bit or of the wrong size, unknown format/version, sensors that do not match the
/// profile).
struct Recording {
  std::filesystem::path dir;
  Profile profile;
  std::vector<std::pair<OdometryMsg, double>> odometry;         ///< (message, arrival)
  std::vector<std::vector<RecordedFrameRef>> frames;            ///< per sensor, in arrival order
  [[nodiscard]] double end_s() const;                           ///< the last arrival [s]
};
[[nodiscard]] Recording read_recording(const std::filesystem::path& dir);

/// Delivers a recording to the runtime: advance(t) releases every message with arrival <= t.
class ReplaySource final : public RobotSource {
 public:
  explicit ReplaySource(const Recording& recording);
  ~ReplaySource() override;
  [[nodiscard]] ChassisInterface& chassis() override;
  [[nodiscard]] std::span<RgbdSensorInterface* const> sensors() override { return ifaces_; }
  void advance(double now_s) override;
  /// True once everything was delivered.
  [[nodiscard]] bool finished() const noexcept;
  /// The commands the runtime gave (the replay has no robot to drive; counted for the summary).
  [[nodiscard]] std::size_t commands() const noexcept;

 private:
  class Chassis;
  class Sensor;
  const Recording& rec_;
  std::unique_ptr<Chassis> chassis_;
  std::vector<std::unique_ptr<Sensor>> sensors_;
  std::vector<RgbdSensorInterface*> ifaces_;
  std::size_t next_odom_ = 0;
  std::vector<std::size_t> next_frame_;
};

}  // namespace duet
