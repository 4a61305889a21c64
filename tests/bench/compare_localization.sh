#!/usr/bin/env bash
# carenav localize against MRPT's own pf-localization (headless) on MRPT's
# localization_demo (real laser + odometry, 37 scans), with the same particle
# settings: KLD sample size 150..40000 (bins 0.10 m / 10 deg, delta = epsilon
# = 0.01), 40000 initial particles, likelihood field (sigma 0.20 m, every 20th
# beam). MRPT's app spreads its particles over x in [-10, 10], y in [-15, -5]
# (its INI); carenav's --global spreads them over the whole 72 x 28 m map.
# Reports wall time per process (best of N runs, map loading included) and
# their ratio, and the distance between the final poses.
# Usage: tests/bench/compare_localization.sh [build-dir] [work-dir] [runs]
set -euo pipefail
build=$(realpath "${1:-build}")
work=${2:-/tmp/carenav-bench-localization}
runs=${3:-3}
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
bin="$build/apps/carenav/carenav"
data=${CARENAV_MRPT_DATASETS:-/usr/share/mrpt/datasets}
ini_src=/usr/share/mrpt/config_files/pf-localization/localization_demo.ini
[ -x "$bin" ] || { echo "build first: $bin not found" >&2; exit 2; }
command -v pf-localization >/dev/null || { echo "pf-localization missing: install mrpt-apps" >&2; exit 2; }
mkdir -p "$work"
cd "$work"

# MRPT's INI made headless: absolute data paths, no 3D window, no log folder.
sed -e "s|^map_file=.*|map_file=$data/localization_demo.simplemap.gz|" \
    -e "s|^rawlog_file=.*|rawlog_file=$data/localization_demo.rawlog|" \
    -e 's|^logOutput_dir=.*|logOutput_dir=|' \
    -e 's|^SHOW_PROGRESS_3D_REAL_TIME.*|SHOW_PROGRESS_3D_REAL_TIME=false|' \
    -e 's|^3DSceneFrequency=.*|3DSceneFrequency=-1|' "$ini_src" > mrpt_headless.ini

now() { date +%s%N; }
best_mrpt=999999; best_carenav=999999
for i in $(seq "$runs"); do
  t0=$(now); pf-localization mrpt_headless.ini > mrpt.log 2>&1; t1=$(now)
  ms=$(( (t1 - t0) / 1000000 )); [ "$ms" -lt "$best_mrpt" ] && best_mrpt=$ms
  t0=$(now)
  "$bin" -q localize --profile "$root/ini/defaults.ini" --map "$data/localization_demo.simplemap.gz" \
    --rawlog "$data/localization_demo.rawlog" --global --out carenav_out
  t1=$(now)
  ms=$(( (t1 - t0) / 1000000 )); [ "$ms" -lt "$best_carenav" ] && best_carenav=$ms
done

# MRPT: the last "PDF estimation: (x,y,phideg)" line.
read -r mx my myaw < <(grep -o 'PDF estimation: ([^)]*)' mrpt.log | tail -1 |
  sed -e 's/.*(//' -e 's/deg)//' -e 's/,/ /g')
# carenav: final_pose of summary.json.
read -r cx cy cyaw < <(python3 -c "
import json; f = json.load(open('carenav_out/summary.json'))['final_pose']
print(f['x'], f['y'], f['yaw_deg'])")
conv=$(python3 -c "import json; print(json.load(open('carenav_out/summary.json'))['convergence_time'])")

printf '%-28s %12s %12s\n' "" "carenav" "pf-localization"
printf '%-28s %12s %12s\n' "wall time, best of $runs (ms)" "$best_carenav" "$best_mrpt"
printf '%-28s %12s %12s\n' "final x (m)" "$(printf %.3f "$cx")" "$mx"
printf '%-28s %12s %12s\n' "final y (m)" "$(printf %.3f "$cy")" "$my"
printf '%-28s %12s %12s\n' "final yaw (deg)" "$(printf %.2f "$cyaw")" "$myaw"
awk -v a="$best_carenav" -v b="$best_mrpt" 'BEGIN { printf "time ratio carenav / MRPT: %.2f\n", a / b }'
awk -v x1="$cx" -v y1="$cy" -v a1="$cyaw" -v x2="$mx" -v y2="$my" -v a2="$myaw" \
  'BEGIN { d = a1 - a2; while (d > 180) d -= 360; while (d < -180) d += 360;
           printf "final pose difference: %.3f m, %.2f deg\n", sqrt((x1-x2)^2 + (y1-y2)^2), (d < 0 ? -d : d) }'
echo "carenav convergence time (global start over the whole map): $conv s"
