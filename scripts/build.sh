#!/usr/bin/env bash
# Configures and builds emf in a build folder. Usage: scripts/build.sh <build-dir> [cmake args...]
set -euo pipefail
cd "$(dirname "$0")/.."
dir="$1"
shift
jobs="${EMF_JOBS:-$(nproc)}"
cmake -S . -B "$dir" -G Ninja "$@" >/dev/null
cmake --build "$dir" -j "$jobs"
