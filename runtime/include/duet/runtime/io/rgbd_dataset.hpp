#pragma once
/// @file rgbd_dataset.hpp
/// Reader for recorded RGB-D sequences on disk (the input of `duet map`), with the camera
/// pose of every frame. Two layouts are read, detected automatically:
///
///  - "slambook2" (gaoxiang12/slambook2 ch5/rgbd):
///      pose.txt      one line per frame "tx ty tz qx qy qz qw" (camera -> world), in frame order
///      color/N.png   8-bit colour
///      depth/N.pgm   16-bit depth (depth/N.png also accepted), millimetres
///    N = 1, 2, ... (sorted numerically; the k-th pose line belongs to the k-th frame).
///    The folder has no intrinsics: the layout's known values are used (Kinect of the
///    dataset: 640x480, fx 518, fy 519, cx 325.5, cy 253.5, 1000 units/m) unless overridden.
///  - "tum" (TUM RGB-D benchmark folders):
///      rgb.txt, depth.txt        "timestamp filename" (sorted, no duplicates)
///      groundtruth.txt           "timestamp tx ty tz qx qy qz qw" (camera -> world); optional
///                                with RgbdDatasetOptions::require_poses = false
///      camera-intrinsics.txt     3x3 K (optional; default: TUM's "ROS default" 525, 525, 319.5, 239.5)
///    Each depth frame takes the colour frame and the pose nearest in time within 0.02 s (as
///    the TUM tools' associate.py); depth frames without both are left out. Depth: 5000 units/m.
///  - "3dmatch" (3DMatch / SUN3D, as in nvblox's test data):
///      camera-intrinsics.txt           3x3 matrix K
///      frame-NNNNNN.color.png          8-bit colour
///      frame-NNNNNN.depth.png          16-bit depth, millimetres
///      frame-NNNNNN.pose.txt           4x4 matrix, camera -> world
///
/// Poses are T_world_camera: camera optical frame (z forward, x right, y down) -> the
/// dataset's world frame. A quaternion whose norm is within 1e-3 of 1 (a rotation matrix whose
/// R^T R is within 1e-3 of I) is re-normalised (re-orthonormalised); beyond that it is an error.
///
/// Errors are duet::Error naming the file (and line, for pose.txt) and the problem:
///   kIo              folder or frame file missing, image cannot be decoded
///   kParse           unknown layout, pose / intrinsics text malformed (count of numbers,
///                    non-numeric, non-unit rotation), depth not 16-bit single-channel,
///                    colour / depth size mismatch, pose count != frame count
///   kInvalidArgument bad options, frame index out of range
///
/// Thread safety: open() is reentrant. An RgbdDataset is immutable after open(): its const
/// members (including load()) may be called from any number of threads at once.
#include <duet/kernels/back_projection.hpp>
#include <duet/kernels/types.hpp>

#include <Eigen/Geometry>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace duet {

struct RgbdDatasetOptions {
  /// "auto" (detect from the folder's contents), "slambook2", "3dmatch" or "tum".
  std::string layout = "auto";
  /// Replaces the intrinsics of the layout / folder. width and height must match the images.
  std::optional<PinholeIntrinsics> intrinsics;
  /// Replaces the raw depth units per metre of the layout (1000 for both: millimetres), > 0.
  std::optional<float> depth_units_per_m;
  /// false: frames are loaded without colour (RgbdFrame::color stays empty; colour files are
  /// still required to exist).
  bool load_color = true;
  /// A quaternion norm / rotation matrix within this of unit is re-normalised, else an error.
  float rotation_tolerance = 1e-3f;
  /// false: a TUM folder without groundtruth.txt is read too (every depth frame with a colour
  /// frame within 0.02 s; poses identity) - for visual odometry (duet replay).
  bool require_poses = true;
};

/// One frame, owning its pixels (no OpenCV types).
struct RgbdFrame {
  std::string name;                  ///< file stem: "3" (slambook2), "frame-000116" (3dmatch)
  int width = 0;                     ///< [px]
  int height = 0;                    ///< [px]
  std::vector<std::uint16_t> depth;  ///< width*height raw depth units, row-major; 0 = no return
  std::vector<Rgb8> color;           ///< width*height RGB, row-major; empty if not loaded
  float depth_units_per_m = 1000.0f; ///< metres = depth / depth_units_per_m
  PinholeIntrinsics intrinsics;      ///< the dataset's intrinsics
  Eigen::Isometry3f T_world_camera = Eigen::Isometry3f::Identity();  ///< optical frame -> world

  /// The frame as the back-projection kernel's input. The view points into this frame's
  /// buffers: valid while the frame lives and its vectors are not resized.
  /// `T_target_camera` becomes SensorFrame::T_robot_camera: identity keeps the points in the
  /// camera frame, T_world_camera puts them in the dataset's world frame.
  [[nodiscard]] SensorFrame sensor_frame(
      const Eigen::Isometry3f& T_target_camera = Eigen::Isometry3f::Identity()) const;
};

class RgbdDataset {
 public:
  /// Opens the folder, detects (or checks) the layout, reads every pose and the intrinsics,
  /// checks that every frame's files exist, and decodes the first depth image for the image
  /// size. Pixels are decoded later, by load().
  [[nodiscard]] static RgbdDataset open(const std::filesystem::path& dir, const RgbdDatasetOptions& options = {});

  [[nodiscard]] std::size_t size() const noexcept { return frames_.size(); }
  [[nodiscard]] bool empty() const noexcept { return frames_.empty(); }
  /// Decodes frame i (0-based, in the layout's frame order). Throws as described above.
  [[nodiscard]] RgbdFrame load(std::size_t i) const;

  [[nodiscard]] const PinholeIntrinsics& intrinsics() const noexcept { return intrinsics_; }
  [[nodiscard]] float depth_units_per_m() const noexcept { return depth_units_per_m_; }
  /// "slambook2", "3dmatch" or "tum".
  [[nodiscard]] std::string layout() const { return layout_; }
  [[nodiscard]] const std::filesystem::path& root() const noexcept { return root_; }
  /// Frame i's name and pose without decoding its images.
  [[nodiscard]] const std::string& frame_name(std::size_t i) const;
  [[nodiscard]] const Eigen::Isometry3f& pose(std::size_t i) const;
  /// Frame i's time stamp [s] (TUM: the depth image's; other layouts: the frame index / 30 Hz).
  [[nodiscard]] double stamp(std::size_t i) const;

 private:
  struct Entry {
    std::string name;
    std::filesystem::path color, depth;
    Eigen::Isometry3f T_world_camera = Eigen::Isometry3f::Identity();
    double stamp_s = -1.0;  ///< TUM: the depth image's stamp; else -1 (index / 30 Hz)
  };
  RgbdDataset() = default;
  const Entry& entry(std::size_t i) const;

  std::filesystem::path root_;
  std::string layout_;
  PinholeIntrinsics intrinsics_;
  float depth_units_per_m_ = 1000.0f;
  bool load_color_ = true;
  std::vector<Entry> frames_;
};

}  // namespace duet
