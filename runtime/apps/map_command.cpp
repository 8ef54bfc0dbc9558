// `duet map DIR`: maps a folder of RGB-D frames with known camera poses into a cloud (PCD, PLY)
// and a 2D grid (map_server PGM + YAML, PNG), with the mapping pipeline of paper §2.2.
#include "commands.hpp"
#include "stop_signals.hpp"

#include <duet/kernels/error.hpp>
#include <duet/kernels/normals.hpp>
#include <duet/kernels/voxel_filter.hpp>
#include <duet/runtime/io/cloud_io.hpp>
#include <duet/runtime/io/grid_io.hpp>
#include <duet/runtime/io/output.hpp>
#include <duet/runtime/mapping/mapper.hpp>
#include <duet/runtime/config/profile.hpp>
#include <duet/runtime/io/rgbd_dataset.hpp>

#include <nlohmann/json.hpp>
#include <tbb/task_arena.h>

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <sstream>
#include <string>

namespace duet::app {
namespace {

struct MapOptions {
  std::string input;
  std::string out = "out/map";
  std::string profile = "dual";
  std::string up = "auto";
  std::string floor_z = "auto";
  std::string layout = "auto";
  float leaf = 0.0f;      // 0 = profile's
  float grid_res = 0.0f;  // 0 = profile's
  int threads = 0;
  bool quiet = false;
  // duet replay --poses vision: the folder is read without its poses, and these (one per frame;
  // nothing: the frame is not mapped) take their place; `extra` joins summary.json.
  const std::vector<std::optional<Eigen::Isometry3f>>* poses = nullptr;
  nlohmann::json extra;
};

// "+x", "-y", "z", or "ux,uy,uz"; "auto" is handled by the caller.
Eigen::Vector3f parse_up(const std::string& s) {
  if (s.size() <= 2 && !s.empty()) {
    const float sign = s[0] == '-' ? -1.0f : 1.0f;
    const char axis = s.back();
    if (axis == 'x') return Eigen::Vector3f::UnitX() * sign;
    if (axis == 'y') return Eigen::Vector3f::UnitY() * sign;
    if (axis == 'z') return Eigen::Vector3f::UnitZ() * sign;
  }
  Eigen::Vector3f v;
  char c1 = 0, c2 = 0;
  std::istringstream in(s);
  if (in >> v.x() >> c1 >> v.y() >> c2 >> v.z() && c1 == ',' && c2 == ',' && in.peek() == EOF && v.allFinite() &&
      v.norm() > 1e-6f)
    return v.normalized();
  fail(ErrorCode::kInvalidArgument, "--up '" + s + "': expected auto, +x, -x, +y, -y, +z, -z or 'ux,uy,uz' (non-zero)");
}

// Hand-held recordings are usually held roughly level: the mean of the cameras' up axes
// (-y of the optical frame) in the world is a good estimate of the world's up direction.
template <class PoseOf>
Eigen::Vector3f estimate_up(std::size_t frames, const PoseOf& pose_of) {
  Eigen::Vector3f sum = Eigen::Vector3f::Zero();
  for (std::size_t i = 0; i < frames; ++i)
    if (const auto T = pose_of(i)) sum += T->linear() * Eigen::Vector3f(0.0f, -1.0f, 0.0f);
  if (sum.norm() < 1e-3f) return Eigen::Vector3f::UnitZ();
  return sum.normalized();
}

int run_map(const MapOptions& o) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  Profile profile = resolve_profile(o.profile);
  MappingSettings ms = profile.mapping;
  if (o.leaf > 0.0f) ms.voxel_filter.leaf_size_m = o.leaf;
  if (o.grid_res > 0.0f) ms.grid_resolution_m = o.grid_res;

