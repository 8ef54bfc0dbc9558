#!/usr/bin/env bash
# The main job (for now): install + build (scripts/setup.sh), then run duet_bench with repeated,
# randomly interleaved runs and print the ratio table (DESIGN.md §8, bench/RESULTS.md).
#
# Usage: scripts/bench.sh [extra duet_bench args, e.g. --benchmark_filter=VoxelFilter]
# Environment:
#   DUET_BUILD_DIR          build directory                      (default: <repo>/build)
#   DUET_BENCH_OUT          output directory                     (default: <repo>/out)
#   DUET_BENCH_REPETITIONS  repetitions per benchmark            (default: 5)
#   DUET_BENCH_MIN_TIME     minimum seconds per repetition       (default: 0.2)
#   DUET_BENCH_CMAKE_ARGS   extra cmake arguments for setup.sh   (default: none)
#   DUET_BENCH_SKIP_SETUP=1 skip setup.sh (packages + full build); only build the two targets
# Outputs: $DUET_BENCH_OUT/bench.json (Google Benchmark JSON, aggregates only) and
#          $DUET_BENCH_OUT/bench_table.md (the Markdown ratio table, also printed).
# Takes about 5 minutes on 2 cores once built. Timings are only meaningful on an idle machine:
# the load average is printed before and after the run and recorded in the table.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${DUET_BUILD_DIR:-$here/build}"
out="${DUET_BENCH_OUT:-$here/out}"
reps="${DUET_BENCH_REPETITIONS:-5}"
min_time="${DUET_BENCH_MIN_TIME:-0.2}"
jobs="$(nproc 2>/dev/null || echo 2)"

if [ "${DUET_BENCH_SKIP_SETUP:-0}" != 1 ]; then
  # shellcheck disable=SC2086  # word splitting of the extra cmake args is intended
  "$here/scripts/setup.sh" "$build" -DDUET_BUILD_BENCH=ON ${DUET_BENCH_CMAKE_ARGS:-}
elif [ ! -f "$build/CMakeCache.txt" ]; then
  # shellcheck disable=SC2086
  cmake -S "$here" -B "$build" -DCMAKE_BUILD_TYPE=Release -DDUET_BUILD_BENCH=ON ${DUET_BENCH_CMAKE_ARGS:-} >/dev/null
fi
cmake --build "$build" --target duet_bench duet_ratio_table -j "$jobs"

mkdir -p "$out"
echo "bench: load before the run: $(uptime)"
load1="$(cut -d' ' -f1 /proc/loadavg 2>/dev/null || echo 0)"
if awk -v l="$load1" 'BEGIN { exit !(l > 0.5) }'; then
  echo "bench: WARNING: 1-minute load average $load1 > 0.5: other work is running, timings will be noisy" >&2
fi

"$build/duet_bench" \
  --benchmark_repetitions="$reps" \
  --benchmark_min_time="$min_time" \
  --benchmark_enable_random_interleaving=true \
  --benchmark_report_aggregates_only=true \
  --benchmark_out="$out/bench.json" \
  --benchmark_out_format=json \
  "$@"

load_after="$(cut -d' ' -f1-3 /proc/loadavg 2>/dev/null || echo '?')"
echo "bench: load after the run: $(uptime)"
echo
"$build/duet_ratio_table" "$out/bench.json" -o "$out/bench_table.md" \
  --note "command: \`scripts/bench.sh${*:+ $*}\` = \`duet_bench --benchmark_repetitions=$reps --benchmark_min_time=$min_time --benchmark_enable_random_interleaving=true --benchmark_report_aggregates_only=true${*:+ $*}\`" \
  --note "load average after the run: $load_after"
echo
echo "bench: wrote $out/bench.json and $out/bench_table.md"
