#!/usr/bin/env bash
# Fails if the given binary links a GUI toolkit or an MRPT library that pulls one in.
set -euo pipefail
bin="$1"
[ -x "$bin" ] || { echo "not an executable: $bin"; exit 1; }
libs=$(ldd "$bin")
if ! grep -q 'libmrpt-obs' <<<"$libs"; then
  echo "ldd output does not list libmrpt-obs: cannot trust it"; echo "$libs"; exit 1
fi
bad=$(grep -oE 'lib(wx_[A-Za-z0-9_.-]+|mrpt-gui[^ ]*|mrpt-nanogui[^ ]*|mrpt-hwdrivers[^ ]*|mrpt-apps[^ ]*|nanogui[^ ]*|glfw[^ ]*)' <<<"$libs" | sort -u || true)
if [ -n "$bad" ]; then
  echo "carenav links GUI libraries:"; echo "$bad"; exit 1
fi
echo "no GUI libraries among $(wc -l <<<"$libs") linked libraries"
