#pragma once
/// @file mapper.hpp
/// The mapping pipeline of paper §2.2 / Fig. 4 on the kernels: for every synchronized
/// observation (one frame per sensor) at a known robot pose,
///   back-projection -> map frame -> voxel filter (0.05 m) -> normals (k = 10, facing the sensor)
///   -> segmentation (verticality, Euclidean clusters, height) -> 2D log-odds grid update with
///   free space cleared along each sensor's rays,
/// and the voxel-filtered frames accumulate into the global cloud (re-filtered as it grows).
///
/// Frames: the map frame is gravity-aligned (z up, floor at segmentation.floor_z_m).
/// T_map_world turns the pose source's world frame into it (identity for a robot whose odometry
/// frame is already z-up; a rotation for a hand-held recording whose "up" is e.g. -y).
///
/// Thread safety: one Mapper per thread of calls; integrate() is parallel inside (TBB) and its
/// results do not depend on the thread count.
#include <duet/kernels/back_projection.hpp>
#include <duet/kernels/grid.hpp>
#include <duet/kernels/motion_model.hpp>
#include <duet/kernels/normals.hpp>
#include <duet/kernels/segmentation.hpp>
#include <duet/kernels/voxel_filter.hpp>
#include <duet/runtime/config/profile.hpp>

#include <span>

namespace duet {

struct MapperStats {
  std::size_t observations = 0;     ///< integrate() calls
  std::size_t frames = 0;           ///< sensor frames integrated
  std::size_t raw_points = 0;       ///< valid depth pixels back-projected
  std::size_t filtered_points = 0;  ///< points after the per-frame voxel filter
  std::size_t obstacle_points = 0;  ///< of those, labelled obstacle
  std::size_t floor_points = 0;     ///< of those, labelled floor
};

/// A submap: what the mapper integrated over a stretch of time, kept apart so that it can be
/// moved as a whole when a loop closure corrects the poses it was integrated at (see
/// Mapper::keep_submaps()).
struct Submap {
  OccupancyGrid grid;        ///< this submap's observations only (log-odds, clamped), map frame as integrated
  PointCloud cloud;          ///< its voxel-filtered points (colours), map frame as integrated
  Pose2 placement;           ///< where its content lies now: p_map = placement * p_integrated (identity until moved)
  std::size_t frames = 0;    ///< sensor frames integrated into it
};

class Mapper {
 public:
  explicit Mapper(const MappingSettings& settings, const Eigen::Isometry3f& T_map_world = Eigen::Isometry3f::Identity());

  /// Integrates one observation: frames[i].T_robot_camera places sensor i on the robot, and
  /// T_world_robot is the robot's pose. Throws duet::Error on bad frames or settings; every
  /// frame is validated first, so a bad observation integrates nothing and the map keeps
  /// everything accepted before.
  void integrate(std::span<const SensorFrame> frames, const Eigen::Isometry3f& T_world_robot);
  /// The same for frames already back-projected: `points` = back_project_camera(frames,
  /// settings' back_projection) (a pipeline that used them before, e.g. to correct the pose,
  /// reads each depth image once). Throws duet::Error(kInvalidArgument) if `points` do not
  /// belong to `frames` (offsets) or were sampled with another pixel_step.
  void integrate(const CameraPoints& points, std::span<const SensorFrame> frames, const Eigen::Isometry3f& T_world_robot);

  /// The global cloud (map frame), voxel-filtered at the mapping leaf size, with colours.
  [[nodiscard]] const PointCloud& cloud();
  [[nodiscard]] const OccupancyGrid& grid() const noexcept { return grid_; }
  /// The points of the last integrate() labelled obstacle - the ones that marked the grid - as
  /// map-frame xy, after the per-frame voxel filter, all frames (empty before the first call).
  [[nodiscard]] const std::vector<Eigen::Vector2f>& last_obstacles() const noexcept { return obstacles_; }
  [[nodiscard]] const MapperStats& stats() const noexcept { return stats_; }
  [[nodiscard]] const MappingSettings& settings() const noexcept { return settings_; }
  [[nodiscard]] const Eigen::Isometry3f& T_map_world() const noexcept { return T_map_world_; }

