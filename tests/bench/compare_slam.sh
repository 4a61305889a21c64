#!/usr/bin/env bash
# Side by side, in one run: carenav slam against MRPT's own icp-slam and
# rbpf-slam (headless settings) on the same rawlogs with the same settings.
#   - SENA (MRPT's real loop, laser + odometry): wall time; final pose.
#   - Intel and CSAIL (real CARMEN logs, laser only, SLAM-corrected
#     reference trajectory): wall time and ATE/RPE against the reference.
# carenav runs `icp` and `rbpf` with MRPT's own INI files (equivalent
# settings: the same engine and parameters), `icp-graph` with the same [ICP]
# values. Prints a table; numbers go to docs/BENCHMARKS.md.
# Usage: tests/bench/compare_slam.sh [build-dir] [work-dir]
set -euo pipefail
build=$(realpath "${1:-build}")
work=${2:-/tmp/carenav-bench-slam}
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
bin="$build/apps/carenav/carenav"
data=${CARENAV_MRPT_DATASETS:-/usr/share/mrpt/datasets}
cfg=/usr/share/mrpt/config_files
testdata="$root/tests/data"
[ -x "$bin" ] || { echo "build first: $bin not found" >&2; exit 2; }
for t in icp-slam rbpf-slam rawlog-edit; do
  command -v $t >/dev/null || { echo "$t missing: install mrpt-apps" >&2; exit 2; }
done
mkdir -p "$work"
cd "$work"

secs() {  # wall seconds of a command
  local t0 t1
  t0=$(date +%s%N)
  "$@" >/dev/null 2>&1 || { echo "FAILED: $*" >&2; return 1; }
  t1=$(date +%s%N)
  awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.2f", (b - a) / 1e9 }'
}
ratio() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.2f", a / b }'; }

# MRPT app INI made headless: rawlog, output folder, no windows/images.
headless() {  # template rawlog outdir > ini
  sed -e "s|^rawlog_file=.*|rawlog_file=$2|" -e "s|^logOutput_dir=.*|logOutput_dir=$3|" \
      -e 's|^SHOW_PROGRESS_3D_REAL_TIME=.*|SHOW_PROGRESS_3D_REAL_TIME=0|' \
      -e 's|^SHOW_PROGRESS_IN_WINDOW=.*|SHOW_PROGRESS_IN_WINDOW=0|' \
      -e 's|^SAVE_3D_SCENE=.*|SAVE_3D_SCENE=0|' -e 's|^SAVE_MAP_IMAGES=.*|SAVE_MAP_IMAGES=0|' \
      -e 's|^SAVE_POSE_LOG=.*|SAVE_POSE_LOG=0|' -e 's|^LOG_FREQUENCY=.*|LOG_FREQUENCY=100000|' \
      -e 's|^verbosity_level.*|verbosity_level = ERROR|' "$1"
}

# MRPT's log_estimated_path.txt (step x y phi) as TUM, stamped with the times
# of carenav's trajectory of the same scans (both apps take one step per scan).
mrpt_path_to_tum() {  # log_estimated_path.txt carenav.tum > out.tum
  awk 'NR == FNR { if ($1 !~ /^#/) t[n++] = $1; next }
       { if ($1 in t) printf "%s %s %s 0 0 0 %.9f %.9f\n", t[$1], $2, $3, sin($4 / 2), cos($4 / 2) }' \
      "$2" "$1"
}

printf '%-8s %-22s %9s %9s %7s  %s\n' log method "carenav s" "MRPT s" ratio "final pose (carenav | MRPT)"
row() { printf '%-8s %-22s %9s %9s %7s  %s\n' "$@"; }

