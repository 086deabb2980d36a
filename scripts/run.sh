#!/usr/bin/env bash
# The main job (README): installs what is missing, builds, and runs emf on the built-in default
# input, writing its outputs to out/default/. Extra arguments are passed to the command.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
bash scripts/build.sh build -DCMAKE_BUILD_TYPE=RelWithDebInfo
mkdir -p out/default
./build/bin/emf info "$@" | tee out/default/info.txt
echo "emf: outputs in $(pwd)/out/default"
