// The ray-tracing observation model of the paper (§3.1, Fig. 5; entropy of Eq. 5 summed along the
// rays of each sensor's sector), with a 2D DDA backend and an Embree backend (observation.hpp).
#include <duet/kernels/observation.hpp>

#include <duet/kernels/entropy.hpp>
#include <duet/kernels/error.hpp>
#include <duet/kernels/grid.hpp>

#include "observation_model.hpp"
#include "parallel.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

namespace duet {
namespace {

std::string fstr(float v) { return std::to_string(v); }

using detail::fan_direction;
using detail::fan_origin;
using detail::turn;

}  // namespace

// ---- sensors ------------------------------------------------------------------------------------

std::vector<SensorSector> paper_dual_sensors(int rays_per_sensor) {
  SensorSector s1;
  s1.x_m = -0.118f;
  s1.y_m = 0.0f;
  s1.yaw_rad = 0.0f;
  s1.rays = rays_per_sensor;
  SensorSector s2 = s1;
  s2.yaw_rad = -std::numbers::pi_v<float> / 2.0f;
  validate(s1);
  return {s1, s2};
}

float heading_to_look(float look_rad, float from_rad, std::span<const SensorSector> sensors) {
  const float pi = std::numbers::pi_v<float>;
  auto wrap = [pi](float a) {
    a = std::remainder(a, 2.0f * pi);  // [-pi, pi]
    return a <= -pi ? a + 2.0f * pi : a;
  };
  if (!std::isfinite(look_rad) || !std::isfinite(from_rad) || sensors.empty()) return look_rad;
  float best = wrap(look_rad), best_turn = std::numeric_limits<float>::infinity();
  for (const SensorSector& s : sensors) {
    if (!std::isfinite(s.yaw_rad)) continue;
    const float h = wrap(look_rad - s.yaw_rad);
    const float turn_rad = std::fabs(wrap(h - from_rad));
    if (turn_rad < best_turn) {
      best_turn = turn_rad;
      best = h;
    }
  }
  return best;
}

double fan_cells(std::span<const SensorSector> sensors, float resolution_m) {
  const double res = std::max(resolution_m, kMinGridResolutionM);
  double cells = 0.0;  // every ray walked to its range, at most
  for (const auto& sec : sensors) cells += static_cast<double>(sec.rays) * (2.0 * sec.max_range_m / res + 2.0);
  return cells;
}

void validate(const SensorSector& s) {
  if (!std::isfinite(s.x_m) || !std::isfinite(s.y_m) || !std::isfinite(s.yaw_rad))
    fail(ErrorCode::kInvalidArgument, "SensorSector: x_m, y_m, yaw_rad must be finite");
  // A mount offset is within the sensor range limit (a sensor 3e38 m off the robot made Embree
  // rays with infinite origins: found by fuzz_capi).
  if (!(std::fabs(s.x_m) <= kMaxSensorRangeM) || !(std::fabs(s.y_m) <= kMaxSensorRangeM))
    fail(ErrorCode::kInvalidArgument, "SensorSector: x_m, y_m must be within +-" + fstr(kMaxSensorRangeM) + " m of the robot, got " +
                                          fstr(s.x_m) + ", " + fstr(s.y_m));
  if (!(s.fov_rad > 0.0f) || !(s.fov_rad <= 2.0f * std::numbers::pi_v<float>))
    fail(ErrorCode::kInvalidArgument, "SensorSector.fov_rad must be in (0, 2 pi], got " + fstr(s.fov_rad));
  if (!(s.min_range_m >= 0.0f) || !std::isfinite(s.min_range_m))
    fail(ErrorCode::kInvalidArgument, "SensorSector.min_range_m must be finite and >= 0, got " + fstr(s.min_range_m));
  // At most kMaxSensorRangeM: a ray walks range / cell cells, also beyond the grid (unknown), so
  // the range bounds the work of every walk (1e30 m walked for ever).
  if (!(s.max_range_m >= s.min_range_m) || !(s.max_range_m <= kMaxSensorRangeM))
    fail(ErrorCode::kInvalidArgument, "SensorSector.max_range_m must be in [min_range_m (" + fstr(s.min_range_m) + "), " +
                                          fstr(kMaxSensorRangeM) + "] m, got " + fstr(s.max_range_m));
  if (s.rays < 1 || s.rays > 100000)
    fail(ErrorCode::kInvalidArgument, "SensorSector.rays must be in [1, 100000], got " + std::to_string(s.rays));
}

void validate(std::span<const SensorSector> sensors) {
  if (sensors.empty()) fail(ErrorCode::kInvalidArgument, "sensors: at least one SensorSector is required");
  for (const auto& s : sensors) validate(s);
}

void sector_rays(const Pose2& pose, const SensorSector& s, std::span<Eigen::Vector2f> origins,
                 std::span<Eigen::Vector2f> dirs) {
  validate(s);
  if (origins.size() != static_cast<std::size_t>(s.rays) || dirs.size() != static_cast<std::size_t>(s.rays))
    fail(ErrorCode::kInvalidArgument, "sector_rays: origins and dirs must have SensorSector.rays = " +
                                          std::to_string(s.rays) + " elements, got " + std::to_string(origins.size()) +
                                          " and " + std::to_string(dirs.size()));
  const float c = std::cos(pose.theta), sn = std::sin(pose.theta);
  for (int r = 0; r < s.rays; ++r) {
    origins[static_cast<std::size_t>(r)] = fan_origin(pose, s, c, sn);
    dirs[static_cast<std::size_t>(r)] = turn(c, sn, fan_direction(s, r));
  }
}

void validate(const ObservationSettings& s) {
  validate(s.thresholds);
  if (s.backend != ObservationBackend::kEmbree && s.backend != ObservationBackend::kDda)
    fail(ErrorCode::kInvalidArgument, "ObservationSettings.backend must be kEmbree or kDda");
  if (s.tile_cells < 1 || s.tile_cells > 65536)
    fail(ErrorCode::kInvalidArgument,
         "ObservationSettings.tile_cells must be in [1, 65536], got " + std::to_string(s.tile_cells));
}

// ---- the model: grid ingestion ----------------------------------------------------------------

void ObservationModel::Impl::ingest(const GridView& g, std::atomic<std::uint8_t>* dirty) {
  const std::size_t n = g.cell_count();
  logodds.assign(g.logodds.begin(), g.logodds.end());
  view = GridView(std::span<const float>(logodds), g.width, g.height, g.resolution_m, g.origin);
  states.resize(n);
  entropy.resize(n);
  classify_grid(view, settings.thresholds, states);
  grid_entropy(view, entropy);
  const std::size_t bx = (static_cast<std::size_t>(g.width) + 3) / 4, by = (static_cast<std::size_t>(g.height) + 3) / 4;
  const bool keep = dirty != nullptr && packed.size() == bx * by * 16 && blocks_x == bx;
  blocks_x = bx;
  packed.resize(bx * by * 16, kUnknownWord);
  const int w = view.width, h = view.height, T = settings.tile_cells;
  detail::for_blocks(static_cast<std::size_t>(h), 16, [&](std::size_t, std::size_t rb, std::size_t re) {
    for (std::size_t iy = rb; iy < re; ++iy)
      for (int ix = 0; ix < w; ++ix) {
        const std::size_t i = iy * static_cast<std::size_t>(w) + static_cast<std::size_t>(ix);
        const std::uint32_t nw = fixed_entropy(entropy[i]) |
                                 (states[i] == CellState::kOccupied ? kOccupiedBit : 0u);
        std::uint32_t& pw = packed[packed_index(static_cast<unsigned>(ix), static_cast<unsigned>(iy))];
        if (keep && ((pw ^ nw) & kOccupiedBit)) {
          const int y = static_cast<int>(iy);
          const int nb[5][2] = {{ix, y}, {ix - 1, y}, {ix + 1, y}, {ix, y - 1}, {ix, y + 1}};
          for (const auto& c : nb)
            if (c[0] >= 0 && c[1] >= 0 && c[0] < w && c[1] < h)
              dirty[static_cast<std::size_t>(c[1] / T) * static_cast<std::size_t>(tiles_x) + static_cast<std::size_t>(c[0] / T)]
                  .store(1, std::memory_order_relaxed);
        }
        pw = nw;
      }
  });
}

void ObservationModel::Impl::full_rebuild(const GridView& g) {
  validate(g, "ObservationModel::set_grid: grid");
  if (settings.backend == ObservationBackend::kEmbree && g.cell_count() >= (std::size_t{1} << 30))
    fail(ErrorCode::kOutOfRange, "ObservationModel::set_grid: the Embree backend supports grids of < 2^30 cells, got " +
                                     std::to_string(g.cell_count()));
  if (settings.backend == ObservationBackend::kEmbree) {
    release_tiles();
    check("releasing tiles");
  }
  ingest(g, nullptr);
  if (settings.backend != ObservationBackend::kEmbree) return;
  const int T = settings.tile_cells;
  tiles_x = (view.width + T - 1) / T;
  tiles_y = (view.height + T - 1) / T;
  tiles.clear();
  tiles.resize(static_cast<std::size_t>(tiles_x) * static_cast<std::size_t>(tiles_y));
  std::vector<std::size_t> all(tiles.size());
  for (std::size_t t = 0; t < all.size(); ++t) all[t] = t;
  rebuild_tiles(all);
}

std::size_t ObservationModel::Impl::incremental(const GridView& g) {
  validate(g, "ObservationModel::update_grid: grid");
  if (!same_geometry(g) || states.size() != g.cell_count()) {
    full_rebuild(g);
    return tiles.size();
  }
  if (settings.backend != ObservationBackend::kEmbree) {
    ingest(g, nullptr);
    return 0;
  }
  std::unique_ptr<std::atomic<std::uint8_t>[]> dirty(new std::atomic<std::uint8_t>[tiles.size()]);
  for (std::size_t t = 0; t < tiles.size(); ++t) dirty[t].store(0, std::memory_order_relaxed);
  ingest(g, dirty.get());
  std::vector<std::size_t> list;
  for (std::size_t t = 0; t < tiles.size(); ++t)
    if (dirty[t].load(std::memory_order_relaxed)) list.push_back(t);
  if (!list.empty()) rebuild_tiles(list);
  return list.size();
}

// ---- the model: public methods ----------------------------------------------------------------

namespace {
ObservationModel::Impl& need(const std::unique_ptr<ObservationModel::Impl>& p) {
  if (!p) fail(ErrorCode::kInvalidArgument, "ObservationModel: used after being moved from");
  return *p;
}

void check_rays(std::span<const Eigen::Vector2f> origins, std::span<const Eigen::Vector2f> dirs, float t0, float t1,
                std::size_t out_size) {
  if (origins.size() != dirs.size() || out_size != origins.size())
    fail(ErrorCode::kInvalidArgument, "ObservationModel::cast: origins (" + std::to_string(origins.size()) + "), dirs (" +
                                          std::to_string(dirs.size()) + ") and out (" + std::to_string(out_size) +
                                          ") must have the same size");
  if (!(t0 >= 0.0f) || !(t1 >= t0) || !std::isfinite(t1))
    fail(ErrorCode::kInvalidArgument, "ObservationModel::cast: need 0 <= t0 <= t1 < inf, got t0 = " + fstr(t0) +
                                          ", t1 = " + fstr(t1));
  for (std::size_t i = 0; i < origins.size(); ++i) {
    if (!within_map_limits(origins[i]) || !dirs[i].allFinite() || !(std::fabs(dirs[i].squaredNorm() - 1.0f) <= 2e-3f))
      fail(ErrorCode::kInvalidArgument, "ObservationModel::cast: ray " + std::to_string(i) +
                                            ": origin must be within the map frame's +-" + fstr(kMaxCoordinateM) +
                                            " m and dir a unit vector (|dir| within 1e-3 of 1)");
  }
}
}  // namespace

ObservationModel::ObservationModel(const ObservationSettings& s) {
  validate(s);
  impl_ = std::make_unique<Impl>(s);
  if (s.backend == ObservationBackend::kEmbree) impl_->init_embree();
}
ObservationModel::~ObservationModel() = default;
ObservationModel::ObservationModel(ObservationModel&&) noexcept = default;
ObservationModel& ObservationModel::operator=(ObservationModel&&) noexcept = default;

const ObservationSettings& ObservationModel::settings() const { return need(impl_).settings; }
void ObservationModel::set_grid(const GridView& grid) { need(impl_).full_rebuild(grid); }
std::size_t ObservationModel::update_grid(const GridView& grid) { return need(impl_).incremental(grid); }
const GridView& ObservationModel::grid() const { return need(impl_).view; }
std::span<const CellState> ObservationModel::states() const { return need(impl_).states; }
std::span<const float> ObservationModel::entropy() const { return need(impl_).entropy; }
int ObservationModel::tiles_x() const { return need(impl_).tiles_x; }
int ObservationModel::tiles_y() const { return need(impl_).tiles_y; }

void ObservationModel::cast(std::span<const Eigen::Vector2f> origins, std::span<const Eigen::Vector2f> dirs, float t0,
                            float t1, std::span<RayHit> out) const {
  const Impl& m = need(impl_);
  check_rays(origins, dirs, t0, t1, out.size());
  const std::size_t n = origins.size();
  if (m.settings.backend == ObservationBackend::kDda) {
    detail::for_blocks(n, 64, [&](std::size_t, std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) out[i] = m.cast_dda(origins[i], dirs[i], t0, t1);
    });
    return;
  }
  detail::for_blocks(detail::block_count(n, 8), 8, [&](std::size_t, std::size_t pb, std::size_t pe) {
    for (std::size_t p = pb; p < pe; ++p) {
      const std::size_t b = p * 8;
      const int count = static_cast<int>(std::min<std::size_t>(8, n - b));
      float range[8];
      std::int64_t cell[8];
      m.trace8(origins.data() + b, dirs.data() + b, count, t0, t1, range, cell);
      for (int k = 0; k < count; ++k) out[b + static_cast<std::size_t>(k)] = RayHit{range[k], cell[k] >= 0};
    }
  });
}

