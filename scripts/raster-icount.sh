#!/usr/bin/env bash
# Instructions one fill-rate call of the soft rasterizer executes, exactly
# (valgrind's callgrind counts them): a 2-call run minus a 1-call run of the
# `fill_calls` example, so that the workload's generation and the first call's
# allocations cancel. The way to compare two builds of the rasterizer on a
# shared machine whose timings drift (DEVELOPERS.md).
#
#   scripts/raster-icount.sh [FILL_CALLS_BINARY] [LEG ...]   (default: target/release/examples/fill_calls, legs 10 25)
set -euo pipefail
bin=${1:-target/release/examples/fill_calls}
shift || true
legs=("$@")
((${#legs[@]})) || legs=(10 25)
if [[ ! -x $bin ]]; then
  echo "raster-icount: no $bin (cargo build --release -p occlude-soft --example fill_calls)" >&2
  exit 2
fi
command -v valgrind >/dev/null || { echo "raster-icount: needs valgrind (apt-get install valgrind)" >&2; exit 2; }
refs() {
  valgrind --tool=callgrind --callgrind-out-file=/dev/null "$bin" --leg "$1" --calls "$2" --threads 1 2>&1 |
    awk '/refs:/ {gsub(",", "", $4); print $4}'
}
for n in "${legs[@]}"; do
  one=$(refs "$n" 1)
  two=$(refs "$n" 2)
  echo "N=$n: $(((two - one) / 1000000)) M instructions per call"
done
