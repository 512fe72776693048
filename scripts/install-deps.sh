#!/usr/bin/env bash
# Installs the Debian 12 packages cisamr builds with, when missing (needs root or sudo).
set -euo pipefail
packages=(build-essential cmake ninja-build libcgal-dev libboost-dev libgmp-dev libmpfr-dev
          nlohmann-json3-dev libcli11-dev libfmt-dev libgtest-dev libtet1.5-dev
          libopenmpi-dev openmpi-bin libpugixml-dev zlib1g-dev
          calculix-ccx gmsh python3-meshio python3-vtk9 tetgen
          libocct-foundation-dev libocct-modeling-data-dev libocct-modeling-algorithms-dev
          libocct-data-exchange-dev libtbb-dev)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "installing: ${missing[*]}"
  sudo_cmd=""
  [ "$(id -u)" -eq 0 ] || sudo_cmd="sudo"
  $sudo_cmd apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
