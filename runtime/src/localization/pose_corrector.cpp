/// @file pose_corrector.cpp
/// Scan-to-map correction of the wheel odometry (see pose_corrector.hpp).
#include <duet/kernels/error.hpp>
#include <duet/runtime/localization/pose_corrector.hpp>

#include "mapping/cell_key.hpp"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <numbers>
#include <string>

namespace duet {

void validate(const PoseCorrectionSettings& s) {
  validate(s.match);
  auto bad = [](const std::string& what) { fail(ErrorCode::kInvalidArgument, "PoseCorrectionSettings::" + what); };
  if (!(std::isfinite(s.min_height_m) && std::isfinite(s.max_height_m) && s.min_height_m < s.max_height_m))
    bad("min_height_m < max_height_m (finite) required, got " + std::to_string(s.min_height_m) + ", " + std::to_string(s.max_height_m));
  if (!(std::isfinite(s.reference_age_s) && s.reference_age_s >= 0.0 && s.reference_age_s <= 3600.0))
    bad("reference_age_s must be in [0, 3600] s, got " + std::to_string(s.reference_age_s));
  if (s.pixel_step < 1 || s.pixel_step > 64) bad("pixel_step must be in [1, 64], got " + std::to_string(s.pixel_step));
  if (s.max_points < 1) bad("max_points must be >= 1");
  if (!(std::isfinite(s.gain) && s.gain > 0.0f && s.gain <= 1.0f)) bad("gain must be in (0, 1], got " + std::to_string(s.gain));
  if (!(std::isfinite(s.rate_gain) && s.rate_gain >= 0.0f && s.rate_gain <= 1.0f))
    bad("rate_gain must be in [0, 1], got " + std::to_string(s.rate_gain));
  if (!(std::isfinite(s.rate_gain_initial) && s.rate_gain_initial >= s.rate_gain && s.rate_gain_initial <= 1.0f && s.rate_gain_initial > 0.0f))
    bad("rate_gain_initial must be in [rate_gain, 1] and > 0, got " + std::to_string(s.rate_gain_initial));
  if (s.relocalize_after < 0 || s.relocalize_after > 5) bad("relocalize_after must be in [0, 5], got " + std::to_string(s.relocalize_after));
  auto in = [](float v, float lo, float hi) { return std::isfinite(v) && v > lo && v <= hi; };
  if (!in(s.relocalize_window_m, 0.0f, 5.0f)) bad("relocalize_window_m must be in (0, 5] m, got " + std::to_string(s.relocalize_window_m));
  if (!in(s.relocalize_window_deg, 0.0f, 45.0f)) bad("relocalize_window_deg must be in (0, 45] deg, got " + std::to_string(s.relocalize_window_deg));
  if (!in(s.relocalize_step_m, 0.0f, 1.0f)) bad("relocalize_step_m must be in (0, 1] m, got " + std::to_string(s.relocalize_step_m));
  if (!in(s.relocalize_step_deg, 0.0f, 10.0f)) bad("relocalize_step_deg must be in (0, 10] deg, got " + std::to_string(s.relocalize_step_deg));
  if (!in(s.relocalize_min_gain, 0.0f, 1.0f)) bad("relocalize_min_gain must be in (0, 1], got " + std::to_string(s.relocalize_min_gain));
  if (!(s.relocalize_min_conflict >= 0.0f && s.relocalize_min_conflict <= 1.0f))
    bad("relocalize_min_conflict must be in [0, 1], got " + std::to_string(s.relocalize_min_conflict));
  if (!(s.relocalize_min_margin >= 0.0f && s.relocalize_min_margin <= 1.0f))
    bad("relocalize_min_margin must be in [0, 1], got " + std::to_string(s.relocalize_min_margin));
  if (!(s.relocalize_min_clearance_m >= 0.0f && s.relocalize_min_clearance_m <= 1.0f))
    bad("relocalize_min_clearance_m must be in [0, 1] m, got " + std::to_string(s.relocalize_min_clearance_m));
  if (!(s.relocalize_edge_steps >= 0.0f && s.relocalize_edge_steps <= 5.0f))
    bad("relocalize_edge_steps must be in [0, 5] lattice steps, got " + std::to_string(s.relocalize_edge_steps));
  if (!in(s.relocalize_distinct_m, 0.0f, 5.0f)) bad("relocalize_distinct_m must be in (0, 5] m, got " + std::to_string(s.relocalize_distinct_m));
}

namespace {
/// `fit` lies within relocalize_edge_steps lattice steps of the wide window's edge around `prior`
/// in x, y or heading (false with the check off). The edge is the lattice's outermost step
/// (scan_match.cpp: floor(window / step) steps each way).
bool on_wide_window_edge(const Pose2& fit, const Pose2& prior, const PoseCorrectionSettings& pc) {
  if (!(pc.relocalize_edge_steps > 0.0f)) return false;
  auto edge = [&](float window, float step) { return std::floor(window / step + 1e-4f) * step - pc.relocalize_edge_steps * step; };
  const float edge_m = edge(pc.relocalize_window_m, pc.relocalize_step_m);
  const float edge_rad = edge(pc.relocalize_window_deg, pc.relocalize_step_deg) * std::numbers::pi_v<float> / 180.0f;
  return std::abs(fit.x - prior.x) >= edge_m || std::abs(fit.y - prior.y) >= edge_m ||
         std::abs(std::remainder(fit.theta - prior.theta, 2.0f * std::numbers::pi_v<float>)) >= edge_rad;
}
}  // namespace

PoseCorrector::PoseCorrector(const Profile& profile, const PoseCorrectionSettings& settings) : profile_(profile), settings_(settings) {
  validate(settings_);
}

void PoseCorrector::shift(const Pose2& D) {
  correction_ = compose(D, correction_);
  have_reference_ = false;  // the reference copy is of the old frame
  pending_t_ = -1.0;
}

void PoseCorrector::scan_from(const CameraPoints& points, std::span<const SensorFrame> frames) {
  const int step = settings_.pixel_step;
  const CameraPoints* src = &points;
  if (step % points.pixel_step != 0) {  // not a sub-lattice of the points': read the images at the matcher's step
    BackProjectionSettings bp = profile_.mapping.back_projection;
    bp.pixel_step = step;
    back_project_camera(frames, bp, own_points_);
    src = &own_points_;
  }
  scan_cloud_.clear();
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const auto w = static_cast<std::uint32_t>(frames[i].depth.width);
    const auto s = static_cast<std::uint32_t>(step);
    const Eigen::Matrix3f R = frames[i].T_robot_camera.linear();  // as back_project() applies it
    const Eigen::Vector3f t = frames[i].T_robot_camera.translation();
    for (std::size_t k = src->offsets[i]; k < src->offsets[i + 1]; ++k) {
      const std::uint32_t px = src->pixel[k];
      if ((px % w) % s != 0 || (px / w) % s != 0) continue;
      scan_cloud_.push_back(R * src->cloud.points[k] + t);
    }
  }
}

