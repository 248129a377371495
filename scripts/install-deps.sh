#!/usr/bin/env bash
# Installs PointRT's build dependencies from Debian 12's packages (needs root or sudo).
# CUDA is optional: when /usr/local/cuda/bin/nvcc exists the CUDA backend is built too.
set -euo pipefail
packages=(
    cmake g++ make pkg-config
    libpcl-dev libflann-dev liblz4-dev libeigen3-dev
    libopenmesh-dev libopenimageio-dev openimageio-tools
    libglfw3-dev libgl-dev
    nlohmann-json3-dev libcli11-dev libxxhash-dev libgtest-dev
    libembree-dev
    pybind11-dev python3-dev python3-numpy python3-pytest
    python3-dask python3-distributed python3-xxhash python3-psutil
    xvfb xauth
)
sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
missing=()
for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
    echo "install-deps: all ${#packages[@]} packages already installed"
    exit 0
fi
echo "install-deps: installing ${missing[*]}"
$sudo apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