  RgbdDatasetOptions dopt;
  dopt.layout = o.layout;
  dopt.require_poses = o.poses == nullptr;
  const RgbdDataset ds = RgbdDataset::open(o.input, dopt);
  if (ds.empty()) fail(ErrorCode::kInvalidArgument, o.input + ": no frames found");
  if (o.poses && o.poses->size() != ds.size())
    fail(ErrorCode::kInvalidArgument, o.input + ": " + std::to_string(o.poses->size()) + " poses for " + std::to_string(ds.size()) + " frames");
  const auto pose_of = [&](std::size_t i) -> std::optional<Eigen::Isometry3f> {
    if (o.poses) return (*o.poses)[i];
    return ds.pose(i);
  };
  const std::filesystem::path out(o.out);
  const StopSignals signals;  // SIGINT / SIGTERM from here on: stop after the current frame, save the map so far, say so
  prepare_output_dir(out);  // before the frames are mapped, not after
  int stopped_by = 0;
  // A recording's own depth range: the profile's sensor range does not apply to a hand-held camera,
  // but the mapping back-projection range does.
  const bool tty = stderr_is_tty() && !o.quiet;
  tbb::task_arena arena(o.threads > 0 ? o.threads : tbb::task_arena::automatic);
  int rc = 0;
  arena.execute([&] {
    // First pass: every frame in the recording's world frame, voxel-filtered, with normals. It
    // gives the up direction (auto) and the floor height (auto).
    PointCloud merged;
    if (o.up == "auto" || o.floor_z == "auto") {
      PointCloud all, raw, filtered;
      for (std::size_t i = 0; i < ds.size(); ++i) {
        const auto T = pose_of(i);
        if (!T) continue;
        const RgbdFrame f = ds.load(i);
        const SensorFrame sf = f.sensor_frame(*T);
        back_project(std::span<const SensorFrame>(&sf, 1), ms.back_projection, raw);
        voxel_filter(raw.points_view(), ColorsView(), ms.voxel_filter, filtered);
        all.points.insert(all.points.end(), filtered.points.begin(), filtered.points.end());
      }
      voxel_filter(all.points_view(), ColorsView(), ms.voxel_filter, merged);
      if (merged.empty()) fail(ErrorCode::kInvalidArgument, o.input + ": no valid depth in any frame");
      estimate_normals(merged, ms.normals);
    }
    const Eigen::Vector3f up = o.up == "auto" ? refine_up(merged, estimate_up(ds.size(), pose_of)) : parse_up(o.up);
    const Eigen::Isometry3f T_map_world = gravity_alignment(up);
    if (!o.quiet)
      std::fprintf(stderr, "duet map: %s (%s layout, %zu frames), up = (%.3f, %.3f, %.3f)%s\n", o.input.c_str(),
                   ds.layout().c_str(), ds.size(), static_cast<double>(up.x()), static_cast<double>(up.y()),
                   static_cast<double>(up.z()), o.up == "auto" ? " (estimated from the camera poses and surface normals)" : "");
    float floor_z;
    if (o.floor_z == "auto") {
      merged.transform(T_map_world);
      floor_z = estimate_floor_z(merged, ms.segmentation.max_floor_tilt_deg);
      if (!o.quiet) std::fprintf(stderr, "duet map: floor at z = %.3f m in the map frame (estimated)\n", static_cast<double>(floor_z));
    } else {
      try {
        std::size_t used = 0;
        floor_z = std::stof(o.floor_z, &used);
        if (used != o.floor_z.size() || !std::isfinite(floor_z)) throw std::invalid_argument("");
      } catch (const std::exception&) {
        fail(ErrorCode::kInvalidArgument, "--floor-z '" + o.floor_z + "': expected auto or a height in metres");
      }
    }
    ms.segmentation.floor_z_m = floor_z;

    Mapper mapper(ms, T_map_world);
    std::vector<Eigen::Vector2f> track;
    std::size_t mapped = 0;
    for (std::size_t i = 0; i < ds.size(); ++i) {
      if ((stopped_by = StopSignals::received()) != 0) break;
      const auto ti = Clock::now();
      const auto T = pose_of(i);
      if (!T) continue;
      const RgbdFrame f = ds.load(i);
      const SensorFrame sf = f.sensor_frame(*T);  // camera -> world; the "robot" is the world origin
      const auto before = mapper.stats();
      mapper.integrate(std::span<const SensorFrame>(&sf, 1), Eigen::Isometry3f::Identity());
      const auto& st = mapper.stats();
      const Eigen::Vector3f cam = (T_map_world * *T).translation();
      track.push_back(cam.head<2>());
      ++mapped;
      if (!o.quiet) {
        const double dt = std::chrono::duration<double>(Clock::now() - ti).count();
        std::fprintf(stderr, "%s[%zu/%zu] %s: %zu points -> %zu voxels (%zu obstacle, %zu floor), grid %dx%d, %.0f ms%s",
                     tty ? "\r\033[K" : "", i + 1, ds.size(), f.name.c_str(), st.raw_points - before.raw_points,
                     st.filtered_points - before.filtered_points, st.obstacle_points - before.obstacle_points,
                     st.floor_points - before.floor_points, mapper.grid().width(), mapper.grid().height(), dt * 1e3,
                     tty ? "" : "\n");
      }
    }
    if (tty) std::fputc('\n', stderr);

    const PointCloud& cloud = mapper.cloud();
    write_pcd(out / "cloud.pcd", cloud, PcdEncoding::kBinaryCompressed);
    write_ply(out / "cloud.ply", cloud, PlyEncoding::kBinaryLittleEndian);
    write_map_server(mapper.grid(), out / "grid.yaml");
    GridPngOptions png;
    png.scale = std::max(1, 400 / std::max(1, std::max(mapper.grid().width(), mapper.grid().height())));
    png.polyline = track;
    write_grid_png(mapper.grid(), out / "grid.png", png);

    std::vector<std::int8_t> ros(mapper.grid().cell_count());
    mapper.grid().to_ros_trinary(ros);
    std::size_t occ = 0, fr = 0;
    for (const auto v : ros) {
      occ += v == 100;
      fr += v == 0;
    }
    const double area = static_cast<double>(mapper.grid().resolution()) * mapper.grid().resolution();
    nlohmann::json j;
    const auto& st = mapper.stats();
    j["input"] = o.input;
    j["layout"] = ds.layout();
    j["frames"] = st.frames;
    j["raw_points"] = st.raw_points;
    j["cloud_points"] = cloud.size();
    j["voxel_leaf_m"] = ms.voxel_filter.leaf_size_m;
    j["up_in_world"] = {up.x(), up.y(), up.z()};
    j["floor_z_m"] = ms.segmentation.floor_z_m;
    const Eigen::Matrix4f Tm = T_map_world.matrix();
    j["T_map_world_row_major"] = std::vector<float>(Tm.transpose().data(), Tm.transpose().data() + 16);
    j["grid"] = {{"width", mapper.grid().width()},
                 {"height", mapper.grid().height()},
                 {"resolution_m", mapper.grid().resolution()},
                 {"origin_m", {mapper.grid().origin().x(), mapper.grid().origin().y()}},
                 {"occupied_cells", occ},
                 {"free_cells", fr},
                 {"known_area_m2", static_cast<double>(occ + fr) * area}};
    for (const auto& [k, v] : o.extra.items()) j[k] = v;
    j["seconds"] = std::chrono::duration<double>(Clock::now() - t0).count();
    if (stopped_by) {
      j["interrupted"] = std::string(StopSignals::name(stopped_by)) + " after " + std::to_string(mapped) + " of " +
                         std::to_string(ds.size()) + " frames: the map of those frames was saved";
      std::fprintf(stderr, "duet map: %s\n", j["interrupted"].get<std::string>().c_str());
      rc = StopSignals::exit_code(stopped_by);
    }
    write_text_file(out / "summary.json", j.dump(2) + "\n");
    if (!o.quiet)
      std::fprintf(stderr,
                   "duet map: %zu points in the cloud, grid %dx%d at %.3f m (%zu occupied, %zu free cells); wrote %s/{cloud.pcd, "
                   "cloud.ply, grid.yaml, grid.pgm, grid.png, summary.json} in %.2f s\n",
                   cloud.size(), mapper.grid().width(), mapper.grid().height(),
                   static_cast<double>(mapper.grid().resolution()), occ, fr, out.c_str(),
                   std::chrono::duration<double>(Clock::now() - t0).count());
  });
  return rc;
}

}  // namespace

