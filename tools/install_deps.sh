#!/usr/bin/env bash
# Installs the Debian packages this project builds and runs with (Debian 12 /
# Ubuntu 22.04+). Does nothing when they are all present already.
# libhdf5-openmpi-dev: fix mpm/fluid's ranks write their output in parallel (MPI-IO; without it
# rank 0 gathers and writes alone); hdf5-tools: h5dump, with which the tests compare output files.
set -euo pipefail
pkgs=(cmake ninja-build g++ make pkg-config
      liggghts libliggghts-dev libeigen3-dev libopenmpi-dev openmpi-bin
      libhdf5-dev libhdf5-openmpi-dev hdf5-tools libgtest-dev python3 python3-venv
      libhypre-dev libcli11-dev libtomlplusplus-dev nlohmann-json3-dev)
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi
echo "install_deps: installing ${missing[*]}" >&2
sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >&2
