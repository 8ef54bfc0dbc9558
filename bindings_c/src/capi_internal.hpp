#pragma once
/// @file capi_internal.hpp
/// Internals of the C API (never installed): the handle registry, the objects behind the
/// handles, error reporting and the guard that keeps every exception inside the library.
///
/// Handles are not pointers to the objects: a handle is an opaque 64-bit token
/// (id << 4 | kind) with a never-reused id, looked up in a process-wide registry on every
/// call. A released handle is therefore detected without touching freed memory and can never
/// alias a newer object (no ABA). The registry holds std::shared_ptr<Object>; a call takes
/// its own shared_ptr copy, so an object released by another thread during a call stays
/// alive until that call returns.
#include <duet.h>

#include <duet/kernels/back_projection.hpp>
#include <duet/kernels/clustering.hpp>
#include <duet/kernels/error.hpp>
#include <duet/kernels/grid.hpp>
#include <duet/kernels/normals.hpp>
#include <duet/kernels/segmentation.hpp>
#include <duet/kernels/types.hpp>
#include <duet/kernels/voxel_filter.hpp>
// The exploration planner (planner.cpp, planner_settings.cpp).
#include <duet/kernels/dwa.hpp>
#include <duet/kernels/exploration.hpp>
#include <duet/kernels/frontier.hpp>
#include <duet/kernels/inflation.hpp>
#include <duet/kernels/observation.hpp>
#include <duet/kernels/partial_sim.hpp>
#include <duet/kernels/path.hpp>
#include <duet/kernels/scan_match.hpp>
#include <duet/runtime/config/profile.hpp>

#include <tbb/task_arena.h>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <mutex>
#include <new>
#include <shared_mutex>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace duet::capi {

enum class Kind : std::uint8_t { kDevice = 1, kCloud = 2, kGrid = 3, kPlanner = 4, kRuntime = 5, kSim = 6 };

[[nodiscard]] const char* kind_name(Kind kind) noexcept;

/// A C struct with every byte zero (padding included), so that outputs are deterministic bytes.
template <class T>
T blank() {
  T t;
  std::memset(&t, 0, sizeof t);
  return t;
}

struct Object {
  explicit Object(Kind k) noexcept : kind(k) {}
  Object(const Object&) = delete;
  Object& operator=(const Object&) = delete;
  virtual ~Object() = default;
  /// Called once when the last handle reference is released (outside the registry's lock),
  /// before the registry's shared_ptr is dropped; the object may live on in calls in flight.
  virtual void released() noexcept {}

  const Kind kind;
  std::uint64_t key = 0;      ///< registry key = handle value
  std::uint64_t parent = 0;   ///< key of the creating device (0 for a device)
};

struct Device final : Object {
  Device(int threads, bool verbose);

  tbb::task_arena arena;
  const int thread_count;
  const bool verbose;

  std::mutex error_mutex;
  duet_error first_error = DUET_ERROR_NONE;  // first since the last get
  std::string last_message;
  duet_error_callback callback = nullptr;
  void* callback_user = nullptr;
};

struct Cloud final : Object {
  explicit Cloud(std::shared_ptr<Device> d) : Object(Kind::kCloud), device(std::move(d)) {}
  std::shared_ptr<Device> device;
  std::shared_mutex mutex;
  PointCloud cloud;
  PointCloud spare;  ///< results are computed here, then swapped in (aliasing + strong guarantee)
  VoxelFilterWorkspace voxel_workspace;
};

struct Grid final : Object {
  Grid(std::shared_ptr<Device> d, float resolution)
      : Object(Kind::kGrid), device(std::move(d)), grid(resolution) {}
  std::shared_ptr<Device> device;
  std::shared_mutex mutex;
  OccupancyGrid grid;
  GridUpdateWorkspace workspace;
};

/// The exploration and control kernels' state (duet.h, "Exploration planner"). Every call
/// takes `mutex` exclusively: the workspaces, the DWA state and the blacklist are mutable.
struct Planner final : Object {
  explicit Planner(std::shared_ptr<Device> d)
      : Object(Kind::kPlanner), device(std::move(d)), sensors(paper_dual_sensors(30)) {}
  std::shared_ptr<Device> device;
  std::mutex mutex;

  bool has_grid = false;                    ///< model and inflated describe a valid grid
  ObservationSettings observation_settings; ///< what `model` was built with
  InflationSettings inflation_settings;     ///< what `inflated` was built with
  ObservationModel model;                   ///< owns its copy of the log-odds
  InflatedGrid inflated;
  std::vector<SensorSector> sensors;
  GoalBlacklist blacklist;
  DwaState dwa_state;