float PoseCorrector::free_conflict(const OccupancyGrid& grid, const Pose2& pose) const {
  if (scan_points_.empty() || grid.width() <= 0 || grid.height() <= 0) return 0.0f;
  const float c = std::cos(pose.theta), s = std::sin(pose.theta);
  std::size_t on_free = 0;
  for (const Eigen::Vector2f& p : scan_points_) {
    const Eigen::Vector2f w(pose.x + c * p.x() - s * p.y(), pose.y + s * p.x() + c * p.y());
    const Eigen::Vector2i k = grid.cell_of(w);
    if (grid.in_bounds(k.x(), k.y()) && classify(grid.at(k.x(), k.y()), profile_.exploration.cells) == CellState::kFree) ++on_free;
  }
  return static_cast<float>(on_free) / static_cast<float>(scan_points_.size());
}

Pose2 PoseCorrector::update(std::span<const SensorFrame> frames, const Pose2& odom, const OccupancyGrid& grid, double t) {
  BackProjectionSettings bp = profile_.mapping.back_projection;
  bp.pixel_step = settings_.pixel_step;
  back_project_camera(frames, bp, own_points_);
  return update(own_points_, frames, odom, grid, t);
}

Pose2 PoseCorrector::update(const CameraPoints& points, std::span<const SensorFrame> frames, const Pose2& odom,
                            const OccupancyGrid& grid, double t) {
  if (points.offsets.size() != frames.size() + 1 || points.offsets.back() != points.cloud.size())
    fail(ErrorCode::kInvalidArgument, "PoseCorrector::update: the points are not those of the " + std::to_string(frames.size()) + " frames");
  Pose2 prior = compose(correction_, odom);
  const auto t0 = std::chrono::steady_clock::now();
  const PoseCorrectionSettings& pc = settings_;
  constexpr float kTwoPi = 2.0f * std::numbers::pi_v<float>;
  // Predict: the heading drifts at the estimated rate since the last update.
  const double dt = last_match_t_ >= 0.0 ? std::max(0.0, t - last_match_t_) : 0.0;
  last_match_t_ = t;
  prior.theta = std::remainder(prior.theta + heading_rate_ * static_cast<float>(dt), kTwoPi);
  // Obstacle points of the frames in the robot frame, one per grid cell (the first in pixel
  // order), heights relative to the floor of the map frame.
  scan_from(points, frames);
  const float floor_z = profile_.mapping.segmentation.floor_z_m;
  const float res = grid.resolution();
  scan_keys_.clear();
  for (std::size_t i = 0; i < scan_cloud_.size(); ++i) {
    const Eigen::Vector3f& p = scan_cloud_[i];
    const float h = p.z() - floor_z;
    if (!(h >= pc.min_height_m && h <= pc.max_height_m)) continue;
    scan_keys_.emplace_back(cell_key(p.x(), p.y(), res), static_cast<std::uint32_t>(i));
  }
  std::sort(scan_keys_.begin(), scan_keys_.end());
  scan_keys_.erase(std::unique(scan_keys_.begin(), scan_keys_.end(), [](const auto& a, const auto& b) { return a.first == b.first; }),
                   scan_keys_.end());
  const std::size_t stride = (scan_keys_.size() + pc.max_points - 1) / pc.max_points;
  scan_points_.clear();
  for (std::size_t k = 0; k < scan_keys_.size(); k += std::max<std::size_t>(stride, 1)) {
    const Eigen::Vector3f& p = scan_cloud_[scan_keys_[k].second];
    scan_points_.emplace_back(p.x(), p.y());
  }
  Pose2 at = prior;  // not accepted: the predicted drift still applies
  bool accepted = false;
  // The reference map (PoseCorrectionSettings::reference_age_s): the copy before the latest.
  if (pc.reference_age_s <= 0.0) {
    if (grid.width() > 0 && grid.height() > 0) {
      occupied_distance(GridView(grid), profile_.exploration.cells, distance_);
      have_reference_ = true;
    }
  } else if (pending_t_ < 0.0 || t - pending_t_ >= pc.reference_age_s) {
    if (pending_t_ >= 0.0 && pending_grid_.width() > 0 && pending_grid_.height() > 0) {
      occupied_distance(GridView(pending_grid_), profile_.exploration.cells, distance_);
      have_reference_ = true;
    }
    pending_grid_ = grid;
    pending_t_ = t;
  }
  bool relocalized = false;
  if (have_reference_ && scan_points_.size() >= pc.match.min_points) {
    const ScanMatchResult r = scan_match(distance_.clearance(), scan_points_, prior, pc.match);
    // A match that fails, or hits the window's edge, again and again: the pose is off by more
    // than the window (pushed, slipped) - look wider.
    const bool edge = r.status == ScanMatchStatus::kMatched &&
                      std::hypot(r.pose.x - prior.x, r.pose.y - prior.y) > 0.8f * pc.match.linear_window_m;
    // The last 8 updates, one bit each: rejected or at the window's edge.
    suspect_ = ((suspect_ << 1) | (r.status == ScanMatchStatus::kMatched && !edge ? 0u : 1u)) & 0xFFu;
    // The prediction explains almost none of the scan while the matcher found nothing near it:
    // look wider at once, before this scan is integrated where it does not belong.
    const bool lost = r.status != ScanMatchStatus::kMatched && r.prior_score < 0.5f * pc.match.min_score;
    const int recent = std::popcount(suspect_ & 0x1Fu);  // of the last 5
    // Only against the current grid: an aged reference lacks what the robot has just seen, and
    // a wide window then finds false fits of the scan's few known parts.
    const bool asked = relocalize_asked_ && pc.relocalize_after > 0 && pc.reference_age_s <= 0.0;
    relocalize_asked_ = false;
    if (asked) ++relocalizations_asked_;
    bool wide_due = pc.relocalize_after > 0 && pc.reference_age_s <= 0.0 && (recent >= pc.relocalize_after || lost || asked);
    if (wide_due) last_conflict_ = free_conflict(grid, prior);
    if (wide_due && !asked && pc.relocalize_min_conflict > 0.0f && last_conflict_ < pc.relocalize_min_conflict) {
      wide_due = false;  // the scan sees new space, not a map it contradicts
      ++relocalizations_new_space_;
    }
    if (wide_due && odometry_confirmed_ && !asked) {
      suspect_ = 0;
      ++relocalizations_held_;
    } else if (wide_due) {
      suspect_ = 0;
      ScanMatchSettings wide = pc.match;
      wide.linear_window_m = pc.relocalize_window_m;
      wide.angular_window_deg = pc.relocalize_window_deg;
      wide.linear_step_m = pc.relocalize_step_m;
      wide.angular_step_deg = pc.relocalize_step_deg;
      wide.prior_sigma_m = 100.0f * pc.relocalize_window_m;  // no pull toward the prediction
      wide.prior_sigma_deg = 100.0f * pc.relocalize_window_deg;
      wide.runner_up_distance_m = pc.relocalize_distinct_m;
      const ScanMatchResult w = scan_match(distance_.clearance(), scan_points_, prior, wide);
      // Clearly better than the prediction and a good fit in itself (a pushed robot's scan
      // scores ~0.96 at the found pose against ~0.01 at the prediction).
      const bool clear = w.status == ScanMatchStatus::kMatched && w.score >= w.prior_score + pc.relocalize_min_gain &&
                         w.score >= pc.match.min_score + pc.relocalize_min_gain &&
                         std::hypot(w.pose.x - prior.x, w.pose.y - prior.y) > 0.5f * pc.match.linear_window_m;
      // Another fit elsewhere in the window nearly as good: the scan does not say which.
      const bool ambiguous = clear && pc.relocalize_min_margin > 0.0f && w.score < w.runner_up_score + pc.relocalize_min_margin;
      if (ambiguous) ++relocalizations_ambiguous_;
      // A fit on the window's edge is where the window cut the score off, not where it peaks.
      const bool at_edge = clear && !ambiguous && on_wide_window_edge(w.pose, prior, pc);
      if (at_edge) ++relocalizations_at_edge_;
      // A fit that puts the robot in a wall (or the wall's first cells) is a false one.
      bool in_obstacle = false;
      if (clear && !ambiguous && !at_edge && pc.relocalize_min_clearance_m > 0.0f) {
        Eigen::Vector2i c;
        in_obstacle = distance_.cell_of(Eigen::Vector2f(w.pose.x, w.pose.y), c) &&
                      distance_.clearance_m[distance_.index(c.x(), c.y())] < pc.relocalize_min_clearance_m;
        if (in_obstacle) ++relocalizations_in_obstacle_;
      }
      if (clear && !ambiguous && !at_edge && !in_obstacle) {
        at = w.pose;
        relocalized = true;
        ++relocalizations_;
        last_relocalization_ = Pose2{w.pose.x - prior.x, w.pose.y - prior.y, std::remainder(w.pose.theta - prior.theta, kTwoPi)};
        last_relocalization_scores_ = {w.score, w.prior_score, w.runner_up_score};
      }
    }
    if (!relocalized && r.status == ScanMatchStatus::kMatched) {
      const float g = pc.gain;
      const float e_theta = std::remainder(r.pose.theta - prior.theta, kTwoPi);
      at = Pose2{prior.x + g * (r.pose.x - prior.x), prior.y + g * (r.pose.y - prior.y), std::remainder(prior.theta + g * e_theta, kTwoPi)};
      if (dt > 0.0 && pc.rate_gain > 0.0f) {
        const float k = std::max(pc.rate_gain, 1.0f / (1.0f / pc.rate_gain_initial + static_cast<float>(rate_updates_++)));
        heading_rate_ += k * e_theta / static_cast<float>(dt);
      }
      accepted = true;
    }
  }
  correction_ = compose(at, inverse(odom));
  ++(accepted || relocalized ? matches_ : rejected_);
  time_s_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return at;
}

}  // namespace duet
