#!/usr/bin/env bash
# Installs the Debian 12 packages heatcvt needs. Idempotent: packages already present are kept.
set -euo pipefail
packages=(build-essential cmake pkg-config
          libeigen3-dev libsuitesparse-dev libcgal-dev libpcl-dev libflann-dev
          libgtest-dev libcli11-dev libtbb-dev nlohmann-json3-dev
          libopenblas0-pthread)  # optimised BLAS: CHOLMOD's supernodal factorisation is ~3-4x faster than with the reference BLAS
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install_deps: all ${#packages[@]} packages already installed"
  exit 0
fi
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
echo "install_deps: installing ${missing[*]}"
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
