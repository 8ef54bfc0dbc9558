#pragma once
/// @file contact_layer.hpp
/// A costmap layer: the contact obstacles. Where the robot stalled against something its
/// sensors never saw (too low, too thin, glass), a disc of radius_m is an obstacle for good,
/// for planning and for the dynamic window.
#include <duet/runtime/navigation/costmap_layer.hpp>

#include <Eigen/Core>

#include <vector>

namespace duet {

class ContactLayer final : public CostmapLayer {
 public:
  /// radius_m: the disc marked round each contact [m]; occupied_logodds: the value written.
  ContactLayer(float radius_m, float occupied_logodds) : radius_m_(radius_m), occupied_(occupied_logodds) {}

  /// A contact (map frame); non-finite points are ignored.
  void add(const Eigen::Vector2f& p);
  [[nodiscard]] const std::vector<Eigen::Vector2f>& points() const noexcept { return points_; }

  [[nodiscard]] std::string_view name() const override { return "contacts"; }
  [[nodiscard]] bool active() const override { return !points_.empty(); }
  void apply(OccupancyGrid& grid) override;
  void shift(const Pose2& D) override;

 private:
  float radius_m_;
  float occupied_;
  std::vector<Eigen::Vector2f> points_;
};

}  // namespace duet
