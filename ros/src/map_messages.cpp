#include <duet_ros/map_messages.hpp>

#include <tf2/utils.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <vector>

namespace duet_ros {
namespace {

bool is_frontier(const nav_msgs::OccupancyGrid& m, int x, int y) {
  const int w = static_cast<int>(m.info.width), h = static_cast<int>(m.info.height);
  if (m.data[static_cast<std::size_t>(y) * w + x] != 0) return false;
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      const int qx = x + dx, qy = y + dy;
      if ((dx || dy) && qx >= 0 && qy >= 0 && qx < w && qy < h && m.data[static_cast<std::size_t>(qy) * w + qx] < 0) return true;
    }
  return false;
}

}  // namespace

geometry_msgs::Quaternion yaw_quaternion(double yaw) {
  geometry_msgs::Quaternion q;
  q.w = std::cos(yaw / 2.0);
  q.z = std::sin(yaw / 2.0);
  return q;
}

duet_pose2 planar_pose(const nav_msgs::Odometry& m) {
  return duet_pose2{static_cast<float>(m.pose.pose.position.x), static_cast<float>(m.pose.pose.position.y),
                    static_cast<float>(tf2::getYaw(m.pose.pose.orientation))};
}

duet_twist planar_twist(const nav_msgs::Odometry& m) {
  return duet_twist{static_cast<float>(m.twist.twist.linear.x), static_cast<float>(m.twist.twist.angular.z)};
}

nav_msgs::OccupancyGrid to_occupancy_grid(duet_grid grid, const std::string& frame, const ros::Time& stamp) {
  nav_msgs::OccupancyGrid m;
  m.header.frame_id = frame;
  m.header.stamp = stamp;
  m.info.map_load_time = stamp;
  const int w = duet_grid_get_width(grid), h = duet_grid_get_height(grid);
  m.info.resolution = duet_grid_get_resolution(grid);
  float ox = 0.0f, oy = 0.0f;
  duet_grid_get_origin(grid, &ox, &oy);
  m.info.origin.position.x = ox;
  m.info.origin.position.y = oy;
  m.info.origin.orientation.w = 1.0;
  if (w <= 0 || h <= 0) return m;
  m.info.width = static_cast<std::uint32_t>(w);
  m.info.height = static_cast<std::uint32_t>(h);
  m.data.resize(static_cast<std::size_t>(w) * static_cast<std::size_t>(h));
  duet_grid_copy_ros(grid, m.data.data(), m.data.size(), 0.65f, 0.45f);  // duet's map_server export's thresholds
  return m;
}

sensor_msgs::PointCloud2 to_point_cloud2(duet_cloud cloud, const std::string& frame, const ros::Time& stamp) {
  sensor_msgs::PointCloud2 m;
  m.header.frame_id = frame;
  m.header.stamp = stamp;
  const std::size_t n = duet_cloud_get_size(cloud);
  const char* names[4] = {"x", "y", "z", "rgb"};
  for (std::uint32_t i = 0; i < 4; ++i) {
    sensor_msgs::PointField f;
    f.name = names[i];
    f.offset = 4 * i;
    f.datatype = sensor_msgs::PointField::FLOAT32;
    f.count = 1;
    m.fields.push_back(f);
  }
  m.height = 1;
  m.width = static_cast<std::uint32_t>(n);
  m.point_step = 16;
  m.row_step = m.point_step * m.width;
  m.is_bigendian = false;
  m.is_dense = true;
  m.data.resize(static_cast<std::size_t>(m.row_step));
  if (n == 0) return m;
  std::vector<float> xyz(3 * n);
  std::vector<std::uint8_t> rgb(3 * n, 200);
  duet_cloud_copy_points(cloud, xyz.data(), 3 * sizeof(float), n);
  const std::uint8_t* colors = nullptr;
  std::size_t stride = 0;
  duet_cloud_get_colors(cloud, &colors, &stride);
  if (colors != nullptr) duet_cloud_copy_colors(cloud, rgb.data(), 3, n);
  for (std::size_t i = 0; i < n; ++i) {
    std::uint8_t* p = &m.data[i * 16];
    std::memcpy(p, &xyz[3 * i], 12);
    const std::uint32_t packed = (std::uint32_t{rgb[3 * i]} << 16) | (std::uint32_t{rgb[3 * i + 1]} << 8) | rgb[3 * i + 2];
    std::memcpy(p + 12, &packed, 4);  // PCL's / RViz's packed rgb: the bytes of a float32 field
  }
  return m;
}