# ---------------------------------------------------------------- SENA
sena="$data/2006-01ENE-21-SENA_Telecom Faculty_one_loop_only.rawlog"
headless "$cfg/icp-slam/icp-slam_demo_classic.ini" "$sena" "$work/sena_mrpt_icp" > sena_icp.ini
headless "$cfg/rbpf-slam/gridmapping_optimal_sampling.ini" "$sena" "$work/sena_mrpt_rbpf" > sena_rbpf.ini
final_c() { awk '/"final_pose"/ { f = 1 } f && /"x"/ { x = $2 } f && /"y"/ { y = $2 }
                 f && /yaw_deg/ { printf "%.2f %.2f", x, y; exit }' "$1/summary.json" | tr -d ','; }
final_m() { tail -1 "$1/log_estimated_path.txt" | awk '{ printf "%.2f %.2f", $2, $3 }'; }

m=$(secs icp-slam sena_icp.ini)
c=$(secs "$bin" -q slam --profile sena_icp.ini --rawlog "$sena" --method icp --out sena_c_icp)
row SENA "icp (MRPT INI)" "$c" "$m" "$(ratio "$c" "$m")" "$(final_c sena_c_icp) | $(final_m sena_mrpt_icp)"
c=$(secs "$bin" -q slam --profile sena_icp.ini --rawlog "$sena" --method icp-graph --out sena_c_graph)
row SENA "icp-graph vs icp-slam" "$c" "$m" "$(ratio "$c" "$m")" "$(final_c sena_c_graph) | $(final_m sena_mrpt_icp)"
m=$(secs rbpf-slam sena_rbpf.ini)
c=$(secs "$bin" -q slam --profile sena_rbpf.ini --rawlog "$sena" --method rbpf --out sena_c_rbpf)
row SENA "rbpf (MRPT INI)" "$c" "$m" "$(ratio "$c" "$m")" "$(final_c sena_c_rbpf) | $(final_m sena_mrpt_rbpf)"

# ---------------------------------------------------------------- CARMEN, laser only
# The corrected logs' odometry fields repeat the corrected poses: importing
# with --odometry none leaves the scans alone, and the pose fields become the
# reference. ATE after SE(2) alignment (carenav eval). CSAIL stores times with
# 6 significant digits (406 scans share 2 timestamps), so poses are matched by
# scan index there (both apps write one pose per scan, in log order).
ate() {  # est.tum ref.tum by_index -> "rmse"
  local e=$1 r=$2
  if [ "$3" = 1 ]; then
    awk '!/^#/ { $1 = n++; print }' "$1" > "$1.idx"; e="$1.idx"
    awk '!/^#/ { $1 = n++; print }' "$2" > "$2.idx"; r="$2.idx"
  fi
  "$bin" -q eval --est "$e" --ref "$r" --json 2>/dev/null |
    awk '/"ate"/ { f = 1 } f && /"rmse"/ { gsub(",", ""); printf "%.3f", $2; exit }'
}
for log in intel csail; do
  byidx=0; [ $log = csail ] && byidx=1
  "$bin" -q import carmen "$testdata/carmen/$log-corrected.log.gz" --out $log.rawlog --odometry none >/dev/null
  headless "$cfg/icp-slam/icp-slam_demo_classic.ini" "$work/$log.rawlog" "$work/${log}_mrpt_icp" > ${log}_icp.ini
  m=$(secs icp-slam ${log}_icp.ini)
  c=$(secs "$bin" -q slam --profile ${log}_icp.ini --rawlog $log.rawlog --method icp --out ${log}_c_icp)
  mrpt_path_to_tum "${log}_mrpt_icp/log_estimated_path.txt" ${log}_c_icp/trajectory.tum > ${log}_mrpt_icp.tum
  row "$log" "icp (MRPT INI)" "$c" "$m" "$(ratio "$c" "$m")" \
      "ATE rmse carenav $(ate ${log}_c_icp/trajectory.tum $log.tum $byidx) m | MRPT $(ate ${log}_mrpt_icp.tum $log.tum $byidx) m"
  c=$(secs "$bin" -q slam --profile ${log}_icp.ini --rawlog $log.rawlog --method icp-graph --out ${log}_c_graph)
  row "$log" "icp-graph vs icp-slam" "$c" "$m" "$(ratio "$c" "$m")" \
      "ATE rmse carenav $(ate ${log}_c_graph/trajectory.tum $log.tum $byidx) m | MRPT $(ate ${log}_mrpt_icp.tum $log.tum $byidx) m"
done

# ---------------------------------------------------------------- simulated loop
# `carenav simulate`: the INTERBOT's laser alone (its Kinect section dropped
# from the resolved profile) at 5 Hz, driven once round the SENA building's
# loop on the real SENA map, with the simulator's odometry noise (6.5 m and
# 32 deg off at the end). Reference: the exact ground truth. MRPT's icp-slam
# takes one step per rawlog entry (odometry, laser, ...): its pose after the
# k-th laser (step 2k + 1) is stamped with the time of carenav's k-th scan.
"$bin" profile show "$root/ini/interbot.ini" 2>/dev/null |
  awk '/^\[/ { skip = ($0 == "[sensor.kinect]") } !skip' > sim_laser.ini
"$bin" -q simulate --profile sim_laser.ini --world "$root/maps/worlds/sena.yaml" \
  --path "-8,4.5 3,4.5 3,-16 -8,-16 -8,4.5" --start -8,4.5,0 --set sensor.laser.rate_hz=5 \
  --seed 3 --out simloop.rawlog
headless "$cfg/icp-slam/icp-slam_demo_classic.ini" "$work/simloop.rawlog" "$work/simloop_mrpt_icp" > simloop_icp.ini
m=$(secs icp-slam simloop_icp.ini)
c=$(secs "$bin" -q slam --profile simloop_icp.ini --rawlog simloop.rawlog --method icp --out simloop_c_icp)
awk 'NR == FNR { if ($1 !~ /^#/) t[n++] = $1; next }
     ($1 % 2 == 1) { k = ($1 - 1) / 2; if (k in t) printf "%s %s %s 0 0 0 %.9f %.9f\n", t[k], $2, $3, sin($4 / 2), cos($4 / 2) }' \
  simloop_c_icp/trajectory.tum simloop_mrpt_icp/log_estimated_path.txt > simloop_mrpt_icp.tum
row "sim loop" "icp (MRPT INI)" "$c" "$m" "$(ratio "$c" "$m")" \
    "ATE rmse carenav $(ate simloop_c_icp/trajectory.tum simloop.gt.tum 0) m | MRPT $(ate simloop_mrpt_icp.tum simloop.gt.tum 0) m"
c=$(secs "$bin" -q slam --profile simloop_icp.ini --rawlog simloop.rawlog --method icp-graph --out simloop_c_graph)
row "sim loop" "icp-graph vs icp-slam" "$c" "$m" "$(ratio "$c" "$m")" \
    "ATE rmse carenav $(ate simloop_c_graph/trajectory.tum simloop.gt.tum 0) m | MRPT $(ate simloop_mrpt_icp.tum simloop.gt.tum 0) m"