void ObservationModel::observe(std::span<const Pose2> poses, std::span<const SensorSector> sensors,
                               std::span<RayObservation> out) const {
  const Impl& m = need(impl_);
  validate(sensors);
  std::size_t total = 0;
  for (const auto& s : sensors) total += static_cast<std::size_t>(s.rays);
  if (out.size() != poses.size() * total)
    fail(ErrorCode::kInvalidArgument, "ObservationModel::observe: out has " + std::to_string(out.size()) +
                                          " elements, must be poses.size() * total rays = " +
                                          std::to_string(poses.size() * total));
  for (std::size_t p = 0; p < poses.size(); ++p)
    if (!std::isfinite(poses[p].x) || !std::isfinite(poses[p].y) || !std::isfinite(poses[p].theta))
      fail(ErrorCode::kInvalidArgument, "ObservationModel::observe: pose " + std::to_string(p) + " is not finite");
    else if (!within_map_limits({poses[p].x, poses[p].y}))
      fail(ErrorCode::kOutOfRange, "ObservationModel::observe: pose " + std::to_string(p) + " (" + fstr(poses[p].x) + ", " +
                                       fstr(poses[p].y) + ") is beyond the map frame's +-" + fstr(kMaxCoordinateM) + " m");
  {
    const double cells = static_cast<double>(poses.size()) * fan_cells(sensors, m.view.resolution_m);
    if (!(cells <= kMaxObservedCells))
      fail(ErrorCode::kInvalidArgument, "ObservationModel::observe: poses * the sensors' rays * their cells (" +
                                            std::to_string(static_cast<long long>(cells)) + ") is more than the budget of " +
                                            std::to_string(static_cast<long long>(kMaxObservedCells)) + " cell visits per call");
  }
  std::vector<std::size_t> first(sensors.size());
  for (std::size_t s = 0, acc = 0; s < sensors.size(); ++s) {
    first[s] = acc;
    acc += static_cast<std::size_t>(sensors[s].rays);
  }
  const std::size_t ns = sensors.size();
  const bool dda = m.settings.backend == ObservationBackend::kDda;
  // Each sensor's fan in the robot frame, turned per pose (one sin/cos per pose, not per ray).
  std::vector<std::vector<Eigen::Vector2f>> fans(ns);
  for (std::size_t si = 0; si < ns; ++si) fans[si] = detail::fan_directions(sensors[si]);
  // One task item = one sensor's fan at one pose; per-ray outputs, so any partition gives the same.
  detail::for_each_index(poses.size() * ns, 1, [&](std::size_t job) {
    const std::size_t p = job / ns, si = job % ns;
    const Pose2& pose = poses[p];
    const SensorSector& s = sensors[si];
    RayObservation* o = out.data() + p * total + first[si];
    const float c = std::cos(pose.theta), sn = std::sin(pose.theta);
    const Eigen::Vector2f org = fan_origin(pose, s, c, sn);
    const std::vector<Eigen::Vector2f>& fan = fans[si];
    if (dda) {
      const bool prefetch = m.packed.size() * sizeof(std::uint32_t) > Impl::kPrefetchBytes;
      for (int r = 0; r < s.rays; ++r) {
        const Eigen::Vector2f dir = turn(c, sn, fan[static_cast<std::size_t>(r)]);
        if (prefetch) m.prefetch_ray(org, dir, s.max_range_m);
        o[r] = m.observe_dda_from_sensor(org, dir, s.min_range_m, s.max_range_m);
      }
      return;
    }
    for (int r0 = 0; r0 < s.rays; r0 += 8) {
      const int count = std::min(8, s.rays - r0);
      Eigen::Vector2f orgs[8], dir[8];
      for (int k = 0; k < count; ++k) {
        orgs[k] = org;
        dir[k] = turn(c, sn, fan[static_cast<std::size_t>(r0 + k)]);
      }
      float range[8];
      std::int64_t cell[8];
      m.trace8(orgs, dir, count, s.min_range_m, s.max_range_m, range, cell);
      for (int k = 0; k < count; ++k) {
        const float blocked = m.blocked_before(org, dir[k], s.min_range_m);
        o[r0 + k] = blocked >= 0.0f ? RayObservation{0.0f, blocked, true, 0}
                                    : m.sum_to(org, dir[k], s.min_range_m, s.max_range_m, range[k], cell[k]);
      }
    }
  });
}

float ObservationModel::information_bits(const Pose2& pose, std::span<const SensorSector> sensors) const {
  validate(sensors);
  std::size_t total = 0;
  for (const auto& s : sensors) total += static_cast<std::size_t>(s.rays);
  std::vector<RayObservation> obs(total);
  observe(std::span<const Pose2>(&pose, 1), sensors, obs);
  double sum = 0.0;
  for (const auto& r : obs) sum += static_cast<double>(r.entropy_bits);
  return static_cast<float>(sum);
}

}  // namespace duet
