# Sourced by scripts/fuzz.sh and scripts/sanitize.sh: configures $B (clang-14,
# CARENAV_FUZZ: ASan + UBSan on every library, the binary and the tests, and
# libFuzzer's coverage instrumentation) unless it is configured already.
command -v clang++-14 >/dev/null || {
  echo "$0: needs clang++-14 and libclang-rt-14-dev (apt-get install clang-14 libclang-rt-14-dev)" >&2
  exit 1
}
if [ ! -f "$B/CMakeCache.txt" ]; then
  launcher=()
  command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  cmake -S . -B "$B" -DCMAKE_CXX_COMPILER=clang++-14 -DCARENAV_FUZZ=ON -DCARENAV_BUILD_BENCH=OFF \
    -DCMAKE_BUILD_TYPE=RelWithDebInfo "${launcher[@]}" >/dev/null
fi
