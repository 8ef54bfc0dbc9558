// duet_cloud: creation, reference counting, contents in and out (duet.h, "Cloud").
#include "capi_internal.hpp"

#include <cstring>

namespace duet::capi {
namespace {

/// Looks the cloud up and runs `body(cloud)` guarded, with errors going to its device.
template <class F>
void with_cloud(duet_cloud handle, const char* fn, F&& body) noexcept {
  auto c = resolve<Cloud>(handle, fn, "cloud");
  if (!c) return;
  guarded(c->device.get(), fn, [&] { body(*c); });
}

/// Shared body of the duet_cloud_get_* borrow functions.
template <class T, class Get>
void borrow(duet_cloud cloud, const char* fn, const T** ptr, size_t* stride, std::size_t elem,
            Get&& get) {
  if (ptr != nullptr) *ptr = nullptr;
  if (stride != nullptr) *stride = 0;
  with_cloud(cloud, fn, [&](Cloud& c) {
    check_not_null(ptr, "ptr");
    std::shared_lock lock(c.mutex);
    *ptr = get(c.cloud);
    if (stride != nullptr) *stride = elem;
  });
}


/// Shared body of the duet_cloud_copy_* functions.
template <class T, class Get>
void copy_out(duet_cloud cloud, const char* fn, void* dst, size_t stride, size_t count,
              std::size_t elem, std::size_t align, const char* attribute, Get&& get) {
  with_cloud(cloud, fn, [&](Cloud& c) {
    const std::size_t s = check_buffer(dst, stride, count, elem, align, "out");
    std::shared_lock lock(c.mutex);
    check_count(c.cloud.size(), count, "out");
    const std::vector<T>& v = get(c.cloud);
    if (count == 0) return;
    if (v.size() != count) {
      api_fail(DUET_ERROR_INVALID_OPERATION,
               std::string("the cloud has no ") + attribute + " (" + std::to_string(count) +
                   " points)");
    }
    scatter(v.data(), count, dst, s);
  });
}


}  // namespace
}  // namespace duet::capi

using namespace duet::capi;

