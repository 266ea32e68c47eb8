#!/usr/bin/env bash
# Installs the Debian 12 packages TeraWalk builds and runs with, skipping those already present.
# Used by both README commands so that a fresh machine needs nothing else.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config time
  libembree-dev libopenvdb-dev libboost-iostreams-dev libopenmesh-dev libmeshoptimizer-dev
  libtbb-dev libglfw3-dev libglm-dev libbenchmark-dev libgtest-dev
  libegl-dev libgl-dev libgl1-mesa-dri libegl-mesa0
  libzstd-dev libxxhash-dev libmetis-dev libsqlite3-dev libcli11-dev nlohmann-json3-dev
  libstb-dev libtinygltf-dev libimgui-dev xvfb gnuplot-nox
  libocct-data-exchange-dev libocct-modeling-algorithms-dev libocct-ocaf-dev
  libxml2-dev libxml2-utils libzip-dev ffmpeg libopenmpi-dev openmpi-bin
  clang libclang-rt-14-dev
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi

echo "Installing missing Debian packages: ${missing[*]}"
sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
