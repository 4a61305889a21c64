#!/usr/bin/env bash
# The whole test suite under ASan + UBSan (clang-14): builds build-san/ (the
# same build as scripts/fuzz.sh) and runs ctest there; prints how long each
# step took. Extra arguments go to ctest (e.g. -R Navigator).
#   scripts/sanitize.sh [CTEST ARGS...]          (tests/fuzz/README.md)
set -euo pipefail
cd "$(dirname "$0")/.."
B=build-san
. scripts/san_configure.sh
t0=$(date +%s)
cmake --build $B -j"$(nproc)" >/dev/null
t1=$(date +%s)
echo "sanitize.sh: build $((t1 - t0)) s"
status=0
# alloc_dealloc_mismatch=0: Debian's libsimpleini (under MRPT's
# CConfigFileMemory) frees with free() what it allocated with new[]; that
# is its bug, reported on every profile read, not carenav's.
ASAN_OPTIONS=detect_leaks=1:abort_on_error=0:alloc_dealloc_mismatch=0 \
  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ctest --test-dir $B --output-on-failure -j"$(nproc)" "$@" || status=$?
t2=$(date +%s)
echo "sanitize.sh: tests $((t2 - t1)) s, exit $status"
exit $status
