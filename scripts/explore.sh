#!/usr/bin/env bash
# The main job: install + build (scripts/setup.sh), then `duet explore` - the paper's experiment
# in the simulator: the robot with both RGB-D sensors (profile dual) explores the replica of the
# paper's lab (world lab) on its own; maps, trajectory, time-area curve and summary go to out/.
#
# Usage: scripts/explore.sh [extra `duet explore` options, e.g. --seed 3 --profile single]
# Environment:
#   DUET_BUILD_DIR   build directory   (default: <repo>/build)
#   DUET_OUT         output directory  (default: <repo>/out)
#   DUET_SKIP_SETUP=1  skip setup.sh (packages + full build); only build the `duet` program
# Takes about a minute on 2 cores once built (10 simulated minutes at >10x real time).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${DUET_BUILD_DIR:-$here/build}"
out="${DUET_OUT:-$here/out}"
if [ "${DUET_SKIP_SETUP:-0}" != 1 ]; then
  "$here/scripts/setup.sh" "$build"
else
  cmake --build "$build" -j "$(nproc 2>/dev/null || echo 2)" --target duet_cli
fi
"$build/duet" explore --world lab --profile dual --out "$out" "$@"
echo "explore: results in $out/ (summary.json, grid.png, curve.png, cloud.pcd, ...)"
