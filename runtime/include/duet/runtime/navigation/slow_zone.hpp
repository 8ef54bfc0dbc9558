#pragma once
/// @file slow_zone.hpp
/// A controller behaviour: near obstacles the top speed falls with the clearance on the
/// planning grid - slow_speed_mps at the dynamic window's margin (robot radius + safety margin)
/// and below, rising linearly to the profile's top speed at slow_clearance_m; off the map (nothing
/// known) slow. slow_clearance_m <= 0 turns it off.
#include <duet/kernels/dwa.hpp>
#include <duet/kernels/inflation.hpp>

namespace duet {

class SlowZone {
 public:
  SlowZone(float slow_clearance_m, float slow_speed_mps) : clearance_m_(slow_clearance_m), speed_mps_(slow_speed_mps) {}
  /// The top speed at `robot` [m/s] (ds.limits.max_v_mps where the zone does not apply).
  [[nodiscard]] float speed_limit(const Pose2& robot, const DwaSettings& ds, const InflatedGrid& planning) const;

 private:
  float clearance_m_;
  float speed_mps_;
};

}  // namespace duet
