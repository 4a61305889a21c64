#!/usr/bin/env bash
# Side by side, in one run: `carenav rawlog info` against MRPT's
# `rawlog-edit --info` on the same rawlogs. Prints mean wall time per run and
# the ratio (carenav / MRPT; below 1 means carenav is faster).
# Usage: tests/bench/compare_rawlog_info.sh [build-dir] [runs]
set -euo pipefail
build=${1:-build}
runs=${2:-20}
bin="$build/apps/carenav/carenav"
data=${CARENAV_MRPT_DATASETS:-/usr/share/mrpt/datasets}
[ -x "$bin" ] || { echo "build first: $bin not found" >&2; exit 2; }
command -v rawlog-edit >/dev/null || { echo "rawlog-edit missing: install mrpt-apps" >&2; exit 2; }

mean_ms() {  # runs the command $runs times, prints the mean wall time in ms
  local t0 t1
  t0=$(date +%s%N)
  for ((i = 0; i < runs; i++)); do "$@" >/dev/null 2>&1; done
  t1=$(date +%s%N)
  awk -v a="$t0" -v b="$t1" -v n="$runs" 'BEGIN { printf "%.2f", (b - a) / 1e6 / n }'
}

printf '%-58s %12s %12s %8s\n' rawlog "carenav ms" "MRPT ms" ratio
for f in "2006-01ENE-21-SENA_Telecom Faculty_one_loop_only.rawlog" tests_rgbd.rawlog \
         kf-slam_6D_demo.rawlog uwb_ro-localization_demo.rawlog test_rtk_path.rawlog; do
  ours=$(mean_ms "$bin" -q rawlog info "$data/$f")
  theirs=$(mean_ms rawlog-edit --info -i "$data/$f")
  printf '%-58s %12s %12s %8s\n' "$f" "$ours" "$theirs" "$(awk -v a="$ours" -v b="$theirs" 'BEGIN { printf "%.2f", a / b }')"
done
