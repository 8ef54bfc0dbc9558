#!/usr/bin/env bash
# Builds the libFuzzer targets (clang, ASan + UBSan + LeakSanitizer; fuzz/README.md) and fuzzes
# each one for a while.
# Usage: scripts/fuzz.sh [seconds per target (default 60)] [target...]
#   FUZZ_RUNS=N  stop each target after N executions instead (the time limit still applies)
#   FUZZ_BUILD=dir  build folder (default build-fuzz)
#   FUZZ_SEED=N  libFuzzer's random seed (CI: 1, so a run is repeatable; default: random)
# Seeds: fuzz/corpus/<target> (checked in: seeds and every regression input), the project's
# profiles and worlds, and the small real files of ../shared/data when present. New inputs that
# reach new code are kept in <build>/corpus/<target> between runs. A crash, a hang (> 1 s per
# input), a leak or a sanitizer report stops the target, saves the input as
# <build>/artifacts/<target>/crash-* (or timeout-*, leak-*) and fails the script: reproduce it
# with `<build>/fuzz/fuzz_<target> <file>`, fix it, and add the file to fuzz/corpus/<target>/
# as a regression input (Fuzz.<target> replays it in every test build).
# The summary (executions, speed, corpus, result per target) goes to <build>/fuzz-summary.txt.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
seconds="${1:-60}"
shift || true
all=(pcd ply map_server world profile rgbd recording capi tum)
targets=("$@")
((${#targets[@]})) || targets=("${all[@]}")
build="${FUZZ_BUILD:-$here/build-fuzz}"
data="$here/../shared/data"

DUET_EXTRA_PKGS="clang-14 libclang-rt-14-dev" CC=clang-14 CXX=clang++-14 DUET_BUILD_TYPE=RelWithDebInfo \
  DUET_BUILD_TARGETS="$(printf 'fuzz_%s ' "${targets[@]}")" \
  "$here/scripts/setup.sh" "$build" -DDUET_FUZZ=ON -DDUET_BUILD_TESTS=OFF -DDUET_BUILD_BENCH=OFF

# Extra seeds from the project and the shared data (read in place, never copied into the repo).
seeds_for() {
  case "$1" in
    pcd) ls "$data"/pcl/*.pcd 2>/dev/null | while read -r f; do [ "$(stat -c %s "$f")" -le 300000 ] && echo "$f"; done ;;
    profile) ls "$here"/profiles/*.yaml ;;
    world) echo "$here/profiles/worlds/lab.yaml" ;;
    tum) ls "$data"/trajectories/*.txt 2>/dev/null ;;
    *) ;;
  esac
}

export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:strict_string_checks=1:allocator_may_return_null=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
summary="$build/fuzz-summary.txt"
printf '%-11s %12s %10s %8s %s\n' target executions "exec/s" corpus result > "$summary"
# One target: fuzz it, write its summary line to <build>/fuzz-<target>.result, return its status.
fuzz_one() {
  local t="$1" corpus="$build/corpus/$1" art="$build/artifacts/$1" extra="$build/seeds/$1" log="$build/fuzz-$1.log"
  mkdir -p "$corpus" "$art" "$extra"
  while read -r f; do [ -n "$f" ] && cp -f "$f" "$extra/"; done < <(seeds_for "$t")
  local runs=()
  [ -n "${FUZZ_RUNS:-}" ] && runs=(-runs="$FUZZ_RUNS")
  [ -n "${FUZZ_SEED:-}" ] && runs+=(-seed="$FUZZ_SEED")
  echo "== fuzz $t: ${seconds} s${FUZZ_RUNS:+ or $FUZZ_RUNS runs}"
  local rc=0
  "$build/fuzz/fuzz_$t" -max_total_time="$seconds" "${runs[@]}" -timeout=1 -rss_limit_mb=4096 -max_len=65536 \
    -print_final_stats=1 -artifact_prefix="$art/" "$corpus" "$here/fuzz/corpus/$t" "$extra" > "$log" 2>&1 || rc=$?
  local execs speed units result
  execs="$(grep -m1 -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo 0)"
  speed="$(grep -m1 -o 'stat::average_exec_per_sec: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo 0)"
  units="$(find "$corpus" -type f | wc -l)"
  if [ "$rc" = 0 ]; then result=ok; else result="FAILED (rc $rc, see $log and $art)"; fi
  printf '%-11s %12s %10s %8s %s\n' "$t" "$execs" "$speed" "$units" "$result" > "$build/fuzz-$t.result"
  if [ "$rc" != 0 ]; then grep -m 20 -E 'ERROR|SUMMARY|Test unit written|==[0-9]+==' "$log" || tail -30 "$log"; fi
  return "$rc"
}

# The targets run FUZZ_JOBS at a time (default: one per core; each libFuzzer process is
# single-threaded), each for the same time as alone.
par="${FUZZ_JOBS:-$(nproc 2>/dev/null || echo 2)}"
status=0
running=0
for t in "${targets[@]}"; do
  rm -f "$build/fuzz-$t.result"
  if ((running >= par)); then
    wait -n || status=1
    running=$((running - 1))
  fi
  fuzz_one "$t" &
  running=$((running + 1))
done
while ((running > 0)); do
  wait -n || status=1
  running=$((running - 1))
done
for t in "${targets[@]}"; do
  if [ -f "$build/fuzz-$t.result" ]; then cat "$build/fuzz-$t.result" >> "$summary"
  else printf '%-11s %s\n' "$t" "FAILED (no result: see $build/fuzz-$t.log)" >> "$summary"; status=1; fi
done
echo "== fuzz summary ($summary)"
cat "$summary"
exit "$status"
