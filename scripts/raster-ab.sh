#!/usr/bin/env bash
# Fastest fill-rate call of each of several builds of the `fill_calls`
# example, run in alternation (ROUNDS rounds of ten calls each, one thread), so
# that the machine's slow drifts hit every build alike; prints each build's
# fastest call. Differences under about 5 % are noise on a shared VM
# (DEVELOPERS.md).
#
#   scripts/raster-ab.sh LEG ROUNDS BINARY [BINARY ...]
set -euo pipefail
if (($# < 3)); then
  echo "usage: scripts/raster-ab.sh LEG ROUNDS BINARY [BINARY ...]" >&2
  exit 2
fi
leg=$1 rounds=$2
shift 2
declare -A best
for ((r = 0; r < rounds; r++)); do
  for b in "$@"; do
    ms=$("$b" --leg "$leg" --calls 10 --threads 1 | sed 's/.*calls \([0-9.]*\) ms.*/\1/')
    if [[ -z ${best[$b]:-} ]] || awk -v a="$ms" -v b="${best[$b]}" 'BEGIN {exit !(a < b)}'; then
      best[$b]=$ms
    fi
  done
done
for b in "$@"; do
  echo "N=$leg $b: fastest call ${best[$b]} ms"
done
