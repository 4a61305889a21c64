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

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
[ ${#missing[@]} -eq 0 ] && exit 0

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "setup.sh: run as root (or install sudo) to install: ${missing[*]}" >&2; exit 1; }
  SUDO="sudo"
fi
echo "setup.sh: installing ${missing[*]}" >&2
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
