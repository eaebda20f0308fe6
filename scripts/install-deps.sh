#!/usr/bin/env bash
# Installs bounce's build and test dependencies from Debian 12 packages.
# Idempotent: does nothing (and needs no network) when everything is already installed.
set -euo pipefail
packages=(
  build-essential cmake ninja-build pkg-config
  libembree-dev libtbb-dev libopenimageio-dev openimageio-tools libopenexr-dev libimath-dev
  libassimp-dev nlohmann-json3-dev libcli11-dev libfmt-dev libgtest-dev libbenchmark-dev
  libosd-dev libcpp-httplib-dev chromium
  clang libclang-rt-dev clang-format python3-matplotlib
  libopenmpi-dev openmpi-bin
  libopencolorio-dev
  python3-dev python3-pybind11 python3-numpy python3-pytest
  blender
)
missing=()
for p in "${packages[@]}"; do
  dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p")
done
# node and npm for the lighting tool's page (three.js) and browser test (playwright-core):
# Debian's packages unless a node is already installed some other way.
command -v node >/dev/null 2>&1 || missing+=(nodejs)
command -v npm >/dev/null 2>&1 || missing+=(npm)
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi
echo "install-deps: installing ${missing[*]}"
sudo_cmd=()
[ "$(id -u)" -ne 0 ] && sudo_cmd=(sudo)
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
