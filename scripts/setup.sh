#!/usr/bin/env bash
# Installs the Debian 12 packages ispm needs (only those missing), then configures and
# builds into BUILD_DIR (default: build/). Extra arguments go to cmake's configure step.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${BUILD_DIR:-build}
PKGS=(build-essential cmake pkg-config git
      libosmesa6-dev libegl-dev libegl-mesa0 libgl-dev libembree-dev libopenexr-dev libopenimageio-dev openimageio-tools
      libtinygltf-dev libdraco-dev nlohmann-json3-dev libcjson-dev libwebp-dev libmeshoptimizer-dev check libsubunit-dev libxxhash-dev
      libplplot-dev plplot-driver-cairo libpng-dev
      chromium libxml2-utils
      clang libclang-rt-14-dev libomp-14-dev valgrind
      libsdl2-dev libsdl2-ttf-dev fonts-dejavu-core xvfb xauth xdotool imagemagick
      slurm-wlm munge
      python3-jsonschema man-db groff-base)
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO=sudo
  $SUDO apt-get update -q
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
fi
cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=RelWithDebInfo "$@" >/dev/null
cmake --build "$BUILD_DIR" -j"$(nproc)"
