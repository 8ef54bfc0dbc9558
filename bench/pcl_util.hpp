#pragma once
/// @file pcl_util.hpp
/// Copies of the shared inputs in PCL's layout (made before a timed loop, never inside it).
#ifdef DUET_HAVE_PCL
#include <duet/kernels/types.hpp>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

namespace duet::bench {

inline pcl::PointCloud<pcl::PointXYZ>::Ptr to_pcl_xyz(const PointCloud& c) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr out(new pcl::PointCloud<pcl::PointXYZ>);
  out->resize(c.size());
  for (std::size_t i = 0; i < c.size(); ++i) {
    (*out)[i].x = c.points[i].x();
    (*out)[i].y = c.points[i].y();
    (*out)[i].z = c.points[i].z();
  }
  out->width = static_cast<std::uint32_t>(c.size());
  out->height = 1;
  out->is_dense = true;
  for (const auto& p : c.points) out->is_dense = out->is_dense && is_finite(p);
  return out;
}

inline pcl::PointCloud<pcl::PointXYZRGB>::Ptr to_pcl_xyzrgb(const PointCloud& c) {
  pcl::PointCloud<pcl::PointXYZRGB>::Ptr out(new pcl::PointCloud<pcl::PointXYZRGB>);
  out->resize(c.size());
  for (std::size_t i = 0; i < c.size(); ++i) {
    auto& q = (*out)[i];
    q.x = c.points[i].x();
    q.y = c.points[i].y();
    q.z = c.points[i].z();
    const Rgb8 col = c.has_colors() ? c.colors[i] : Rgb8{255, 255, 255};
    q.r = col.r;
    q.g = col.g;
    q.b = col.b;
    q.a = 255;
  }
  out->width = static_cast<std::uint32_t>(c.size());
  out->height = 1;
  out->is_dense = true;
  for (const auto& p : c.points) out->is_dense = out->is_dense && is_finite(p);
  return out;
}

}  // namespace duet::bench
#endif