  // Workspaces (simulate and find_frontier use the exploration workspace's members).
  ExplorationWorkspace exploration_ws;
  PathWorkspace path_ws;
  DwaWorkspace dwa_ws;
  std::vector<float> staging;               ///< packed copy of strided caller rows
  std::vector<Eigen::Vector2f> path_in;     ///< dwa_step's path, gathered
  std::vector<Pose2> poses_in;              ///< observe's poses, converted
  std::vector<RayObservation> rays_out;     ///< observe's results before conversion
};

template <class T> struct KindOf;
template <> struct KindOf<Device> { static constexpr Kind value = Kind::kDevice; };
template <> struct KindOf<Cloud> { static constexpr Kind value = Kind::kCloud; };
template <> struct KindOf<Grid> { static constexpr Kind value = Kind::kGrid; };
template <> struct KindOf<Planner> { static constexpr Kind value = Kind::kPlanner; };

// ---- errors ------------------------------------------------------------------------------

/// An error raised by the C layer itself (validation).
class ApiError : public std::runtime_error {
 public:
  ApiError(duet_error code, const std::string& what) : std::runtime_error(what), code_(code) {}
  [[nodiscard]] duet_error code() const noexcept { return code_; }

 private:
  duet_error code_;
};

[[noreturn]] inline void api_fail(duet_error code, const std::string& what) {
  throw ApiError(code, what);
}
[[noreturn]] inline void invalid_argument(const std::string& what) {
  throw ApiError(DUET_ERROR_INVALID_ARGUMENT, what);
}

[[nodiscard]] duet_error map_error_code(ErrorCode code) noexcept;

/// Records an error on `device` (nullptr: this thread's no-device slot), prints it when the
/// device is verbose, and calls the callback. Never throws. `fn` prefixes the message.
void report(Device* device, duet_error code, const char* fn, const char* message) noexcept;

/// Runs `body`, converting every exception into a reported error. Returns true on success.
template <class F>
bool guarded(Device* device, const char* fn, F&& body) noexcept {
  try {
    body();
    return true;
  } catch (const ApiError& e) {
    report(device, e.code(), fn, e.what());
  } catch (const Error& e) {
    report(device, map_error_code(e.code()), fn, e.what());
  } catch (const std::bad_alloc&) {
    report(device, DUET_ERROR_OUT_OF_MEMORY, fn, "out of memory");
  } catch (const std::length_error& e) {
    report(device, DUET_ERROR_OUT_OF_MEMORY, fn, e.what());
  } catch (const std::exception& e) {
    report(device, DUET_ERROR_UNKNOWN, fn, e.what());
  } catch (...) {
    report(device, DUET_ERROR_UNKNOWN, fn, "unknown exception");
  }
  return false;
}

/// Runs `body` inside the device's task arena (every kernel call goes through here).
template <class F>
void in_arena(Device& device, F&& body) {
  device.arena.execute(std::forward<F>(body));
}

// ---- registry ----------------------------------------------------------------------------

/// Registers a new object with one reference (and one more reference on its parent device,
/// if `obj->parent` != 0). Returns the handle key.
std::uint64_t register_object(std::shared_ptr<Object> obj);

/// Looks `handle` up. On failure reports and returns nullptr: NULL -> INVALID_ARGUMENT, dead
/// or foreign -> INVALID_OPERATION, other kind -> INVALID_OPERATION. The error goes to the
/// device the handle belongs to when it is known and alive (a handle of another kind, or one of
/// the last released ones) and `to_owner`, else to the no-device slot.
std::shared_ptr<Object> lookup(const void* handle, Kind expected, const char* fn,
                               const char* arg, bool to_owner = true) noexcept;

template <class T>
std::shared_ptr<T> resolve(const void* handle, const char* fn, const char* arg, bool to_owner = true) noexcept {
  return std::static_pointer_cast<T>(lookup(handle, KindOf<T>::value, fn, arg, to_owner));
}

void retain_handle(const void* handle, Kind expected, const char* fn) noexcept;
void release_handle(const void* handle, Kind expected, const char* fn) noexcept;

template <class H>
H to_handle(std::uint64_t key) noexcept {
  return reinterpret_cast<H>(static_cast<std::uintptr_t>(key));
}

// ---- buffers -----------------------------------------------------------------------------

/// Validates a caller buffer of `count` elements of `elem_size` bytes at `stride` (0 =
/// packed) and returns the effective stride. `align` is the required alignment of the pointer
/// and the stride. Throws ApiError(INVALID_ARGUMENT) naming `name`.
std::size_t check_buffer(const void* ptr, std::size_t stride, std::size_t count,
                         std::size_t elem_size, std::size_t align, const char* name);