int run_map_folder(const std::string& input, const std::string& out, const std::string& profile, const std::string& layout, int threads,
                   bool quiet, const std::vector<std::optional<Eigen::Isometry3f>>* poses, const nlohmann::json& extra) {
  MapOptions o;
  o.poses = poses;
  o.extra = extra;
  o.input = input;
  o.out = out;
  o.profile = profile;
  o.layout = layout;
  o.threads = threads;
  o.quiet = quiet;
  return run_map(o);
}

void add_map_command(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<MapOptions>();
  auto* cmd = app.add_subcommand("map", "Map a folder of RGB-D frames with known camera poses into a cloud and a 2D grid");
  cmd->add_option("input", o->input, "folder of frames (slambook2, 3dmatch or TUM RGB-D layout)")->required()->check(CLI::ExistingDirectory);
  cmd->add_option("-o,--out", o->out, "output folder")->capture_default_str();
  cmd->add_option("-p,--profile", o->profile, "mapping settings: dual, single or a profile YAML")->capture_default_str();
  cmd->add_option("--up", o->up,
                  "the recording's up direction in its world frame: auto (from the camera poses), +x, -x, +y, -y, +z, "
                  "-z or ux,uy,uz")
      ->capture_default_str();
  cmd->add_option("--floor-z", o->floor_z, "floor height in the gravity-aligned map frame [m], or auto")->capture_default_str();
  cmd->add_option("--layout", o->layout, "auto, slambook2, 3dmatch or tum")->capture_default_str();
  cmd->add_option("--leaf", o->leaf, "voxel size [m] (default: the profile's, 0.05)")->check(CLI::PositiveNumber);
  cmd->add_option("--grid-res", o->grid_res, "grid cell size [m], [0.001, 10] (default: the profile's, 0.05)")->check(CLI::Range(0.001, 10.0));
  cmd->add_option("-j,--threads", o->threads, "worker threads (0 = all cores)")->check(CLI::NonNegativeNumber)->capture_default_str();
  cmd->add_flag("-q,--quiet", o->quiet, "no progress output");
  cmd->callback([o, &exit_code] { exit_code = run_map(*o); });
}

}  // namespace duet::app
