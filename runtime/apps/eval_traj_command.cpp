// `duet eval-traj EST GT`: the accuracy of a trajectory against ground truth, both TUM files
// (runtime/io/trajectory_io.hpp): ATE after rigid alignment (Horn / Umeyama) and RPE per frame,
// per second or per metre (kernels/trajectory_eval.hpp), with the TUM tools' association.
// Prints a table, or JSON with --json.
#include "commands.hpp"

#include <duet/kernels/trajectory_eval.hpp>
#include <duet/runtime/io/trajectory_io.hpp>

#include <cstdio>
#include <iostream>

namespace duet::app {
namespace {

struct EvalOptions {
  std::string estimate, ground_truth;
  double max_dt = 0.02, offset = 0.0, delta = 1.0;
  std::string unit = "f";
  bool no_align = false, scale = false, json = false;
};

nlohmann::json stats_json(const ErrorStats& s) {
  return {{"count", s.count}, {"rmse", s.rmse}, {"mean", s.mean}, {"median", s.median},
          {"std", s.std},     {"min", s.min},   {"max", s.max}};
}

int eval_traj(const EvalOptions& o) {
  const auto est = read_tum_trajectory(o.estimate);
  const auto gt = read_tum_trajectory(o.ground_truth);
  AteSettings as;
  as.association = {o.max_dt, o.offset};
  as.align = !o.no_align;
  as.with_scale = o.scale;
  const AteResult ate = absolute_trajectory_error(est, gt, as);
  RpeSettings rs;
  rs.association = as.association;
  rs.delta = o.delta;
  rs.unit = o.unit == "f" ? RpeUnit::kFrames : o.unit == "s" ? RpeUnit::kSeconds : RpeUnit::kMetres;
  const RpeResult rpe = relative_pose_error(est, gt, rs);
  if (o.json) {
    nlohmann::json j;
    j["estimate"] = {{"file", o.estimate}, {"poses", est.size()}};
    j["ground_truth"] = {{"file", o.ground_truth}, {"poses", gt.size()}};
    j["association"] = {{"max_dt_s", o.max_dt}, {"offset_s", o.offset}, {"pairs", ate.pairs.size()}};
    j["ate_m"] = stats_json(ate.translation);
    j["ate_alignment"] = {{"aligned", as.align}, {"scale", ate.scale}};
    j["rpe"] = {{"delta", o.delta}, {"unit", o.unit}, {"pairs", rpe.pairs},
                {"translation_m", stats_json(rpe.translation)}, {"rotation_deg", stats_json(rpe.rotation)}};
    std::cout << j.dump(2) << "\n";
    return 0;
  }
  std::printf("estimate      %s (%zu poses)\nground truth  %s (%zu poses)\nassociated    %zu pairs (max dt %.3f s, offset %.3f s)\n",
              o.estimate.c_str(), est.size(), o.ground_truth.c_str(), gt.size(), ate.pairs.size(), o.max_dt, o.offset);
  auto row = [](const char* name, const ErrorStats& s, const char* unit) {
    std::printf("%-22s rmse %.6f  mean %.6f  median %.6f  std %.6f  min %.6f  max %.6f %s\n", name, s.rmse, s.mean, s.median, s.std,
                s.min, s.max, unit);
  };
  row(as.align ? (o.scale ? "ATE (Sim3-aligned)" : "ATE (SE3-aligned)") : "ATE (not aligned)", ate.translation, "m");
  if (o.scale) std::printf("%-22s %.6f\n", "scale", ate.scale);
  char name[64];
  std::snprintf(name, sizeof name, "RPE trans (%g %s)", o.delta, o.unit.c_str());
  row(name, rpe.translation, "m");
  std::snprintf(name, sizeof name, "RPE rot (%g %s)", o.delta, o.unit.c_str());
  row(name, rpe.rotation, "deg");
  std::printf("%-22s %zu\n", "RPE pairs", rpe.pairs);
  return 0;
}

}  // namespace

void add_eval_traj_command(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<EvalOptions>();
  CLI::App* cmd = app.add_subcommand("eval-traj", "Trajectory accuracy of a TUM-format estimate against ground truth: ATE and RPE");
  cmd->add_option("estimate", o->estimate, "Estimated trajectory (TUM: t tx ty tz qx qy qz qw)")->required()->check(CLI::ExistingFile);
  cmd->add_option("ground_truth", o->ground_truth, "Ground-truth trajectory (TUM)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--max-dt", o->max_dt, "Associate stamps closer than this [s]")->check(CLI::PositiveNumber)->capture_default_str();
  cmd->add_option("--offset", o->offset, "Added to the estimate's stamps [s]")->capture_default_str();
  cmd->add_flag("--no-align", o->no_align, "Compare as given (no rigid alignment)");
  cmd->add_flag("--scale", o->scale, "Align with scale (Sim3; monocular estimates)");
  cmd->add_option("--delta", o->delta, "RPE step")->check(CLI::PositiveNumber)->capture_default_str();
  cmd->add_option("--delta-unit", o->unit, "RPE step unit: f (frames), s (seconds), m (metres along the ground truth)")
      ->check(CLI::IsMember({"f", "s", "m"}))
      ->capture_default_str();
  cmd->add_flag("--json", o->json, "Print JSON instead of the table");
  cmd->callback([o, &exit_code] { exit_code = eval_traj(*o); });
}

}  // namespace duet::app
