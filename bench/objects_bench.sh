#!/usr/bin/env bash
# Dynamic-object figures of issue 6, the way a user gets them: `emf synth` writes a preset as a
# TUM folder with the simulated detector's masks, `emf run --detector maskfile` replays them
# (or `--detector motion` finds the movers itself), `emf eval` scores camera and objects.
#
#   bench/objects_bench.sh [--emf PATH] [--frames N] [--size WxH] [--out DIR] [--presets LIST]
#   bench/objects_bench.sh --timing [--emf PATH] [--out DIR] [--sizes LIST]
#
# Prints per run: camera ATE, per ground-truth object the matched estimate's ATE and coverage,
# ms per frame per stage (run.json), then the ablation table (association vs p_fg only, the
# paper's "w/o assoc.") on the occlusion preset, and machine-readable lines
#   objects_bench run=<name> camera_ate_cm=.. objects=<gt:ate_cm:coverage,..> ms=..
# --timing: ms per frame by stage with 0, 1 and 3 objects alive, for each size (default
# 320x240,640x480): 30 frames of the occlusion preset from frame 120 on (bear, suitcase and
# chair in view; the maskfile detector runs on the first of them, so all objects are created
# there), with objects.max_objects 0, 1 and 3. Prints lines
#   objects_bench timing size=WxH objects=N confirmed=C total_ms=.. <stage>_ms=..
# (C: objects run.json reports at the end; in 30 frames with one detection frame the objects
# stay tentative, tracked and fused every frame but not confirmed, so C is 0.)
set -euo pipefail
export EMF_LOG_LEVEL=${EMF_LOG_LEVEL:-warning}

EMF=build/bin/emf
FRAMES=150
SIZE=320x240
OUT=out/objects_bench
PRESETS="cars,occlusion"
TIMING=0
SIZES="320x240,640x480"
need_value() {  # <option> [value]: a usage error unless the option has a non-empty value
  [[ $# -ge 2 && -n "$2" ]] || { echo "objects_bench: $1 needs a value (see --help)" >&2; exit 2; }
}
while [[ $# -gt 0 ]]; do
  case "$1" in
    --sizes|--emf|--frames|--size|--out|--presets) need_value "$@" ;;
  esac
  case "$1" in
    --timing) TIMING=1; shift ;;
    --sizes) SIZES="$2"; shift 2 ;;
    --emf) EMF="$2"; shift 2 ;;
    --frames) FRAMES="$2"; shift 2 ;;
    --size) SIZE="$2"; shift 2 ;;
    --out) OUT="$2"; shift 2 ;;
    --presets) PRESETS="$2"; shift 2 ;;
    -h|--help) sed -n 2,19p "$0"; exit 0 ;;
    *) echo "objects_bench: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
size_ok() { [[ "$1" =~ ^[1-9][0-9]*x[1-9][0-9]*$ ]]; }
size_ok "$SIZE" || { echo "objects_bench: --size $SIZE: expected WxH, e.g. 320x240" >&2; exit 2; }
IFS=, read -ra _sizes <<<"$SIZES"
for s in "${_sizes[@]}"; do
  size_ok "$s" || { echo "objects_bench: --sizes: '$s' is not WxH, e.g. 320x240" >&2; exit 2; }
done
[[ "$FRAMES" =~ ^[1-9][0-9]*$ ]] || { echo "objects_bench: --frames $FRAMES: expected a positive integer" >&2; exit 2; }
[[ -n "${PRESETS//,/}" ]] || { echo "objects_bench: --presets names no preset" >&2; exit 2; }
[[ -x "$EMF" ]] || { echo "objects_bench: no emf binary at $EMF (build first or pass --emf)" >&2; exit 2; }
mkdir -p "$OUT"

background() {  # <width>: background at 2 cm for 320x240 and below (as the tests), else 1 cm
  if [[ "$1" -le 320 ]]; then
    echo "--set map.background_voxel_m=0.02 --set map.background_resolution=256"
  fi
}

