#!/usr/bin/env bash
# carenav localize against MRPT's own pf-localization (headless) on walks
# simulated by `carenav simulate`, scored against the simulator's exact ground
# truth with `carenav eval --no-align` (both estimates are in the map frame).
# Both filters start GLOBALLY (uniform particles over the map's free cells,
# any heading) with the same particle settings: 20000 initial particles, KLD
# 150..20000 (bins 0.10 m / 10 deg, delta = epsilon = 0.01), likelihood field
# sigma 0.20 m, max distance 0.30 m, z_hit 0.95, every 60th beam, an update at
# every scan. Differences that stay: MRPT's app spreads its particles over the
# map's bounding box (init_PDF_mode 0: free cells inside it), reads the map at
# the INI's 0.06 m cells, models odometry with its DummyOdometryParams, and
# has no recovery; carenav keeps its augmented-MCL recovery.
# Robot: a lidar-only profile with INTERBOT's Hokuyo UTM-30LX (1081 beams,
# 270 deg) at 10 Hz (not 40 Hz: MRPT's app updates at every scan).
# "global ok" = the final estimate within 0.3 m of the final truth.
# Usage: tests/bench/compare_localization_sim.sh [build-dir] [work-dir]
set -euo pipefail
build=$(realpath "${1:-build}")
work=${2:-/tmp/carenav-bench-localization-sim}
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
bin="$build/apps/carenav/carenav"
ini_src=/usr/share/mrpt/config_files/pf-localization/localization_demo.ini
[ -x "$bin" ] || { echo "build first: $bin not found" >&2; exit 2; }
command -v pf-localization >/dev/null || { echo "pf-localization missing: install mrpt-apps" >&2; exit 2; }
mkdir -p "$work"
cd "$work"

cat > laser.ini <<INI
[profile]
name = bench-laser
base = $root/ini/defaults.ini

[sensor.laser]
type = lidar2d
x = 0.15
z = 0.19
rate_hz = 10
fov = 270
beams = 1081
range_min = 0.1
range_max = 30
noise_std = 0.03
INI
# The apartment's bare PNG as a map_server YAML, and both maps as MRPT gridmaps.
printf 'image: %s\nresolution: 0.05\norigin: [0.0, 0.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n' \
  "$root/maps/worlds/apartment.png" > apartment.yaml
"$bin" -q map convert apartment.yaml apartment.gridmap > /dev/null
"$bin" -q map convert "$root/maps/sena.gridmap.gz" sena.gridmap > /dev/null

# name world map seed path
# Eight walks: four in the apartment (rooms, corridor, a short one, past the
# table) and one along each of SENA's four corridors, whose long, similar
# stretches are look-alikes of one another.
runs=(
  "apt_living  apartment apartment 2 1,1 6,1 6,2.5 1,2.5"
  "apt_corr    apartment apartment 5 9,1 9,3.5 4,3.5 4,6.5"
  "apt_short   apartment apartment 3 6,2.5 1.5,2.5 1.5,1"
  "apt_table   apartment apartment 7 1,7 5,7 5,4.5"
  "sena_north  sena      sena      1 -8,4.5 3,4.5"
  "sena_east   sena      sena      4 3,1 3,-12"
  "sena_west   sena      sena      6 -8.3,0 -8.3,-12"
  "sena_south  sena      sena      8 -8,-16 3,-16"
)
sets=(--set localization.global_particles=20000 --set localization.particles_max=20000
      --set localization.particles_min=150 --set localization.lf_decimation=60
      --set localization.update_min_d=0 --set localization.update_min_a=0)

now() { date +%s%N; }
ate() { "$bin" eval --est "$1" --ref "$2" --no-align --json |
  python3 -c "import json,sys; print('%.3f' % json.load(sys.stdin)['ate']['translation_m']['rmse'])"; }
final_err() { python3 - "$1" "$2" <<'PY'
import sys, math
def last(p):
    rows = [l.split() for l in open(p) if l.strip() and not l.startswith('#')]
    return float(rows[-1][1]), float(rows[-1][2])
(a, b), (c, d) = last(sys.argv[1]), last(sys.argv[2])
print('%.3f' % math.hypot(a - c, b - d))
PY
}

printf '%-11s %6s | %8s %8s %8s %6s | %8s %8s %8s %6s | %6s\n' run scans \
  "c_ms" "c_ate" "c_final" "c_ok" "m_ms" "m_ate" "m_final" "m_ok" ratio
