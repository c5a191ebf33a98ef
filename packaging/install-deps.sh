#!/usr/bin/env bash
# Installs the Debian 12 packages scanreg needs to build, test and run.
# Idempotent: prints nothing and installs nothing when every package is present.
set -euo pipefail

packages=(
  build-essential cmake ninja-build ccache pkg-config
  qtbase5-dev libvtk9-qt-dev libpcl-dev libopencv-dev libeigen3-dev
  libgtest-dev nlohmann-json3-dev libceres-dev libpugixml-dev libnanoflann-dev
  xvfb xauth libgl1-mesa-dri
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0

sudo_cmd=()
[ "$(id -u)" -ne 0 ] && sudo_cmd=(sudo)
echo "install-deps: installing ${missing[*]}" >&2
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get -o DPkg::Lock::Timeout=900 -qq update >/dev/null
"${sudo_cmd[@]}" apt-get -o DPkg::Lock::Timeout=900 -qq install -y --no-install-recommends "${missing[@]}" >/dev/null
