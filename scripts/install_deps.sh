#!/usr/bin/env bash
# Installs the Debian 12 packages emf needs to build, run and test. Idempotent:
# packages already present are not touched, and apt is not called at all when
# nothing is missing. Needs root or sudo only when something must be installed.
set -euo pipefail

PACKAGES=(
  build-essential cmake ninja-build pkg-config git
  pocl-opencl-icd ocl-icd-opencl-dev opencl-headers clinfo
  libeigen3-dev libopencv-dev libyaml-cpp-dev libgtest-dev libgmock-dev
  libusb-1.0-0-dev libopenni2-dev libv4l-dev zlib1g-dev libpng-dev libjpeg-dev nlohmann-json3-dev
  python3 python3-numpy python3-onnx python3-open3d
  xvfb x11-apps
)

# Installed for this machine's architecture (or arch-independent): a package of a foreign
# architecture (multiarch, e.g. arm64 libraries) does not count.
native="$(dpkg --print-architecture)"
missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status} ${Architecture}\n' "$p" 2>/dev/null |
    grep -qE "^install ok installed ($native|all)$"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install_deps: all ${#PACKAGES[@]} packages present"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then
    SUDO="sudo"
  else
    echo "install_deps: missing packages (${missing[*]}) and not root, no sudo." >&2
    echo "install_deps: run as root: apt-get install ${missing[*]}" >&2
    exit 1
  fi
fi

echo "install_deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
echo "install_deps: done"
