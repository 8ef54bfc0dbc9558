#!/usr/bin/env bash
# Today's front end (wheels + gyro + scan matching) against the same with visual odometry fused
# (localization.visual_odometry.enabled), per seed: ATE RMSE and max against the simulator's
# truth (duet eval-traj --no-align: the map frame starts at the true start pose), coverage,
# collisions. Issue 21's in-the-loop target (bench/RESULTS.md).
# Usage: bench/vision_seeds.sh WORLD SECONDS FIRST_SEED LAST_SEED OUT [extra duet explore args...]
#   bench/vision_seeds.sh lab 900 1 10 out/vis-lab
#   bench/vision_seeds.sh ../shared/data/maps/willow-2010-02-18-0.10.yaml 1200 1 10 out/vis-willow
#   MODES=vision bench/vision_seeds.sh lab 900 1 5 out/v --set localization.visual_odometry.fuse_every_set=true
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
duet="${DUET:-$here/build/duet}"
world="$1" seconds="$2" first="$3" last="$4" out="$5"
shift 5
mkdir -p "$out"
printf '| seed | mode | ATE RMSE [cm] | max [cm] | coverage [%%] | collisions | wall [s] |\n|---|---|---|---|---|---|---|\n'
for ((s = first; s <= last; s++)); do
  for mode in ${MODES:-today vision}; do
    dir="$out/$mode-$s"
    args=(explore -w "$world" -s "$s" -t "$seconds" -q -j 1 -o "$dir" "$@")
    [ "$mode" = vision ] && args+=(--set localization.visual_odometry.enabled=true)
    t0=$(date +%s.%N)
    "$duet" "${args[@]}" > "$dir.log" 2>&1 || { echo "| $s | $mode | failed: see $dir.log |"; continue; }
    t1=$(date +%s.%N)
    "$duet" eval-traj --no-align --json "$dir/trajectory.tum" "$dir/trajectory_true.tum" > "$dir/eval.json"
    /usr/bin/python3 - "$dir" "$s" "$mode" "$t0" "$t1" <<'PY'
import json, sys
d, s, mode, t0, t1 = sys.argv[1], sys.argv[2], sys.argv[3], float(sys.argv[4]), float(sys.argv[5])
e = json.load(open(d + "/eval.json")); j = json.load(open(d + "/summary.json"))
print("| %s | %s | %.2f | %.1f | %.2f | %d | %.0f |" % (s, mode, 100 * e["ate_m"]["rmse"], 100 * e["ate_m"]["max"],
      100 * j["coverage"], j["collisions"], t1 - t0))
PY
  done
done