nav_msgs::Path to_path(const std::vector<float>& xy, const std::string& frame, const ros::Time& stamp) {
  nav_msgs::Path path;
  path.header.frame_id = frame;
  path.header.stamp = stamp;
  const std::size_t n = xy.size() / 2;
  for (std::size_t i = 0; i < n; ++i) {
    geometry_msgs::PoseStamped p;
    p.header = path.header;
    p.pose.position.x = xy[2 * i];
    p.pose.position.y = xy[2 * i + 1];
    const std::size_t j = i + 1 < n ? i + 1 : i;
    const std::size_t k = i + 1 < n ? i : (i > 0 ? i - 1 : i);
    const double yaw = std::atan2(xy[2 * j + 1] - xy[2 * k + 1], xy[2 * j] - xy[2 * k]);
    p.pose.orientation = yaw_quaternion(j == k ? 0.0 : yaw);
    path.poses.push_back(p);
  }
  return path;
}

geometry_msgs::PoseStamped to_pose_stamped(const duet_pose2& p, const std::string& frame, const ros::Time& stamp) {
  geometry_msgs::PoseStamped m;
  m.header.frame_id = frame;
  m.header.stamp = stamp;
  m.pose.position.x = p.x;
  m.pose.position.y = p.y;
  m.pose.orientation = yaw_quaternion(p.theta);
  return m;
}

geometry_msgs::TransformStamped map_to_odom(const duet_pose2& map_from_base, const duet_pose2& odom_from_base, const std::string& map_frame,
                                            const std::string& odom_frame, const ros::Time& stamp) {
  // map_from_odom = map_from_base * inverse(odom_from_base), planar.
  const double th = static_cast<double>(map_from_base.theta) - odom_from_base.theta;
  const double c = std::cos(th), s = std::sin(th);
  geometry_msgs::TransformStamped t;
  t.header.frame_id = map_frame;
  t.header.stamp = stamp;
  t.child_frame_id = odom_frame;
  t.transform.translation.x = map_from_base.x - (c * odom_from_base.x - s * odom_from_base.y);
  t.transform.translation.y = map_from_base.y - (s * odom_from_base.x + c * odom_from_base.y);
  t.transform.rotation = yaw_quaternion(th);
  return t;
}

bool save_map_server(const nav_msgs::OccupancyGrid& map, const std::string& stem, std::string& error) {
  const std::size_t w = map.info.width, h = map.info.height;
  if (w == 0 || h == 0 || map.data.size() != w * h) {
    error = "the map is empty or its data does not match its size";
    return false;
  }
  const std::string pgm = stem + ".pgm", yaml = stem + ".yaml";
  {
    std::ofstream f(pgm, std::ios::binary);
    f << "P5\n" << w << " " << h << "\n255\n";
    std::vector<char> row(w);
    for (std::size_t r = 0; r < h; ++r) {  // the image's top row is the map's last (largest y)
      const std::int8_t* src = &map.data[(h - 1 - r) * w];
      for (std::size_t x = 0; x < w; ++x) row[x] = static_cast<char>(src[x] < 0 ? 205 : (src[x] >= 65 ? 0 : (src[x] <= 19 ? 254 : 205)));
      f.write(row.data(), static_cast<std::streamsize>(w));
    }
    if (!f) {
      error = "cannot write " + pgm;
      return false;
    }
  }
  std::ofstream y(yaml);
  y.precision(9);
  y << "image: " << std::filesystem::path(pgm).filename().string() << "\nresolution: " << map.info.resolution << "\norigin: ["
    << map.info.origin.position.x << ", " << map.info.origin.position.y << ", 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";
  if (!y) {
    error = "cannot write " + yaml;
    return false;
  }
  return true;
}

std::size_t count_frontier_cells(const nav_msgs::OccupancyGrid& map) {
  const int w = static_cast<int>(map.info.width), h = static_cast<int>(map.info.height);
  if (map.data.size() != static_cast<std::size_t>(w) * static_cast<std::size_t>(h)) return 0;
  std::size_t n = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) n += is_frontier(map, x, y) ? 1 : 0;
  return n;
}

visualization_msgs::MarkerArray frontier_markers(const nav_msgs::OccupancyGrid& map) {
  visualization_msgs::Marker m;
  m.header = map.header;
  m.ns = "frontiers";
  m.id = 0;
  m.type = visualization_msgs::Marker::CUBE_LIST;
  m.action = visualization_msgs::Marker::ADD;
  m.pose.orientation.w = 1.0;
  m.scale.x = m.scale.y = map.info.resolution;
  m.scale.z = 0.02;
  m.color.r = 1.0f, m.color.g = 0.5f, m.color.b = 0.0f, m.color.a = 0.9f;
  const int w = static_cast<int>(map.info.width), h = static_cast<int>(map.info.height);
  if (map.data.size() == static_cast<std::size_t>(w) * static_cast<std::size_t>(h)) {
    const double ox = map.info.origin.position.x, oy = map.info.origin.position.y, r = map.info.resolution;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        if (is_frontier(map, x, y)) {
          geometry_msgs::Point p;
          p.x = ox + (x + 0.5) * r;
          p.y = oy + (y + 0.5) * r;
          m.points.push_back(p);
        }
  }
  visualization_msgs::MarkerArray a;
  a.markers.push_back(m);
  return a;
}

}  // namespace duet_ros