all_c=yes; all_m=yes; n_c=0; n_m=0
for spec in "${runs[@]}"; do
  read -r name world map seed path <<< "$spec"
  world_yaml="$root/maps/worlds/$world.yaml"
  "$bin" -q simulate --profile laser.ini --world "$world_yaml" --path "$path" --seed "$seed" \
    --out "$name.rawlog"
  gt="$name.gt.tum"
  scans=$(grep -vc '^#' "$gt")
  read -r x0 x1 y0 y1 < <("$bin" map info "$map.gridmap" | sed -n 's/.*bounds: x \[\(.*\), \(.*\)\], y \[\(.*\), \(.*\)\] m.*/\1 \2 \3 \4/p')

  t0=$(now)
  "$bin" -q localize --profile laser.ini --map "$map.gridmap" --rawlog "$name.rawlog" --global \
    "${sets[@]}" --out "c_$name"
  c_ms=$(( ($(now) - t0) / 1000000 ))

  sed -e "s|^map_file=.*|map_file=$work/$map.gridmap|" \
      -e "s|^rawlog_file=.*|rawlog_file=$work/$name.rawlog|" \
      -e 's|^logOutput_dir=.*|logOutput_dir=|' \
      -e 's|^SHOW_PROGRESS_3D_REAL_TIME.*|SHOW_PROGRESS_3D_REAL_TIME=false|' \
      -e 's|^3DSceneFrequency=.*|3DSceneFrequency=-1|' \
      -e 's|^particles_count=.*|particles_count=20000|' \
      -e 's|^KLD_maxSampleSize=.*|KLD_maxSampleSize=20000|' \
      -e 's|^LF_decimation=.*|LF_decimation=60|' \
      -e "s|^init_PDF_min_x=.*|init_PDF_min_x=$x0|" -e "s|^init_PDF_max_x=.*|init_PDF_max_x=$x1|" \
      -e "s|^init_PDF_min_y=.*|init_PDF_min_y=$y0|" -e "s|^init_PDF_max_y=.*|init_PDF_max_y=$y1|" \
      "$ini_src" > "m_$name.ini"
  t0=$(now)
  pf-localization "m_$name.ini" > "m_$name.log" 2>&1
  m_ms=$(( ($(now) - t0) / 1000000 ))
  # One "PDF estimation" per scan (the rawlog has only the laser): stamp the
  # k-th with the k-th ground-truth time.
  python3 - "m_$name.log" "$gt" "m_$name.tum" <<'PY'
import math, re, sys
est = re.findall(r'PDF estimation: \((-?[0-9.]+),(-?[0-9.]+),(-?[0-9.]+)deg\)', open(sys.argv[1]).read())
ts = [l.split()[0] for l in open(sys.argv[2]) if l.strip() and not l.startswith('#')]
if len(est) != len(ts):
    sys.exit('pf-localization gave %d estimates for %d scans' % (len(est), len(ts)))
with open(sys.argv[3], 'w') as f:
    for t, (x, y, a) in zip(ts, est):
        h = math.radians(float(a)) / 2
        f.write('%s %s %s 0 0 0 %.9f %.9f\n' % (t, x, y, math.sin(h), math.cos(h)))
PY
  c_ate=$(ate "c_$name/track.tum" "$gt"); m_ate=$(ate "m_$name.tum" "$gt")
  c_fin=$(final_err "c_$name/track.tum" "$gt"); m_fin=$(final_err "m_$name.tum" "$gt")
  c_ok=$(awk -v e="$c_fin" 'BEGIN { print (e < 0.3 ? "yes" : "no") }')
  m_ok=$(awk -v e="$m_fin" 'BEGIN { print (e < 0.3 ? "yes" : "no") }')
  if [ "$c_ok" = yes ]; then n_c=$((n_c + 1)); else all_c=no; fi
  if [ "$m_ok" = yes ]; then n_m=$((n_m + 1)); else all_m=no; fi
  printf '%-11s %6s | %8s %8s %8s %6s | %8s %8s %8s %6s | %6s\n' "$name" "$scans" \
    "$c_ms" "$c_ate" "$c_fin" "$c_ok" "$m_ms" "$m_ate" "$m_fin" "$m_ok" \
    "$(awk -v a="$c_ms" -v b="$m_ms" 'BEGIN { printf "%.2f", a / b }')"
done
echo "c_ = carenav localize, m_ = MRPT pf-localization; ms = wall time of the process (map loading"
echo "included); ate = ATE RMSE (m, not aligned) over the whole run, global start included;"
echo "final = distance of the final estimate from the final truth (m); ratio = c_ms / m_ms."
echo "global localisation succeeded on: carenav $n_c of ${#runs[@]} runs, pf-localization $n_m of ${#runs[@]}"
echo "global localisation succeeded on every run: carenav $all_c, pf-localization $all_m"