if [[ "$TIMING" == 1 ]]; then
  IFS=, read -ra SIZE_LIST <<<"$SIZES"
  for size in "${SIZE_LIST[@]}"; do
    w=${size%x*}
    h=${size#*x}
    full="$OUT/data-occlusion-$size-150"
    [[ -f "$full/groundtruth.txt" ]] ||
      "$EMF" synth occlusion --out "$full" --frames 150 --width "$w" --height "$h" --force >/dev/null
    # Frames [120, 150) (t >= 4 s) as their own TUM folder: lists filtered, image folders linked.
    part="$OUT/data-occlusion-$size-120-150"
    rm -rf "$part"
    mkdir -p "$part"
    for d in rgb depth masks objects; do ln -s "$(cd "$full" && pwd)/$d" "$part/$d"; done
    cp "$full/calibration.txt" "$part/"
    for f in rgb.txt depth.txt associations.txt groundtruth.txt; do
      awk '/^#/ || ($1 + 0 >= 4.0 - 1e-6)' "$full/$f" >"$part/$f"
    done
    for n in 0 1 3; do
      dir="$OUT/timing-$size-$n"
      rm -rf "$dir"
      read -ra bg <<<"$(background "$w")"
      "$EMF" run --quiet --source "tum:$part" --detector maskfile --out "$dir" "${bg[@]}" \
        --set objects.max_objects=$n >/dev/null
      python3 - "$size" "$n" "$dir" <<'EOF'
import json, sys
size, n, run = sys.argv[1], sys.argv[2], sys.argv[3]
j = json.load(open(run + "/run.json"))
confirmed = sum(1 for o in j.get("objects", []) if o.get("state") != "deleted")
st = j["ms_per_frame"]
order = ["preprocess", "estep", "track", "track_objects", "detect", "objects", "integrate"]
cells = " ".join(f"{k}_ms={st[k]['median_ms']:.1f}" for k in order if k in st)
print(f"objects_bench timing size={size} objects={n} confirmed={confirmed} "
      f"total_ms={st['total']['median_ms']:.1f} {cells}")
EOF
    done
  done
  exit 0
fi

W=${SIZE%x*}
H=${SIZE#*x}
read -ra BG <<<"$(background "$W")"

summary() {  # <name> <dataset> <run dir>
  local name=$1 data=$2 run=$3
  "$EMF" eval --gt "$data" --est "$run" --no-files | tee "$run/eval.txt"
  python3 - "$name" "$run" <<'EOF'
import json, re, sys
name, run = sys.argv[1], sys.argv[2]
j = json.load(open(run + "/run.json"))
stages = j.get("ms_per_frame", j.get("timing", {}))
def med(s):
    v = stages.get(s, {})
    return v.get("median", v.get("median_ms", 0.0)) if isinstance(v, dict) else 0.0
names = [k for k in stages.keys()]
print("  ms/frame median: " + ", ".join(f"{k} {med(k):.1f}" for k in names))
cam, objs = None, []
for line in open(run + "/eval.txt"):
    f = line.split()
    if len(f) >= 5 and f[0] == "camera":
        cam = float(f[4]) * 100
    if len(f) >= 6 and f[0] == "object" and f[2].startswith("object-"):
        objs.append(f"{f[1]}:{float(f[5]) * 100:.2f}:{f[4].rstrip('%')}")
    elif len(f) >= 3 and f[0] == "object" and f[2] in ("-", "none"):
        objs.append(f"{f[1]}:none:0")
total = med("total")
print(f"objects_bench run={name} camera_ate_cm={cam:.3f} objects={','.join(objs) or 'none'} ms={total:.1f}")
EOF
}

run() {  # <name> <dataset> <detector> [emf run args...]
  local name=$1 data=$2 det=$3
  shift 3
  local dir="$OUT/run-$name"
  echo "== $name: emf run --detector $det $*"
  rm -rf "$dir"
  "$EMF" run --quiet --source "tum:$data" --detector "$det" --out "$dir" "${BG[@]}" "$@" | tail -n +1 >/dev/null
  summary "$name" "$data" "$dir"
}

IFS=, read -ra LIST <<<"$PRESETS"
for p in "${LIST[@]}"; do
  data="$OUT/data-$p-$SIZE-$FRAMES"
  [[ -f "$data/groundtruth.txt" ]] ||
    "$EMF" synth "$p" --out "$data" --frames "$FRAMES" --width "$W" --height "$H" --force >/dev/null
  run "$p" "$data" maskfile
  if [[ "$p" == occlusion ]]; then
    run "$p-pfg" "$data" maskfile --set em.association=pfg
  fi
  if [[ "$p" == cars ]]; then
    # The motion detector needs more frequent calls than a trained one (a region must persist
    # over two calls); its thresholds are the plugin's defaults.
    run "$p-motion" "$data" motion --set detector.every_n_frames=5
  fi
done
