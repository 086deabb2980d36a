#!/usr/bin/env bash
# arm64 from an x86-64 Debian 12 machine: installs what is missing (the cross compiler,
# qemu-user, an arm64 sysroot of Debian's packages with PoCL), cross-builds emf, its
# plugins and tests for arm64 into build-arm64/, and runs the tests under qemu-user with
# PoCL's arm64 CPU device. Nothing arm64 is installed on the machine: the arm64 libraries
# live in build-arm64/sysroot.
#   scripts/test_arm64.sh            the tests that fit user-mode emulation (labels slow, cli,
#                                    faults, install, bench and pipeline left out)
#   scripts/test_arm64.sh --smoke    the smoke set (tests/kernel_smoke.txt and one scene)
#   extra arguments go to ctest (e.g. -R ClRuntime)
# EMF_ARM64_BUILD=<dir> sets the build folder, EMF_JOBS=<n> the parallelism.
set -euo pipefail
cd "$(dirname "$0")/.."
repo="$PWD"
mkdir -p "${EMF_ARM64_BUILD:-build-arm64}"
build="$(cd "${EMF_ARM64_BUILD:-build-arm64}" && pwd)"
jobs="${EMF_JOBS:-$(nproc)}"
smoke=0
if [[ "${1:-}" == "--smoke" ]]; then
  smoke=1
  shift
fi
sudo=""
if [[ $(id -u) -ne 0 ]]; then sudo="sudo"; fi

# ---- 1. host packages ----------------------------------------------------------------------
bash scripts/install_deps.sh
host=(g++-aarch64-linux-gnu qemu-user)
missing=()
for p in "${host[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "emf arm64: installing ${missing[*]}"
  $sudo apt-get update -q
  $sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends \
    "${missing[@]}"
fi

# ---- 2. the arm64 sysroot -------------------------------------------------------------------
# Debian's arm64 packages of what emf links (and PoCL), with their dependencies, unpacked into
# build-arm64/sysroot: nothing arm64 is installed on the machine. (Installed through multiarch
# instead, libopencv-dev:arm64 removes the machine's own libopencv-dev, and PoCL's arm64
# clang-15 conflicts with the cross binutils.) apt reads the arm64 package lists, so arm64 is
# added as a foreign architecture.
sysroot="$build/sysroot"
arm64_packages=(libopencv-dev libyaml-cpp-dev ocl-icd-opencl-dev libgtest-dev libgmock-dev
                libusb-1.0-0-dev libopenni2-dev zlib1g-dev libpng-dev libjpeg-dev libv4l-dev
                libeigen3-dev nlohmann-json3-dev pocl-opencl-icd)
if [[ ! -f "$sysroot/.complete" ]]; then
  if ! dpkg --print-foreign-architectures | grep -qx arm64; then
    $sudo dpkg --add-architecture arm64
  fi
  $sudo apt-get update -q
  apt_dir="$build/apt"
  rm -rf "$sysroot" "$apt_dir"
  mkdir -p "$sysroot" "$apt_dir/archives/partial"
  touch "$apt_dir/status"  # nothing installed: apt downloads the whole closure
  $sudo apt-get -q -o Dir::State::status="$apt_dir/status" -o Dir::Cache::archives="$apt_dir/archives" \
    -o APT::Architecture=arm64 -o APT::Architectures::=arm64 -o Debug::NoLocking=1 \
    -o APT::Install-Recommends=0 install --download-only -y "${arm64_packages[@]}"
  for deb in "$apt_dir"/archives/*.deb; do dpkg -x "$deb" "$sysroot"; done
  # Absolute links (/usr/lib/... -> /lib/...) point into the sysroot instead.
  (cd "$sysroot" && find . -type l -lname '/*' | while read -r link; do
     ln -sfn "$(realpath -m --relative-to="$(dirname "$link")" ".$(readlink "$link")")" "$link"
   done)
  # libblas.so.3 and liblapack.so.3 (OpenCV's) are links that the packages' postinst makes with
  # update-alternatives, which unpacking does not run.
  for lib in blas/libblas.so.3 lapack/liblapack.so.3; do
    ln -sfn "$lib" "$sysroot/usr/lib/aarch64-linux-gnu/$(basename "$lib")"
  done
  touch "$sysroot/.complete"
fi
# PoCL reads its kernel library through a path with '..' (from libpocl's folder), which qemu
# does not look up in the sysroot: the file goes beside the host PoCL's own, under its own name.
for bc in "$sysroot"/usr/share/pocl/kernel-aarch64-*.bc; do
  cmp -s "$bc" "/usr/share/pocl/$(basename "$bc")" || $sudo install -m 644 "$bc" /usr/share/pocl/
done

# ---- 3. cross build ----------------------------------------------------------------------------
cmake -S . -B "$build" -G Ninja -DCMAKE_TOOLCHAIN_FILE=cmake/toolchain-aarch64-linux-gnu.cmake \
  -DEMF_ARM64_SYSROOT="$sysroot" -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
if ((smoke)); then
  # The smoke set's test programs only (and the libraries they link).
  cmake --build "$build" -j "$jobs" --target cl_runtime_test map_integrate_test \
    map_sample_raycast_test track_preprocess_test track_tracker_test em_estep_test \
    pipeline_slam_sequence_test synth_random_test
else
  cmake --build "$build" -j "$jobs"
fi

# PoCL (under qemu) links each kernel with the first `ld` on PATH: the cross linker, with the
# cross compiler's libgcc (the host's own ld cannot link arm64).
mkdir -p "$build/cross-bin"
printf '#!/bin/sh\nexec /usr/bin/aarch64-linux-gnu-ld -L%s -L/usr/aarch64-linux-gnu/lib "$@"\n' \
  "$(dirname "$(aarch64-linux-gnu-gcc -print-libgcc-file-name)")" >"$build/cross-bin/ld"
chmod +x "$build/cross-bin/ld"
export PATH="$build/cross-bin:$PATH"

# ---- 4. tests under qemu-user ----------------------------------------------------------------
export POCL_CACHE_DIR="$build/pocl-cache"
export XDG_CACHE_HOME="$build/test-cache"
cd "$build"
if ((smoke)); then
  # The kernel smoke set, and a generated scene that must be the same scene as on x86-64.
  exec ctest --output-on-failure --no-tests=error -j "$jobs" \
    -R "$(grep -v "^#" "$repo/tests/kernel_smoke.txt" | paste -sd"|")|^RandomScene\.ASeedIsTheSame" \
    "$@"
fi
# Left out: what starts an arm64 child by itself, which user-mode qemu cannot run (the detector
# host: label faults and one scheduler test; install), the viewer and CLI runs (cli), benches,
# and the long sequences (slow, and pipeline: SLAM sequences of 1-10 min each under qemu; one
# runs in the smoke set). Programs the tests start through the shell get the emulator prefix
# (tests/CMakeLists.txt).
exec ctest --output-on-failure --no-tests=error -j "$jobs" \
  -LE "slow|cli|faults|install|bench|^pipeline$" \
  -E "^DetectorSchedulerAsync\.PluginOnTheDetectorThread$" "$@"
