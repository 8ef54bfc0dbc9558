// `duet explore`: the paper's experiment in the simulator - a robot with the profile's RGB-D
// sensors explores a world on its own and comes back with the cloud map, the grid map, its
// trajectory, the time-area curve (Fig. 10) and a JSON summary.
// `duet compare`: dual against single sensors over several seeds, both curves in one PNG.
#include "commands.hpp"
#include "explore_outputs.hpp"
#include "stop_signals.hpp"

#include <duet/kernels/error.hpp>
#include <duet/runtime/io/cloud_io.hpp>
#include <duet/runtime/io/grid_io.hpp>
#include <duet/runtime/io/output.hpp>
#include <duet/runtime/io/plot.hpp>
#include <duet/runtime/config/profile.hpp>
#include <duet/sim/sim_explore.hpp>
#include <duet/sim/world.hpp>

#include <nlohmann/json.hpp>
#include <tbb/task_arena.h>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

namespace duet::app {

nlohmann::json faults_json(const std::vector<FaultCount>& faults) {
  nlohmann::json j = nlohmann::json::array();
  for (const auto& f : faults) j.push_back({{"spec", f.fault.spec}, {"kind", to_string(f.fault.kind)}, {"injected", f.injected}});
  return j;
}


namespace {

struct ExploreOptions {
  std::string world = "lab";
  std::string profile = "dual";
  std::uint64_t seed = 1;
  double max_time = 600.0;
  double stop_at_coverage = 0.0;
  std::string out = "out";
  std::string sensor_rate = "pipeline";
  int threads = 0;
  bool realtime = false;
  std::string execution = "auto";
  bool true_pose = false;
  bool raw_odometry = false;
  float gyro_noise = 0.0f;
  float gyro_bias = -1.0f;  // < 0: the simulator's default (ChassisSimSettings::gyro_bias_std_radps)
  bool no_loop_closure = false;
  std::string on_done;  // empty: the profile's exploration.on_done
  std::vector<std::string> faults;  // --fault, added to the profile's
  std::string record;               // --record DIR
  std::string start;                // --start x,y,theta (empty: the world's, or the map's .start file)
  std::string strategy = "profile";
  std::vector<std::string> configs, sets;
  bool quiet = false;
};

struct CompareOptions {
  std::string world = "lab";
  std::string profiles = "dual,single";
  std::string strategies = "paper";
  std::vector<std::string> configs, sets;
  int seeds = 3;
  std::uint64_t first_seed = 1;
  double max_time = 600.0;
  double stop_at_coverage = 0.0;
  std::string out = "out/compare";
  int threads = 0;
  bool quiet = false;
};

double parse_sensor_rate(const std::string& s) {
  if (s == "pipeline") return 0.0;
  if (s == "full") return -1.0;  // the profile's rate
  try {
    std::size_t used = 0;
    const double v = std::stod(s, &used);
    if (used == s.size() && std::isfinite(v) && v > 0.0 && v <= 1000.0) return v;
  } catch (const std::exception&) {
  }
  fail(ErrorCode::kInvalidArgument, "--sensor-rate '" + s + "': expected pipeline, full or a rate in (0, 1000] Hz");
}

/// The goal selection strategies `--strategy` names (the profile's settings otherwise).
void apply_strategy(Profile& p, const std::string& strategy) {
  ExplorationSettings& s = p.exploration.strategy;
  if (strategy == "paper") {  // Fig. 6: partial map simulation, nearest frontier when R_g <= eps_R
    s.use_simulation = true;
    s.frontier.selection = FrontierSelection::kNearest;
  } else if (strategy == "nearest_frontier") {  // Yamauchi 1997
    s.use_simulation = false;
    s.frontier.selection = FrontierSelection::kNearest;
  } else if (strategy == "explore_lite") {  // explore_lite's frontier cost, its default weights
    s.use_simulation = false;
    s.frontier.selection = FrontierSelection::kExploreLite;
  } else if (strategy != "profile") {
    fail(ErrorCode::kInvalidArgument, "strategy '" + strategy + "': expected paper, nearest_frontier, explore_lite or profile");
  }
}

std::vector<std::string> split_list(const std::string& s) {
  std::vector<std::string> out;
  std::size_t b = 0;
  while (b <= s.size()) {
    const std::size_t e = std::min(s.find(',', b), s.size());
    if (e > b) out.push_back(s.substr(b, e - b));
    b = e + 1;
  }
  return out;
}


void print_progress(const sim::SimExplore& run, bool tty, const char* prefix) {
  const auto s = run.summary();  // measures the map once
  std::fprintf(stderr, "%s%st = %6.1f s  area %6.2f m^2  coverage %5.1f %%  goals %d  collisions %zu  %.1fx real time%s",
               tty ? "\r\033[K" : "", prefix, s.sim_time_s, s.explored_area_m2, 100.0 * s.coverage, s.explorer.goals_reached, s.collisions,
               s.wall_time_s > 0.0 ? s.sim_time_s / s.wall_time_s : 0.0, tty ? "" : "\n");
}

/// Steps `run` to its end with progress on stderr (a terminal: one line updated in place; else a
/// line every 10 simulated s); a SIGINT or SIGTERM (StopSignals) interrupts it, with a stop
/// detail "<prefix><signal> at t = <t> s: <saved>". Returns the signal, 0 if none came.
int run_to_end(sim::SimExplore& run, bool quiet, bool tty, const std::string& prefix, const char* saved) {
  double next_line = 0.0, next_report = 0.0;
  auto progress = [&] {
    if (quiet || (!tty && run.running() && run.now_s() + 1e-9 < next_line)) return;
    print_progress(run, tty, prefix.c_str());
    next_line = run.now_s() + 10.0;
  };
  int sig = 0;
  while (run.step()) {
    if ((sig = StopSignals::received()) != 0) {
      char why[160];
      std::snprintf(why, sizeof why, "%s at t = %.1f s: %s", StopSignals::name(sig), run.now_s(), saved);
      run.interrupt(prefix + why);
      break;
    }
    if (run.now_s() + 1e-9 >= next_report) {
      progress();
      next_report += 1.0;
    }
  }
  progress();
  if (tty) std::fputc('\n', stderr);
  return sig;
}

int run_explore(const ExploreOptions& o) {
  if (!(std::isfinite(o.max_time) && o.max_time > 0.0 && o.max_time <= 1e6))
    fail(ErrorCode::kInvalidArgument, "--max-time must be in (0, 1e6] s, got " + std::to_string(o.max_time));
  const double rate = parse_sensor_rate(o.sensor_rate);
  const StopSignals signals;  // SIGINT / SIGTERM from here on: stop, save the run so far, say so
  prepare_output_dir(o.out);  // before the run, not after it
  sim::World world = sim::resolve_world(o.world);
  Profile profile = resolve_profile(o.profile, overlays(o.configs, o.sets));
  if (!o.start.empty()) sim::set_start(world, sim::parse_start(o.start), profile.chassis.radius_m, "--start");
  apply_strategy(profile, o.strategy);
  sim::ExploreSettings es = sim::explore_settings(profile, o.seed, o.max_time, rate);
  es.stop_at_coverage = o.stop_at_coverage / 100.0;
  es.realtime = o.realtime;
  // Flags given on the command line override the profile; absent ones leave it.
  if (o.execution == "background" || (o.execution == "auto" && o.realtime)) es.runtime.execution = Execution::kBackground;
  else if (o.execution == "lockstep") es.runtime.execution = Execution::kLockstep;
  es.use_true_pose = o.true_pose;
  es.record_dir = o.record;
  es.faults.insert(es.faults.end(), o.faults.begin(), o.faults.end());
  (void)parse_faults(es.faults, profile.sensors.size());  // a bad --fault is an error before the run
  if (o.on_done == "return_home") es.runtime.explorer.on_done = OnDone::kReturnHome;
  else if (o.on_done == "stay") es.runtime.explorer.on_done = OnDone::kStay;
  else if (o.on_done == "patrol") es.runtime.explorer.on_done = OnDone::kPatrol;
  if (o.raw_odometry) es.runtime.pose_correction.enabled = false;
  if (o.no_loop_closure) es.runtime.loop_closure.enabled = false;
  if (o.gyro_noise != 0.0f || o.gyro_bias >= 0.0f) {
    es.chassis = sim::ChassisSimSettings::from_profile(profile.chassis);
    es.chassis->gyro_heading = true;  // as the default chassis (the Kobuki's gyro heading)
    es.chassis->gyro_noise_density = o.gyro_noise;
    if (o.gyro_bias >= 0.0f) es.chassis->gyro_bias_std_radps = o.gyro_bias;
  }
  const bool tty = stderr_is_tty() && !o.quiet;
  int stopped_by = 0;  // the stop signal received, 0 if none
  tbb::task_arena arena(o.threads > 0 ? o.threads : tbb::task_arena::automatic);
  arena.execute([&] {
    if (!o.quiet)
      std::fprintf(stderr, "duet explore: world '%s' (%s), profile '%s' (%zu sensors), seed %llu, max %.0f s%s%s\n",
                   world.name.c_str(), world.source.c_str(), profile.name.c_str(), profile.sensors.size(),
                   static_cast<unsigned long long>(o.seed), o.max_time, o.realtime ? ", real time" : "",
                   o.true_pose ? ", TRUE POSE (debugging)" : "");
    sim::SimExplore run(std::move(world), std::move(profile), es);
    stopped_by = run_to_end(run, o.quiet, tty, "", "the run so far was saved");
    write_outputs(run, o.out);
    const auto s = run.summary();
    if (!o.quiet || stopped_by) {
      std::fprintf(stderr,
                   "duet explore: %s (%s%s%s) at %.1f s: %.2f m^2 explored, coverage %.1f %% of %.2f m^2 reachable, "
                   "%zu collisions, path %.1f m; wrote %s/{cloud.pcd, cloud.ply, grid.yaml, grid.pgm, grid.png, "
                   "trajectory.tum, trajectory_true.tum, curve.csv, curve.png, health.csv, log.json, summary.json}\n",
                   "stopped", sim::to_string(s.stop_reason), s.stop_detail.empty() ? "" : ": ",
                   s.stop_detail.c_str(), s.sim_time_s, s.explored_area_m2, 100.0 * s.coverage, s.reachable_free_area_m2,
                   s.collisions, s.path_length_m, o.out.c_str());
    }
    if (!o.record.empty() && !o.quiet) {
      const RecorderStats r = run.recording();
      std::fprintf(stderr, "duet explore: recorded %llu frames and %llu odometry messages to %s (duet replay %s maps them again)\n",
                   static_cast<unsigned long long>(r.frames_recorded), static_cast<unsigned long long>(r.odometry_recorded),
                   o.record.c_str(), o.record.c_str());
    }
  });
  return stopped_by ? StopSignals::exit_code(stopped_by) : 0;
}

/// The means of one variant's runs (Explore-Bench's measures: coverage, times to the paper's
/// area and to 90 % coverage over the runs that reached them, total time, path length,
/// collisions, runs that stopped by themselves).
nlohmann::json variant_means(const nlohmann::json& runs, const std::string& variant, const std::string& world) {
  double t31 = 0.0, t90 = 0.0, cov = 0.0, total = 0.0, path = 0.0;
  int n31 = 0, n90 = 0, n = 0, self_stopped = 0;
  std::size_t collisions = 0;
  for (const auto& r : runs) {
    if (r["variant"].get<std::string>() != variant || (!world.empty() && r["world"].get<std::string>() != world)) continue;
    ++n;
    cov += r["coverage"].get<double>();
    total += r["sim_time_s"].get<double>();
    path += r["path_length_m"].get<double>();
    collisions += r["collisions"].get<std::size_t>();
    self_stopped += r["stop_reason"].get<std::string>() == "explorer_done";
    if (!r["t_31m2_s"].is_null()) {
      t31 += r["t_31m2_s"].get<double>();
      ++n31;
    }
    if (!r["t90_s"].is_null()) {
      t90 += r["t90_s"].get<double>();
      ++n90;
    }
  }
  return {{"runs", n},
          {"coverage", n ? cov / n : 0.0},
          {"collisions", collisions},
          {"runs_stopped_by_themselves", self_stopped},
          {"t_total_s", n ? total / n : 0.0},
          {"path_length_m", n ? path / n : 0.0},
          {"runs_reaching_31m2", n31},
          {"t_31m2_s", n31 ? nlohmann::json(t31 / n31) : nlohmann::json(nullptr)},
          {"runs_reaching_90pct", n90},
          {"t90_s", n90 ? nlohmann::json(t90 / n90) : nlohmann::json(nullptr)}};
}

/// compare.json: every run's summary; "mean": the means per variant over all runs; with several
/// worlds also "per_world" (the means per world and variant) and "mean_over_worlds" (each world
/// weighs the same: the mean of its means; T_90 over the worlds where it was reached, and
/// "t90_worlds" how many); "t90_ratio": each variant's mean T_90 over the worlds where every
/// variant reached 90 %, divided into the first variant's (> 1: the first is faster);
/// "interrupted" says why a comparison stopped early.
nlohmann::json compare_json(const std::vector<std::string>& worlds, const nlohmann::json& runs, const std::vector<std::string>& variants,
                            const std::string& interrupted) {
  nlohmann::json j;
  j["world"] = worlds.size() == 1 ? nlohmann::json(worlds.front()) : nlohmann::json(nullptr);
  j["worlds"] = worlds;
  j["runs"] = runs;
  for (const std::string& variant : variants) j["mean"][variant] = variant_means(runs, variant, "");
  for (const std::string& w : worlds)
    for (const std::string& variant : variants) j["per_world"][w][variant] = variant_means(runs, variant, w);
  for (const std::string& variant : variants) {
    double cov = 0.0, total = 0.0, path = 0.0, t90 = 0.0;
    int n = 0, n90 = 0;
    std::size_t collisions = 0;
    for (const std::string& w : worlds) {
      const nlohmann::json& m = j["per_world"][w][variant];
      if (m["runs"].get<int>() == 0) continue;
      ++n;
      cov += m["coverage"].get<double>();
      total += m["t_total_s"].get<double>();
      path += m["path_length_m"].get<double>();
      collisions += m["collisions"].get<std::size_t>();
      if (!m["t90_s"].is_null()) {
        t90 += m["t90_s"].get<double>();
        ++n90;
      }
    }
    j["mean_over_worlds"][variant] = {{"worlds", n},
                                      {"coverage", n ? cov / n : 0.0},
                                      {"collisions", collisions},
                                      {"t_total_s", n ? total / n : 0.0},
                                      {"path_length_m", n ? path / n : 0.0},
                                      {"t90_worlds", n90},
                                      {"t90_s", n90 ? nlohmann::json(t90 / n90) : nlohmann::json(nullptr)}};
  }
  // T_90 ratios on the worlds where every variant reached 90 % (the same worlds for all).
  if (variants.size() > 1) {
    std::vector<double> sum(variants.size(), 0.0);
    int common = 0;
    for (const std::string& w : worlds) {
      bool all = true;
      for (const std::string& v : variants) all = all && !j["per_world"][w][v]["t90_s"].is_null();
      if (!all) continue;
      ++common;
      for (std::size_t k = 0; k < variants.size(); ++k) sum[k] += j["per_world"][w][variants[k]]["t90_s"].get<double>();
    }
    j["t90_ratio"]["worlds"] = common;
    for (std::size_t k = 1; k < variants.size(); ++k)
      j["t90_ratio"][variants[k] + " / " + variants[0]] = common && sum[0] > 0.0 ? nlohmann::json(sum[k] / sum[0]) : nlohmann::json(nullptr);
  }
  if (!interrupted.empty()) j["interrupted"] = interrupted;
  return j;
}

/// compare.md: the per-world table and the means over the worlds, in Markdown.
std::string compare_markdown(const nlohmann::json& j, const std::vector<std::string>& worlds, const std::vector<std::string>& variants) {
  auto num = [](const nlohmann::json& v, const char* fmt) {
    if (v.is_null()) return std::string("-");
    char b[64];
    std::snprintf(b, sizeof b, fmt, v.get<double>());
    return std::string(b);
  };
  std::string md = "| world | variant | runs | coverage | T_90 [s] | T_total [s] | path [m] | collisions | stopped by itself |\n"
                   "|---|---|---|---|---|---|---|---|---|\n";
  for (const std::string& w : worlds)
    for (const std::string& v : variants) {
      const nlohmann::json& m = j["per_world"][w][v];
      md += "| " + w + " | " + v + " | " + std::to_string(m["runs"].get<int>()) + " | " + num(100.0 * m["coverage"].get<double>(), "%.1f %%") +
            " | " + num(m["t90_s"], "%.0f") + " (" + std::to_string(m["runs_reaching_90pct"].get<int>()) + ")" + " | " +
            num(m["t_total_s"], "%.0f") + " | " + num(m["path_length_m"], "%.0f") + " | " +
            std::to_string(m["collisions"].get<std::size_t>()) + " | " + std::to_string(m["runs_stopped_by_themselves"].get<int>()) + " |\n";
    }
  if (worlds.size() > 1)
    for (const std::string& v : variants) {
      const nlohmann::json& m = j["mean_over_worlds"][v];
      md += "| **mean over " + std::to_string(m["worlds"].get<int>()) + " worlds** | " + v + " | | " +
            num(100.0 * m["coverage"].get<double>(), "%.1f %%") + " | " + num(m["t90_s"], "%.0f") + " (" +
            std::to_string(m["t90_worlds"].get<int>()) + " worlds) | " + num(m["t_total_s"], "%.0f") + " | " +
            num(m["path_length_m"], "%.0f") + " | " + std::to_string(m["collisions"].get<std::size_t>()) + " | |\n";
    }
  if (j.contains("t90_ratio")) {
    md += "\nT_90 ratio over the " + std::to_string(j["t90_ratio"]["worlds"].get<int>()) + " worlds where every variant reached 90 %:";
    for (const auto& [k, v] : j["t90_ratio"].items())
      if (k != "worlds") md += " " + k + " = " + num(v, "%.2f") + ";";
    md += "\n";
  }
  return md;
}

int run_compare(const CompareOptions& o) {
  if (o.seeds < 1 || o.seeds > 1000) fail(ErrorCode::kInvalidArgument, "--seeds must be in [1, 1000]");
  const std::vector<std::string> profiles = split_list(o.profiles), strategies = split_list(o.strategies), world_args = split_list(o.world);
  if (profiles.empty() || strategies.empty()) fail(ErrorCode::kInvalidArgument, "--profiles and --strategies must name at least one each");
  if (world_args.empty()) fail(ErrorCode::kInvalidArgument, "--world must name at least one world");
  const std::vector<ProfileOverlay> over = overlays(o.configs, o.sets);
  for (const auto& st : strategies) {
    Profile probe = resolve_profile(profiles.front(), over);
    apply_strategy(probe, st);  // a bad name fails before any run
  }
  std::vector<sim::World> worlds;  // every world loads before any run (a bad path fails at once)
  std::vector<std::string> world_names;
  for (const std::string& w : world_args) {
    worlds.push_back(sim::resolve_world(w));
    if (std::find(world_names.begin(), world_names.end(), worlds.back().name) != world_names.end())
      fail(ErrorCode::kInvalidArgument, "--world names " + worlds.back().name + " twice");
    world_names.push_back(worlds.back().name);
  }
  const std::filesystem::path out(o.out);
  const StopSignals signals;  // SIGINT / SIGTERM from here on: stop the current run, save the runs so far, say so
  prepare_output_dir(out);  // before the runs, not after them
  tbb::task_arena arena(o.threads > 0 ? o.threads : tbb::task_arena::automatic);
  const bool tty = stderr_is_tty() && !o.quiet;
  nlohmann::json runs = nlohmann::json::array();
  std::vector<std::vector<PlotSeries>> series(worlds.size());
  std::vector<std::string> variants;
  for (const std::string& pname : profiles)
    for (const std::string& strategy : strategies)
      variants.push_back(strategies.size() == 1 ? pname : profiles.size() == 1 ? strategy : pname + "/" + strategy);
  std::string csv = "world,variant,profile,strategy,seed,time_s,explored_area_m2,coverage\n";
  std::string interrupted;  // why the comparison stopped early ("" if it did not)
  int stopped_by = 0;
  static const Rgb8 kColours[] = {{30, 90, 200}, {220, 120, 20}, {40, 160, 60}, {180, 40, 160}, {120, 120, 120}, {200, 40, 40}};
  // The results so far, rewritten after every run (each file replaced whole): a comparison
  // stopped at any point - a signal, a kill, a crash - keeps every run it finished.
  auto write_results = [&] {
    for (std::size_t w = 0; w < worlds.size(); ++w) {
      if (worlds.size() > 1 && series[w].empty()) continue;  // a world not run yet
      PlotOptions po;
      po.title = "Time-area curves on " + world_names[w] + " (" + std::to_string(o.seeds) + " seeds each)";
      po.x_label = "time [s]";
      po.y_label = "explored area [m^2]";
      po.markers = paper_markers();
      write_plot_png(out / (worlds.size() == 1 ? std::string("compare.png") : "compare_" + world_names[w] + ".png"), series[w], po);
    }
    write_text_file(out / "compare.csv", csv);
    const nlohmann::json j = compare_json(world_names, runs, variants, interrupted);
    write_text_file(out / "compare.json", j.dump(2) + "\n");
    write_text_file(out / "compare.md", compare_markdown(j, world_names, variants));
  };
  arena.execute([&] {
    for (std::size_t w = 0; w < worlds.size() && !stopped_by; ++w) {
      std::size_t vi = 0;
      for (const std::string& pname : profiles)
        for (const std::string& strategy : strategies) {
          const std::string& variant = variants[vi];
          const Rgb8 colour = kColours[vi++ % std::size(kColours)];
          for (int k = 0; k < o.seeds && !stopped_by; ++k) {
            const std::uint64_t seed = o.first_seed + static_cast<std::uint64_t>(k);
            Profile profile = resolve_profile(pname, over);
            apply_strategy(profile, strategy);
            sim::ExploreSettings es = sim::explore_settings(profile, seed, o.max_time, 0.0);
            es.stop_at_coverage = o.stop_at_coverage / 100.0;
            sim::SimExplore run(worlds[w], std::move(profile), es);
            const std::string label = (worlds.size() > 1 ? world_names[w] + " " : std::string()) + variant + " seed " + std::to_string(seed) + ": ";
            stopped_by = run_to_end(run, o.quiet, tty, label, "the runs so far were saved");
            if (stopped_by) interrupted = run.summary().stop_detail;
            series[w].push_back(curve_series(run.curve(), k == 0 ? variant : "", colour, 2));
            for (const auto& c : run.curve()) {
              char buf[320];
              std::snprintf(buf, sizeof buf, "%s,%s,%s,%s,%llu,%.2f,%.3f,%.4f\n", world_names[w].c_str(), variant.c_str(), pname.c_str(),
                            strategy.c_str(), static_cast<unsigned long long>(seed), c.t_s, c.area_m2, c.coverage);
              csv += buf;
            }
            nlohmann::json r = to_json(run.summary());
            r["variant"] = variant;
            r["strategy"] = strategy;
            runs.push_back(std::move(r));
            write_results();
          }
          if (stopped_by) break;
        }
    }
  });
  if (runs.empty()) write_results();
  if (!o.quiet || stopped_by) {
    const nlohmann::json j = compare_json(world_names, runs, variants, interrupted);
    std::fprintf(stderr, "duet compare: %s%swrote %s/{compare.png, compare.csv, compare.json, compare.md}\n%s", interrupted.c_str(),
                 interrupted.empty() ? "" : "; ", o.out.c_str(), compare_markdown(j, world_names, variants).c_str());
  }
  return stopped_by ? StopSignals::exit_code(stopped_by) : 0;
}

/// --stop-at-coverage, the same for `duet explore` and `duet compare` (percent; 0 = none).
void add_stop_at_coverage(CLI::App& cmd, double& percent) {
  cmd.add_option("--stop-at-coverage", percent,
                 "stop once the scored coverage of the world's reachable free area reaches this percentage (stop reason coverage_reached; for times to a coverage such as T_90 without running on to the end). Default: no such stop")
      ->check(CLI::Range(0.0, 100.0).description("[0, 100] %, 0 = none"));
}

}  // namespace

void add_explore_command(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<ExploreOptions>();
  auto* cmd = app.add_subcommand("explore", "Explore a simulated world autonomously (the paper's experiment) and write the maps");
  cmd->add_option("-w,--world", o->world, "a built-in world (lab), a world YAML or a map_server map YAML")->capture_default_str();
  cmd->add_option("-p,--profile", o->profile, "robot profile: dual, single or a profile YAML")->capture_default_str();
  cmd->add_option("--start", o->start,
                  "the robot's start pose x,y,theta (m, m, rad; the world's frame), checked: on the floor and clear of walls "
                  "for the profile's radius. Default: the world's start - for a map_server map, NAME.start beside its YAML when "
                  "present (the real robot's first pose, one line x y theta), else a free spot near the map's centre");
  cmd->add_option("-s,--seed", o->seed, "random seed (sensor and odometry noise, Procedure 1)")->capture_default_str();
  cmd->add_option("-t,--max-time", o->max_time, "simulated time limit [s]")->capture_default_str();
  add_stop_at_coverage(*cmd, o->stop_at_coverage);
  cmd->add_option("-o,--out", o->out, "output folder")->capture_default_str();
  cmd->add_option("--sensor-rate", o->sensor_rate,
                  "render rate: pipeline (what the pipeline consumes: the map rate, 1 Hz - or vision's localization.visual_odometry.rate_hz, 5 Hz, when it is on), full (the profile's 30 Hz) or a rate in Hz")
      ->capture_default_str();
  cmd->add_flag("--realtime", o->realtime, "pace the simulation by the wall clock (the runtime then runs in the background mode)");
  cmd->add_option("--execution", o->execution,
                  "runtime execution: lockstep (map updates and decisions inside the control period: deterministic), background "
                  "(they run as background tasks and control never waits, as on a robot) or auto (background with --realtime, "
                  "else the profile's runtime.execution)")
      ->check(CLI::IsMember({"auto", "lockstep", "background"}))
      ->capture_default_str();
  cmd->add_flag("--true-pose", o->true_pose, "DEBUGGING: map with the true pose instead of the wheel odometry");
  cmd->add_option("--record", o->record,
                  "record every input stream the runtime takes (frames as PNG, odometry, the profile) into this new or empty "
                  "folder (docs/recording.md); `duet replay DIR` maps it again");
  cmd->add_option("--fault", o->faults,
                  "inject a fault, KIND[:SENSOR]@START[+DURATION][=AMOUNT] (repeatable; e.g. camera_stop:1@60+10; kinds: camera_stop, "
                  "depth_zero, depth_noise, color_black, extrinsics, wheel_slip, odom_jump, stamp_disorder, stamp_duplicate, "
                  "stamp_late, clock_back, kidnap; see runtime/robot/faults.hpp)");
  cmd->add_flag("--raw-odometry", o->raw_odometry, "pose = the raw wheel odometry (no scan-to-map correction)");
  cmd->add_option("--gyro-noise", o->gyro_noise,
                  "simulated gyro's rate-noise density [rad/s/sqrt(Hz)], [0, 0.01] (ChassisSimSettings::gyro_noise_density; 0 = none)")
      ->capture_default_str();
  cmd->add_option("--gyro-bias", o->gyro_bias,
                  "std of the simulated gyro's constant bias, drawn once per run from the seed [rad/s], [0, 0.1] "
                  "(ChassisSimSettings::gyro_bias_std_radps; default 8.7e-5; 0 = a gyro without bias)")
      ->check(CLI::Range(0.0f, 0.1f));
  cmd->add_flag("--no-loop-closure", o->no_loop_closure,
                "no loop closure (LoopClosureSettings::enabled = false): the map is the front end's (odometry + scan matching)");
  add_overlay_options(cmd, o->configs, o->sets);
  cmd->add_option("--strategy", o->strategy,
                  "goal selection: profile (the profile's settings), paper (Fig. 6: partial map simulation, then the nearest "
                  "frontier), nearest_frontier (Yamauchi) or explore_lite (its frontier cost)")
      ->check(CLI::IsMember({"profile", "paper", "nearest_frontier", "explore_lite"}))
      ->capture_default_str();
  cmd->add_option("--on-done", o->on_done,
                  "once explored: stay, return_home (drive back to the start and stop there) or patrol (drive a round of "
                  "waypoints along the trail until the time limit); default: the profile's exploration.on_done")
      ->check(CLI::IsMember({"stay", "return_home", "patrol"}));
  cmd->add_option("-j,--threads", o->threads, "worker threads (0 = all cores)")->check(CLI::NonNegativeNumber)->capture_default_str();
  cmd->add_flag("-q,--quiet", o->quiet, "no progress output");
  cmd->callback([o, &exit_code] { exit_code = run_explore(*o); });
}

void add_compare_command(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<CompareOptions>();
  auto* cmd = app.add_subcommand("compare",
                                 "Explore with several profiles and goal selection strategies over several seeds; plot the curves (Fig. 10)");
  cmd->add_option("-w,--world", o->world,
                  "comma-separated worlds: built-in (lab), world YAMLs or map_server map YAMLs (each from its own start: a map's "
                  "NAME.start when present); with several, compare.md has a row per world and the means over the worlds")
      ->capture_default_str();
  cmd->add_option("--profiles", o->profiles, "comma-separated profiles (built-in names or YAML files)")->capture_default_str();
  cmd->add_option("--strategies", o->strategies, "comma-separated strategies: paper, nearest_frontier, explore_lite, profile")
      ->capture_default_str();
  add_overlay_options(cmd, o->configs, o->sets);
  cmd->add_option("-n,--seeds", o->seeds, "runs per profile")->capture_default_str();
  cmd->add_option("--first-seed", o->first_seed, "seed of the first run")->capture_default_str();
  cmd->add_option("-t,--max-time", o->max_time, "simulated time limit per run [s]")->capture_default_str();
  add_stop_at_coverage(*cmd, o->stop_at_coverage);
  cmd->add_option("-o,--out", o->out, "output folder")->capture_default_str();
  cmd->add_option("-j,--threads", o->threads, "worker threads (0 = all cores)")->check(CLI::NonNegativeNumber)->capture_default_str();
  cmd->add_flag("-q,--quiet", o->quiet, "no progress output");
  cmd->callback([o, &exit_code] { exit_code = run_compare(*o); });
}

}  // namespace duet::app
