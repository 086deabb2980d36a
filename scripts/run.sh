#!/usr/bin/env bash
# The main job (README): installs what is missing, builds, then on the built-in default input
#   1. renders the synthetic static room (conf: source.uri) into out/default/input (TUM folder
#      with exact ground truth),
#   2. runs the SLAM on it -> out/default/{camera.txt,background.ply,run.json},
#   3. evaluates the camera trajectory against the ground truth -> out/default/eval.{json,png}.
# EMF_RUN_FRAMES (default 300) sets the sequence length; extra arguments go to `emf run`.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
bash scripts/build.sh build -DCMAKE_BUILD_TYPE=RelWithDebInfo
frames="${EMF_RUN_FRAMES:-300}"
out=out/default
mkdir -p "$out"
./build/bin/emf info --no-kernels | tee "$out/info.txt"
./build/bin/emf synth room --frames "$frames" --out "$out/input" --force
./build/bin/emf run --source "tum:$out/input" --out "$out" --force "$@"
./build/bin/emf eval --gt "$out/input" --est "$out" --out "$out"
echo "emf: outputs in $(pwd)/$out (camera.txt, background.ply, run.json, eval.json, eval.png)"
