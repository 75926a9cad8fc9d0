#!/usr/bin/env bash
# Issue 8's measurements on a machine with a real GPU, in one go: every
# hierarchical method through the wgpu backend on city and plant, a calibrated
# GPU model checked against the measured frame times, the IOC poster's tables
# (`--paper ioc`) measured and predicted by the soft backend with that model,
# and the rasterizer fill-rate table with the GPU's rows. Built for a borrowed machine with little
# time on it (see DEVELOPERS.md, "Measuring on a real GPU"): it needs only a
# release build of `occlude` and a Vulkan driver, and writes seven files.
#
#   scripts/gpu-bench.sh [OCCLUDE_BINARY]      (default: target/release/occlude)
#
# Environment: OUT (where the files go, default ./gpu-out), SIZE (scene size,
# default medium), FRAMES (frames per scene, default 100).
# Files: city.json, plant.json (`occlude bench --json`), gpu.toml (`occlude
# calibrate`), ioc.json and ioc-soft.json (`--paper ioc` on wgpu and on soft
# with gpu.toml, 1920x1080), raster.json (`occlude raster-bench --json`) and
# log.txt (every command's printed output, in order).
set -euo pipefail

bin=${1:-target/release/occlude}
out=${OUT:-gpu-out}
size=${SIZE:-medium}
frames=${FRAMES:-100}
methods=vfc,sw,chc,chcpp,om,roc,ioc,hiz,opt

if [[ ! -x $bin ]]; then
  echo "gpu-bench: no occlude binary at $bin (cargo build --release -p occlude-cli, or pass its path)" >&2
  exit 2
fi
mkdir -p "$out"
log=$out/log.txt
: >"$log"

# Runs a command, its output shown and appended to the log; stops the script
# with the command's exit code when it fails (exit 2: no GPU adapter).
step() {
  echo "\$ $*" | tee -a "$log"
  local rc=0
  "$@" 2>&1 | tee -a "$log" || rc=${PIPESTATUS[0]}
  if ((rc != 0)); then
    echo "gpu-bench: '$*' failed with exit code $rc (log: $log)" | tee -a "$log" >&2
    exit "$rc"
  fi
}

{
  echo "# gpu-bench $(date -u +%Y-%m-%dT%H:%M:%SZ) on $(uname -n)"
  command -v nvidia-smi >/dev/null && nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
  grep -m1 'model name' /proc/cpuinfo || true
} 2>&1 | tee -a "$log"

for scene in city plant; do
  step "$bin" bench --backend wgpu --scene "$scene" --size "$size" --methods "$methods" --frames "$frames" \
    --json "$out/$scene.json"
done
step "$bin" calibrate --backend wgpu --out "$out/gpu.toml"
paper=(bench --paper ioc --size "$size" --frames "$frames" --resolution 1920x1080)
step "$bin" "${paper[@]}" --backend wgpu --json "$out/ioc.json"
step "$bin" "${paper[@]}" --gpu-model "$out/gpu.toml" --json "$out/ioc-soft.json"
step "$bin" raster-bench --gpu required --json "$out/raster.json"
grep -ho '"adapter": *"[^"]*"' "$out/city.json" | head -1 | tee -a "$log"
echo "gpu-bench: done; files in $out" | tee -a "$log"
