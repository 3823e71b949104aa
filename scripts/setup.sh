#!/usr/bin/env bash
# Sets up a fresh Debian machine for MANTA-RAY: system packages, the Python package, native and fuzz builds.
set -euo pipefail
cd "$(dirname "$0")/.."

# Debian packages: compilers, test and format tools for the firmware core, the AVR toolchain and Arduino core,
# the AVR simulator, and the browser the live view's test opens the viewer in. Installed only where missing.
DEBIAN_PACKAGES=(cmake ninja-build g++ clang libclang-rt-14-dev doctest-dev clang-format
                 gcc-avr avr-libc binutils-avr arduino-core-avr simavr libsimavr-dev libelf-dev chromium)
missing=()
for pkg in "${DEBIAN_PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed" || missing+=("$pkg")
done
if ((${#missing[@]})); then
  echo "setup: installing Debian packages: ${missing[*]}"
  if [[ $(id -u) -eq 0 ]]; then SUDO=""; else SUDO="sudo"; fi
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# The Python package (editable, with test extras), from this checkout: another checkout's editable install would
# answer every import (and its build/ every native artifact), so the tests would run that one instead.
installed=$(python3 -c "import mantaray.paths as p; print(p.REPO)" 2>/dev/null || true)
if [ -n "$installed" ] && [ "$installed" != "$(pwd -P)" ]; then
  echo "setup: the mantaray package installed is the checkout in $installed; installing this one ($(pwd -P)) instead"
fi
if [ "$installed" != "$(pwd -P)" ] ||
   ! python3 -c "import mantaray, pytest, hypothesis, serial, numpy, mujoco, matplotlib, tqdm, imageio, imageio_ffmpeg, ray, cv2, optuna, scikit_build_core, ruff, mypy, rerun, playwright" 2>/dev/null ||
   ! python3 -m pip show -q mantaray >/dev/null 2>&1; then
  echo "setup: installing the mantaray Python package"
  python3 -m pip install -q --disable-pip-version-check -e ".[test,lint]"
fi

# Generated protocol code must match the schema before anything is built from it.
python3 protocol/generate.py --check

# Native firmware: unit tests, virtual MCU, C library (build/); libFuzzer target with clang (build-fuzz/).
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
ninja -C build >/dev/null
CC=clang CXX=clang++ cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
ninja -C build-fuzz fuzz_decoder >/dev/null
echo "setup: done"