  /// The cloud map is finished (exploration is over): from now on integrate() updates the grid
  /// (and the open submap's grid) but adds no point to the cloud, so a robot that goes on
  /// driving (patrolling) keeps its navigation map up to date while the cloud - which grows
  /// with every observation until it is filtered - stays as explored. Idempotent.
  void freeze_cloud();
  [[nodiscard]] bool cloud_frozen() const noexcept { return cloud_frozen_; }

  /// Submaps (loop closure): from now on every integrate() also goes into the open submap (the
  /// last of submaps()), and the global cloud is kept per submap instead. Call before the first
  /// integrate(); throws duet::Error(kInvalidArgument) after it. The grid and the cloud are
  /// unchanged by this until place_submaps() moves a submap.
  void keep_submaps();
  [[nodiscard]] bool keeps_submaps() const noexcept { return keep_submaps_; }
  /// Closes the open submap (if it holds anything) and opens an empty one; returns its index.
  /// Throws duet::Error(kInvalidArgument) when submaps are not kept.
  std::size_t open_submap();
  [[nodiscard]] const std::vector<Submap>& submaps() const noexcept { return submaps_; }
  /// Moves the submaps to `placements` (one per submap, submaps().size() of them) and rebuilds
  /// the grid as the sum of their log-odds at their placements (accumulate_grid(), clamped to
  /// the grid update's limits; cells no submap saw are unknown) and the cloud from their points.
  /// Throws duet::Error(kInvalidArgument) for the wrong count, a non-finite placement, or when
  /// submaps are not kept; nothing changes then.
  void place_submaps(std::span<const Pose2> placements);

 private:
  void compact();
  void refilter(PointCloud& cloud);  // voxel filter in place (mapping leaf size)

  MappingSettings settings_;
  Eigen::Isometry3f T_map_world_;
  OccupancyGrid grid_;
  PointCloud global_;   // filtered
  PointCloud pending_;  // per-frame filtered clouds not yet merged into global_
  MapperStats stats_;
  bool keep_submaps_ = false;
  std::vector<Submap> submaps_;
  bool cloud_dirty_ = false;  // submaps: global_ is out of date
  bool cloud_frozen_ = false;
  std::size_t open_filtered_size_ = 0;  // submaps: the open submap's cloud after its last refilter
  // Reused scratch.
  CameraPoints camera_;
  std::vector<Eigen::Vector3f> map_points_;  ///< one frame's points in the map frame
  PointCloud filtered_;
  std::vector<PointLabel> labels_;
  std::vector<Eigen::Vector2f> obstacles_;
  VoxelFilterWorkspace vf_ws_;
  GridUpdateWorkspace grid_ws_;
};

/// Rotation taking the direction `up` (any non-zero vector, in the world frame) to +z, with the
/// smallest rotation angle. Throws duet::Error(kInvalidArgument) for a zero or non-finite vector.
[[nodiscard]] Eigen::Isometry3f gravity_alignment(const Eigen::Vector3f& up);

/// Refines an approximate up direction from a cloud's normals: horizontal surfaces (floor,
/// tables, seats) all face up, so the mean of the normals within cone_deg of `initial_up`
/// (flipped into its hemisphere) is a better estimate; done twice, at cone_deg then cone_deg/2.
/// Returns initial_up (normalised) when fewer than 100 normals fall in the cone.
[[nodiscard]] Eigen::Vector3f refine_up(const PointCloud& cloud, const Eigen::Vector3f& initial_up, float cone_deg = 30.0f);

/// Floor height estimate for a cloud in a z-up frame: the lowest 5 cm height band holding at
/// least max(50, 2 %) of the points whose normal is within max_tilt_deg of vertical (centre of
/// that band's points); falls back to the 1st percentile of all heights. Returns NaN for an
/// empty cloud. cloud.normals must be filled.
[[nodiscard]] float estimate_floor_z(const PointCloud& cloud, float max_tilt_deg = 20.0f);

}  // namespace duet