extern "C" {

DUET_API duet_cloud duet_cloud_new(duet_device device) {
  static constexpr const char* fn = "duet_cloud_new";
  auto d = resolve<Device>(device, fn, "device");
  if (!d) return nullptr;
  duet_cloud result = nullptr;
  guarded(d.get(), fn, [&] {
    auto c = std::make_shared<Cloud>(d);
    c->parent = d->key;
    result = to_handle<duet_cloud>(register_object(std::move(c)));
  });
  return result;
}

DUET_API void duet_cloud_retain(duet_cloud cloud) {
  retain_handle(cloud, Kind::kCloud, "duet_cloud_retain");
}

DUET_API void duet_cloud_release(duet_cloud cloud) {
  release_handle(cloud, Kind::kCloud, "duet_cloud_release");
}

DUET_API void duet_cloud_set_points(duet_cloud cloud, const float* xyz, size_t xyz_stride,
                                    const uint8_t* rgb, size_t rgb_stride, size_t count) {
  with_cloud(cloud, "duet_cloud_set_points", [&](Cloud& c) {
    const std::size_t xs = check_buffer(xyz, xyz_stride, count, 3 * sizeof(float), 4, "xyz");
    const std::size_t cs = rgb != nullptr ? check_buffer(rgb, rgb_stride, count, 3, 1, "rgb") : 0;
    std::unique_lock lock(c.mutex);
    duet::PointCloud& out = c.spare;
    out.clear();
    out.points.resize(count);
    if (count > 0) gather3(xyz, xs, count, out.points.data());
    if (rgb != nullptr && count > 0) {
      out.colors.resize(count);
      for (std::size_t i = 0; i < count; ++i) {
        const std::uint8_t* p = rgb + i * cs;
        out.colors[i] = duet::Rgb8{p[0], p[1], p[2]};
      }
    }
    std::swap(c.cloud, c.spare);
  });
}

DUET_API void duet_cloud_clear(duet_cloud cloud) {
  with_cloud(cloud, "duet_cloud_clear", [&](Cloud& c) {
    std::unique_lock lock(c.mutex);
    c.cloud.clear();
  });
}

DUET_API size_t duet_cloud_get_size(duet_cloud cloud) {
  std::size_t n = 0;
  with_cloud(cloud, "duet_cloud_get_size", [&](Cloud& c) {
    std::shared_lock lock(c.mutex);
    n = c.cloud.size();
  });
  return n;
}

DUET_API int duet_cloud_has_colors(duet_cloud cloud) {
  int r = 0;
  with_cloud(cloud, "duet_cloud_has_colors", [&](Cloud& c) {
    std::shared_lock lock(c.mutex);
    r = c.cloud.has_colors() ? 1 : 0;
  });
  return r;
}

DUET_API int duet_cloud_has_normals(duet_cloud cloud) {
  int r = 0;
  with_cloud(cloud, "duet_cloud_has_normals", [&](Cloud& c) {
    std::shared_lock lock(c.mutex);
    r = c.cloud.has_normals() ? 1 : 0;
  });
  return r;
}


DUET_API void duet_cloud_get_points(duet_cloud cloud, const float** ptr, size_t* stride) {
  borrow(cloud, "duet_cloud_get_points", ptr, stride, sizeof(Eigen::Vector3f),
         [](const duet::PointCloud& pc) -> const float* {
           return pc.points.empty() ? nullptr : pc.points.front().data();
         });
}

DUET_API void duet_cloud_get_colors(duet_cloud cloud, const uint8_t** ptr, size_t* stride) {
  borrow(cloud, "duet_cloud_get_colors", ptr, stride, sizeof(duet::Rgb8),
         [](const duet::PointCloud& pc) -> const std::uint8_t* {
           return pc.colors.empty() ? nullptr : &pc.colors.front().r;
         });
}

DUET_API void duet_cloud_get_normals(duet_cloud cloud, const float** ptr, size_t* stride) {
  borrow(cloud, "duet_cloud_get_normals", ptr, stride, sizeof(Eigen::Vector3f),
         [](const duet::PointCloud& pc) -> const float* {
           return pc.normals.empty() ? nullptr : pc.normals.front().data();
         });
}

DUET_API void duet_cloud_get_curvature(duet_cloud cloud, const float** ptr, size_t* stride) {
  borrow(cloud, "duet_cloud_get_curvature", ptr, stride, sizeof(float),
         [](const duet::PointCloud& pc) -> const float* {
           return pc.curvature.empty() ? nullptr : pc.curvature.data();
         });
}


DUET_API void duet_cloud_copy_points(duet_cloud cloud, float* xyz, size_t stride, size_t count) {
  copy_out<Eigen::Vector3f>(cloud, "duet_cloud_copy_points", xyz, stride, count, 12, 4, "points",
                            [](const duet::PointCloud& pc) -> const auto& { return pc.points; });
}

DUET_API void duet_cloud_copy_colors(duet_cloud cloud, uint8_t* rgb, size_t stride, size_t count) {
  copy_out<duet::Rgb8>(cloud, "duet_cloud_copy_colors", rgb, stride, count, 3, 1, "colors",
                       [](const duet::PointCloud& pc) -> const auto& { return pc.colors; });
}

DUET_API void duet_cloud_copy_normals(duet_cloud cloud, float* normals, size_t stride,
                                      size_t count) {
  copy_out<Eigen::Vector3f>(cloud, "duet_cloud_copy_normals", normals, stride, count, 12, 4,
                            "normals",
                            [](const duet::PointCloud& pc) -> const auto& { return pc.normals; });
}

DUET_API void duet_cloud_copy_curvature(duet_cloud cloud, float* curvature, size_t stride,
                                        size_t count) {
  copy_out<float>(cloud, "duet_cloud_copy_curvature", curvature, stride, count, 4, 4, "curvature",
                  [](const duet::PointCloud& pc) -> const auto& { return pc.curvature; });
}

}  // extern "C"
