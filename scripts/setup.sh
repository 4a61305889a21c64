#!/usr/bin/env bash
# Installs, with apt-get, the Debian packages carenav's build, tests, demo and
# benchmarks need. Idempotent; prints nothing when everything is present.
set -euo pipefail

packages=(
  # toolchain
  g++ make cmake
  # MRPT libraries carenav links (no GUI: never mrpt-gui, -nanogui, -hwdrivers, -apps libs)
  libmrpt-config-dev libmrpt-io-dev libmrpt-serialization-dev libmrpt-obs-dev libmrpt-maps-dev
  libmrpt-slam-dev libmrpt-graphs-dev
  # TP-space reactive navigation (PTGs + holonomic methods): the mrpt-ptg local planner (headless)
  libmrpt-nav-dev
  # header-only use of its sparse Levenberg-Marquardt pose-graph optimiser (the library is not linked)
  libmrpt-graphslam-dev
  # MRPT's real datasets (/usr/share/mrpt/datasets): tests and the demo
  mrpt-common
  # MRPT's own command-line apps (rawlog-edit, icp-slam, pf-localization): test and benchmark baselines
  mrpt-apps
  # cpack -G DEB: dependencies of the package from the linked libraries
  dpkg-dev file
  # command line, tests, benchmarks
  libcli11-dev libgtest-dev libbenchmark-dev
  # JSON written and read (summaries, results between processes)
  nlohmann-json3-dev
  # YAML with line numbers (worlds, scenarios, places, ROS map YAML)
  libyaml-cpp-dev
)

# Optional: the ROS 1 part (docs/ros.md; CARENAV_WITH_ROS). Installed when the
# distribution has them; without them the build leaves the ROS part out.
optional=(
  libroscpp-dev librosbag-storage-dev libsensor-msgs-dev libnav-msgs-dev libgeometry-msgs-dev
  libtf2-msgs-dev libstd-msgs-dev libros-rosgraph-msgs-dev libbz2-dev
  # the tests' ROS master
  python3-rosmaster
)

installed() { dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q "install ok installed"; }

missing=()
for p in "${packages[@]}"; do
  installed "$p" || missing+=("$p")
done
missing_optional=()
for p in "${optional[@]}"; do
  installed "$p" || missing_optional+=("$p")
done
[ ${#missing[@]} -eq 0 ] && [ ${#missing_optional[@]} -eq 0 ] && exit 0

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  if ! command -v sudo >/dev/null; then
    if [ ${#missing[@]} -eq 0 ]; then
      echo "setup.sh: not root: optional ROS packages not installed: ${missing_optional[*]}" >&2
      exit 0
    fi
    echo "setup.sh: run as root (or install sudo) to install: ${missing[*]}" >&2
    exit 1
  fi
  SUDO="sudo"
fi
echo "setup.sh: installing ${missing[*]} ${missing_optional[*]}" >&2
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
if [ ${#missing[@]} -gt 0 ]; then
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
# The optional packages one by one: one the distribution lacks leaves the
# ROS part out of the build (a note), never the set-up failing.
for p in "${missing_optional[@]}"; do
  if ! $SUDO apt-get install -y -qq --no-install-recommends "$p" >/dev/null 2>&1; then
    echo "setup.sh: optional package $p not installed: the build leaves the ROS part out" >&2
  fi
done
