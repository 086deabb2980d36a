#!/usr/bin/env bash
# The main job (README): installs what is missing, builds, then on the built-in default input
#   1. renders the synthetic `cars` scene (two toy cars driving in a room, simulated detections
#      every 30 frames) into out/default/input (TUM folder with exact ground truth),
#   2. runs the SLAM on it with the maskfile detector replaying those detections ->
#      out/default/{camera.txt,object-<id>.txt,background.ply,object-<id>.ply,run.json} and
#      out/default/images/<frame>-objects.png (each object's mask over the colour image),
#   3. evaluates the camera and object trajectories against the ground truth ->
#      out/default/eval.{json,png}.
# EMF_RUN_FRAMES (default 300) sets the sequence length; extra arguments go to `emf run`.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
bash scripts/build.sh build -DCMAKE_BUILD_TYPE=RelWithDebInfo
frames="${EMF_RUN_FRAMES:-300}"
out=out/default
mkdir -p "$out"
./build/bin/emf info --no-kernels | tee "$out/info.txt"
./build/bin/emf synth cars --frames "$frames" --out "$out/input" --force
./build/bin/emf run --source "tum:$out/input" --detector maskfile --out "$out" --force \
  --set output.write_images=true "$@"
./build/bin/emf eval --gt "$out/input" --est "$out" --out "$out"
echo "emf: outputs in $(pwd)/$out (camera.txt, object-<id>.txt, background.ply, run.json," \
  "eval.json, eval.png; images/<frame>-objects.png: the objects' masks over the colour image)"
