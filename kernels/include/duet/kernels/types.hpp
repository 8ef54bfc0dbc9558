#pragma once
/// @file types.hpp
/// Plain data shared by all kernels: strided views over caller memory and the point cloud
/// container. Frames and units follow DESIGN.md §6 (SI units, REP 103/105).
///
/// Thread safety: views are trivially copyable and read-only; any number of threads may read
/// through the same view while nobody writes the underlying memory.
#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <vector>

namespace duet {

struct Rgb8 {
  std::uint8_t r = 0, g = 0, b = 0;
  friend bool operator==(const Rgb8&, const Rgb8&) = default;
};

/// Read-only view of `count` points of 3 consecutive floats (x, y, z) at `stride_bytes` apart.
/// Lets kernels read PCL clouds, Eigen arrays or C buffers without copying.
class PointsView {
 public:
  PointsView() = default;
  PointsView(const float* xyz, std::size_t count, std::size_t stride_bytes = 3 * sizeof(float))
      : base_(reinterpret_cast<const std::byte*>(xyz)), count_(count), stride_(stride_bytes) {}
  PointsView(std::span<const Eigen::Vector3f> pts)  // NOLINT(google-explicit-constructor)
      : PointsView(pts.empty() ? nullptr : pts.data()->data(), pts.size(), sizeof(Eigen::Vector3f)) {}
  PointsView(const std::vector<Eigen::Vector3f>& pts)  // NOLINT(google-explicit-constructor)
      : PointsView(std::span<const Eigen::Vector3f>(pts)) {}

  [[nodiscard]] std::size_t size() const noexcept { return count_; }
  [[nodiscard]] bool empty() const noexcept { return count_ == 0; }
  [[nodiscard]] std::size_t stride_bytes() const noexcept { return stride_; }
  [[nodiscard]] const float* ptr(std::size_t i) const noexcept {
    return reinterpret_cast<const float*>(base_ + i * stride_);
  }
  [[nodiscard]] Eigen::Vector3f operator[](std::size_t i) const noexcept {
    Eigen::Vector3f p;
    std::memcpy(p.data(), base_ + i * stride_, 3 * sizeof(float));
    return p;
  }

 private:
  const std::byte* base_ = nullptr;
  std::size_t count_ = 0;
  std::size_t stride_ = 3 * sizeof(float);
};

/// Read-only view of `count` colours of 3 consecutive bytes (r, g, b) at `stride_bytes` apart.
class ColorsView {
 public:
  ColorsView() = default;
  ColorsView(const std::uint8_t* rgb, std::size_t count, std::size_t stride_bytes = 3)
      : base_(reinterpret_cast<const std::byte*>(rgb)), count_(count), stride_(stride_bytes) {}
  ColorsView(std::span<const Rgb8> c)  // NOLINT(google-explicit-constructor)
      : ColorsView(c.empty() ? nullptr : &c.data()->r, c.size(), sizeof(Rgb8)) {}
  ColorsView(const std::vector<Rgb8>& c)  // NOLINT(google-explicit-constructor)
      : ColorsView(std::span<const Rgb8>(c)) {}

  [[nodiscard]] std::size_t size() const noexcept { return count_; }
  [[nodiscard]] bool empty() const noexcept { return count_ == 0; }
  [[nodiscard]] const std::uint8_t* ptr(std::size_t i) const noexcept {
    return reinterpret_cast<const std::uint8_t*>(base_ + i * stride_);
  }
  [[nodiscard]] Rgb8 operator[](std::size_t i) const noexcept {
    const std::byte* p = base_ + i * stride_;
    return {std::to_integer<std::uint8_t>(p[0]), std::to_integer<std::uint8_t>(p[1]),
            std::to_integer<std::uint8_t>(p[2])};
  }

 private:
  const std::byte* base_ = nullptr;
  std::size_t count_ = 0;
  std::size_t stride_ = 3;
};

static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float));
static_assert(sizeof(Rgb8) == 3);

/// A point cloud: positions plus optional per-point attributes. Every non-empty attribute
/// vector has exactly points.size() entries.
struct PointCloud {
  std::vector<Eigen::Vector3f> points;   ///< positions [m]
  std::vector<Rgb8> colors;              ///< optional colour
  std::vector<Eigen::Vector3f> normals;  ///< optional unit normals (NaN where undefined)
  std::vector<float> curvature;          ///< optional surface variation lambda0/(l0+l1+l2)

  [[nodiscard]] std::size_t size() const noexcept { return points.size(); }
  [[nodiscard]] bool empty() const noexcept { return points.empty(); }
  [[nodiscard]] bool has_colors() const noexcept { return !colors.empty(); }
  [[nodiscard]] bool has_normals() const noexcept { return !normals.empty(); }
  [[nodiscard]] PointsView points_view() const { return PointsView(points); }
  [[nodiscard]] ColorsView colors_view() const { return ColorsView(colors); }
  void clear() {
    points.clear();
    colors.clear();
    normals.clear();
    curvature.clear();
  }
  /// Throws duet::Error(kInvalidArgument) when an attribute has the wrong length.
  void check_consistent() const;
  /// Appends `other` (attributes must match: both with or both without each attribute,
  /// or this cloud empty).
  void append(const PointCloud& other);
  /// Applies T to points and rotates normals.
  void transform(const Eigen::Isometry3f& T);
};

[[nodiscard]] inline bool is_finite(const Eigen::Vector3f& p) noexcept {
  return std::isfinite(p.x()) && std::isfinite(p.y()) && std::isfinite(p.z());
}

}  // namespace duet
