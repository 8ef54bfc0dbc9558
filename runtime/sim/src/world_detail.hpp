#pragma once
/// @file world_detail.hpp
/// Polygon helpers shared by the world loaders (world.cpp) and the geometry queries (world_geometry.cpp).
#include <duet/sim/world.hpp>

#include <Eigen/Core>

#include <cstddef>
#include <vector>

namespace duet::sim::world_detail {

inline bool point_in_polygon(const std::vector<Eigen::Vector2f>& poly, const Eigen::Vector2f& p) {
  bool inside = false;
  for (std::size_t i = 0, n = poly.size(), j = n - 1; i < n; j = i++) {
    const Eigen::Vector2f& a = poly[i];
    const Eigen::Vector2f& b = poly[j];
    if ((a.y() > p.y()) != (b.y() > p.y())) {
      const float x = a.x() + (p.y() - a.y()) * (b.x() - a.x()) / (b.y() - a.y());
      if (p.x() < x) inside = !inside;
    }
  }
  return inside;
}

inline bool height_overlaps(const Solid& s, float z_low, float z_high) { return s.z_max_m > z_low && s.z_min_m < z_high; }

/// collides()'s floor test: a non-finite centre, or a disc of radius r that reaches past the floor.
inline bool leaves_floor(const Region& f, const Eigen::Vector2f& c, float r) {
  return !c.allFinite() || c.x() - r < f.min.x() || c.y() - r < f.min.y() || c.x() + r > f.max.x() || c.y() + r > f.max.y();
}

/// The polygon's axis-aligned bounding box.
void bbox(const std::vector<Eigen::Vector2f>& poly, Eigen::Vector2f& lo, Eigen::Vector2f& hi);

/// Whether a disc of radius r (r2 = r * r) centred at c overlaps the solid's polygon, whose
/// bounding box is [lo, hi]: the test of overlapping_solid() and SolidIndex, one solid.
bool disc_overlaps(const Solid& s, const Eigen::Vector2f& lo, const Eigen::Vector2f& hi, const Eigen::Vector2f& c, float r, float r2);

}  // namespace duet::sim::world_detail
