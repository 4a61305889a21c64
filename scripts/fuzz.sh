#!/usr/bin/env bash
# Builds carenav's libFuzzer harnesses (clang, ASan + UBSan) and runs each for
# SECONDS seconds (default 60) on a seed corpus made from the repository's own
# files. Findings (crash-*, leak-*, timeout-*, oom-*) are left in
# build-san/findings/<harness>/; the summary line of each run is printed.
#   scripts/fuzz.sh [SECONDS] [HARNESS...]     (tests/fuzz/README.md)
set -euo pipefail
cd "$(dirname "$0")/.."
secs=${1:-60}
shift || true
all=(profile places world scenario rosmap image tum cloud carmen rawlog bridge)
[ $# -gt 0 ] && harnesses=("$@") || harnesses=("${all[@]}")
B=build-san  # shared with scripts/sanitize.sh (the test suite under ASan + UBSan)
. scripts/san_configure.sh
# FUZZ_NO_BUILD=1: run what build-san holds (e.g. while it builds the tests).
[ -n "${FUZZ_NO_BUILD:-}" ] ||
  cmake --build $B -j"$(nproc)" --target carenav $(printf 'fuzz_%s ' "${harnesses[@]}") >/dev/null

corpus() {  # corpus NAME: the seed inputs of one harness, from the repository
  local d=$B/corpus/$1
  rm -rf "$d"; mkdir -p "$d"
  case $1 in
    profile) cp ini/*.ini "$d" ;;
    places) cp maps/*.places.yaml "$d" ;;
    world) for f in maps/worlds/*.yaml maps/worlds/*/*.yaml; do cp "$f" "$d/$(echo "$f" | tr / _)"; done ;;
    scenario) cp maps/scenarios/*.yaml "$d" ;;
    rosmap) printf 'image: map.pgm\nresolution: 0.05\norigin: [-1.0, -2.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\nmode: trinary\n' >"$d/map.yaml" ;;
    image) for f in maps/worlds/*.png; do { printf '\001'; cat "$f"; } >"$d/$(basename "$f")"; done
           { printf '\000P5\n4 3\n255\n'; head -c 12 /dev/zero; } >"$d/p5.pgm"
           printf '\000P2\n2 2\n255\n0 255\n255 0\n' >"$d/p2.pgm" ;;
    tum) awk 'BEGIN{for(k=0;k<30;k++) printf "%.2f %.3f %.3f 0 0 0 %.6f %.6f\n", 100+0.1*k, 0.05*k, 0.01*k, sin(0.005*k), cos(0.005*k)}' >"$d/a.tum" ;;
    cloud) { printf '\000# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 4\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 4\nDATA ascii\n1 0 0\n1 0.1 0\n1 0.2 0.5\n2 0 0\n'; } >"$d/a.pcd"
           { printf '\001ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 0 0\n1 0.1 0\n2 0 0.3\n'; } >"$d/a.ply" ;;
    carmen) for f in tests/data/carmen/*.log.gz; do  # head closes the pipe early: not an error
              { zcat "$f" | grep -v '^#' | head -n 40 >"$d/$(basename "$f" .gz)"; } || true; done ;;
    rawlog) { zcat tests/data/carmen/intel-corrected.log.gz | grep -v '^#' | head -n 30 >"$B/seed.log"; } || true
            $B/apps/carenav/carenav -q import carmen "$B/seed.log" --out "$d/seed.rawlog" --compression 1 --no-tum >/dev/null ;;
    bridge) printf 'odom 1.5 0.1 0.2 0.3 0.25 0.1\nscan 1.5 front 4 1.0 2.0 inf 3.5\nintent 1.6 0.3 -0.2\nbye\n' >"$d/lines.txt" ;;
  esac
}

for h in "${harnesses[@]}"; do
  corpus "$h"
  mkdir -p $B/findings/$h $B/work/$h
  ( cd $B/work/$h && ASAN_OPTIONS=detect_leaks=1:allocator_may_return_null=1 \
      ../../tests/fuzz/fuzz_$h ../../corpus/$h -max_total_time="$secs" -rss_limit_mb=2048 \
      -max_len=65536 -timeout=20 -artifact_prefix=../../findings/$h/ -print_final_stats=1 \
      >log.txt 2>&1 ) || true
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' $B/work/$h/log.txt | grep -o '[0-9]*$' || echo 0)
  rate=$(grep -o 'stat::average_exec_per_sec: *[0-9]*' $B/work/$h/log.txt | grep -o '[0-9]*$' || echo 0)
  cov=$(grep -o 'cov: [0-9]*' $B/work/$h/log.txt | tail -1 | grep -o '[0-9]*' || echo 0)
  found=$(ls $B/findings/$h | wc -l)
  printf '%-9s %8s execs %6s/s  coverage %5s  findings %s\n' "$h" "$execs" "$rate" "$cov" "$found"
done
