#!/usr/bin/env bash
# Configures and builds emf in a build folder. Usage: scripts/build.sh <build-dir> [cmake args...]
# EMF_BUILD_TARGET=<target> builds only that target; EMF_JOBS=<n> sets the parallelism.
set -euo pipefail
cd "$(dirname "$0")/.."
dir="$1"
shift
jobs="${EMF_JOBS:-$(nproc)}"
cmake -S . -B "$dir" -G Ninja "$@" >/dev/null
cmake --build "$dir" -j "$jobs" ${EMF_BUILD_TARGET:+--target "$EMF_BUILD_TARGET"}