/// Copies `count` 3-float elements from a strided buffer into packed storage.
inline void gather3(const void* src, std::size_t stride, std::size_t count, Eigen::Vector3f* dst) {
  const auto* p = static_cast<const std::byte*>(src);
  for (std::size_t i = 0; i < count; ++i) {
    std::memcpy(dst[i].data(), p + i * stride, sizeof(Eigen::Vector3f));
  }
}

/// Copies `count` packed elements to a strided caller buffer.
template <class T>
void scatter(const T* src, std::size_t count, void* dst, std::size_t stride) {
  auto* p = static_cast<std::byte*>(dst);
  for (std::size_t i = 0; i < count; ++i) std::memcpy(p + i * stride, &src[i], sizeof(T));
}

/// The int value of an enum received from C. C code may store any int in an enum object, and
/// loading an out-of-range value through the C++ enum type is undefined behaviour, so the
/// bytes are copied instead.
template <class E>
int enum_value(const E& e) noexcept {
  static_assert(sizeof(E) == sizeof(int));
  int v = 0;
  std::memcpy(&v, &e, sizeof v);
  return v;
}

/// Throws ApiError(INVALID_ARGUMENT) "<name>: expected N elements, got M" when they differ.
void check_count(std::size_t expected, std::size_t given, const char* name);

/// Throws ApiError(INVALID_ARGUMENT) when `ptr` is NULL.
void check_not_null(const void* ptr, const char* name);

/// The built-in dual profile (profiles/dual_kinect_kobuki.yaml): the one place the C API's
/// defaults come from (every duet_*_settings_init(), the settings NULL stands for), so that C
/// runs with the values `duet explore` and duet_runtime use.
const Profile& default_profile();

// ---- settings (settings.cpp): C struct -> C++ settings, defaults for NULL, validated ------

BackProjectionSettings to_cpp(const duet_back_projection_settings* s);
VoxelFilterSettings to_cpp(const duet_voxel_filter_settings* s);
NormalSettings to_cpp(const duet_normal_settings* s);
ClusteringSettings to_cpp(const duet_clustering_settings* s);
SegmentationSettings to_cpp(const duet_segmentation_settings* s);
GridUpdateSettings to_cpp(const duet_grid_update_settings* s);
ScanMatchSettings to_cpp(const duet_scan_match_settings* s);

// ---- planner settings (planner_settings.cpp); `name` prefixes the C-level field messages ----

SensorSector to_cpp(const duet_sensor_sector& s);
ObservationSettings to_cpp(const duet_observation_settings* s, const char* name = "settings");
InflationSettings to_cpp(const duet_inflation_settings* s, const char* name = "settings");
PathSettings to_cpp(const duet_path_settings* s, const char* name = "settings");
FrontierSettings to_cpp(const duet_frontier_settings* s, const char* name = "settings");
PartialSimSettings to_cpp(const duet_partial_sim_settings* s, const char* name = "settings");
ExplorationSettings to_cpp(const duet_exploration_settings* s, const char* name = "settings");
DwaSettings to_cpp(const duet_dwa_settings* s, const char* name = "settings");

/// C settings structs from C++ settings (the duet_*_settings_init() bodies; settings.cpp,
/// planner_settings.cpp).
void fill(const BackProjectionSettings& c, duet_back_projection_settings* settings);
void fill(const VoxelFilterSettings& c, duet_voxel_filter_settings* settings);
void fill(const NormalSettings& c, duet_normal_settings* settings);
void fill(const SegmentationSettings& c, duet_segmentation_settings* settings);
void fill(const GridUpdateSettings& c, duet_grid_update_settings* settings);
void fill(const ScanMatchSettings& c, duet_scan_match_settings* settings);
void fill(const ObservationSettings& c, duet_observation_settings* settings);
void fill(const InflationSettings& c, duet_inflation_settings* settings);
void fill(const PathSettings& c, duet_path_settings* settings);
void fill(const ExplorationSettings& c, duet_exploration_settings* settings);
void fill(const DwaSettings& c, duet_dwa_settings* settings);

/// C mirrors of the kernel results (planner_settings.cpp).
duet_sensor_sector to_c(const SensorSector& s);
duet_pose2 to_c(const Pose2& p);
duet_partial_sim_result to_c(const PartialSimResult& r);
duet_frontier_result to_c(const FrontierResult& r);

}  // namespace duet::capi
