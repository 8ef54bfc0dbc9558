#!/usr/bin/env bash
# Installs the Debian packages duet needs and configures + builds it.
# Usage: scripts/setup.sh [build-dir] [extra cmake args...]
#   As root: installs what is missing (apt-get update once, then install).
#   Not root: prints the apt-get command to run and stops if anything is missing.
#   DUET_SETUP_PACKAGES_ONLY=1: the packages only (no configure, no build).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${1:-$here/build}"
shift || true

pkgs=(build-essential cmake ninja-build pkg-config
      libeigen3-dev libembree-dev libtbb-dev libopencv-dev libpcl-dev
      libbenchmark-dev libgtest-dev libgmock-dev libyaml-cpp-dev libspdlog-dev libcli11-dev
      liblzf-dev nlohmann-json3-dev libpng-dev python3 python3-numpy python3-pytest
      libopen3d-dev)  # Open3D: the odometry benchmark's peer only
# ROS 1 as Debian packages it (issue 22: the node, the simulator bridge, bag replay; roscore and
# rosbag for their tests). rosbag's headers include pluginlib's, which need rcpputils' and
# rcutils'. DUET_NO_ROS=1 leaves them out (cmake then builds no ROS part).
if [ "${DUET_NO_ROS:-0}" != 1 ]; then
  pkgs+=(libroscpp-dev librosbag-dev libtf2-ros-dev libmessage-filters-dev libsensor-msgs-dev libnav-msgs-dev
         libgeometry-msgs-dev libvisualization-msgs-dev libstd-srvs-dev librcpputils-dev librcutils-dev
         ros-core python3-rosbag python3-std-srvs rosbash
         python3-geometry-msgs python3-nav-msgs python3-sensor-msgs python3-visualization-msgs)
fi
# DUET_EXTRA_PKGS: more packages a caller needs (scripts/fuzz.sh: clang and libFuzzer).
read -r -a extra_pkgs <<< "${DUET_EXTRA_PKGS:-}"
pkgs+=("${extra_pkgs[@]}")

missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  if [ "$(id -u)" = 0 ]; then
    echo "setup: installing ${missing[*]}"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq --no-install-recommends -o DPkg::Lock::Timeout=600 "${missing[@]}"
  else
    echo "setup: missing packages; run as root:" >&2
    echo "  apt-get update && apt-get install -y --no-install-recommends ${missing[*]}" >&2
    exit 1
  fi
fi

[ "${DUET_SETUP_PACKAGES_ONLY:-0}" = 1 ] && exit 0

jobs="$(nproc 2>/dev/null || echo 2)"
# Ninja for a new build folder (one build graph over all targets: both cores stay busy across
# target boundaries); a folder configured before keeps its generator (CMake cannot switch one).
generator=()
[ -f "$build/CMakeCache.txt" ] || generator=(-G Ninja)
cmake -S "$here" -B "$build" "${generator[@]}" -DCMAKE_BUILD_TYPE="${DUET_BUILD_TYPE:-Release}" "$@" >/dev/null
# DUET_BUILD_TARGETS: build only these targets (space-separated; default: all).
if [ -n "${DUET_BUILD_TARGETS:-}" ]; then
  for t in $DUET_BUILD_TARGETS; do cmake --build "$build" -j "$jobs" --target "$t"; done
else
  cmake --build "$build" -j "$jobs"
fi
