#!/usr/bin/env bash
# `mcl check` on the generated fleets of issue 17 (mcl_coord::gen): the
# table of BENCHMARKS.md, "mcl-coord: fleets".
#
# Usage: benches-scripts/fleet-check.sh [SEED ...]
#   SEEDS default to 1 2. For each seed, fleets of 4, 8, 12 and 16 vehicles,
#   free of deadlock and with a cycle of orders. Environment: MCL (the
#   binary; default: target/debug/mcl, built here: mcl-coord and mcl-net
#   are optimized in the dev profile), WORK (a folder for the fleets;
#   default a temporary one, removed at the end), TIMEOUT (seconds per
#   check, default 120: a fleet that passes the cap of 4 million product
#   states takes longer and ~2-3 GB). Needs GNU time (/usr/bin/time).
#
# Each row: vehicles, constraints, the verdict of `mcl check` (free: exit 0
# and no diagnostic; deadlock: E0406; unknown: W0407; timeout), wall and
# user CPU time and peak resident memory from `/usr/bin/time -v`. On a
# shared machine the wall time follows the load; the CPU time does not.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
SEEDS=("$@")
if [ ${#SEEDS[@]} -eq 0 ]; then
  SEEDS=(1 2)
fi
[ -x /usr/bin/time ] || { echo "error: /usr/bin/time not found (apt-get install -y time)" >&2; exit 1; }

cd "$ROOT"
TARGET="$(cargo metadata --format-version 1 --no-deps | sed -n 's/.*"target_directory":"\([^"]*\)".*/\1/p')"
cargo build -q -p mcl-coord --example fleet
GEN="$TARGET/debug/examples/fleet"
if [ -z "${MCL:-}" ]; then
  cargo build -q --bin mcl
  MCL="$TARGET/debug/mcl"
fi
if [ -z "${WORK:-}" ]; then
  WORK="$(mktemp -d)"
  trap 'rm -rf "$WORK"' EXIT
fi
cp examples/vehicle.mcl "$WORK/"

echo "| vehicles | seed | constraints | generated | verdict | wall (s) | CPU (s) | peak RSS (MiB) |"
echo "|---:|---:|---:|---|---|---:|---:|---:|"
for seed in "${SEEDS[@]}"; do
  for n in 4 8 12 16; do
    for kind in free deadlock; do
      f="$WORK/fleet-$n-$seed-$kind.mcl"
      if [ "$kind" = deadlock ]; then "$GEN" "$n" "$seed" deadlock > "$f"; else "$GEN" "$n" "$seed" > "$f"; fi
      cs="$(sed -n 's/.* \([0-9]*\) constraints.*/\1/p' "$f" | head -1)"
      set +e
      /usr/bin/time -v timeout "${TIMEOUT:-120}" "$MCL" check --color never "$f" > "$WORK/out" 2> "$WORK/time"
      rc=$?
      set -e
      if [ "$rc" = 124 ]; then verdict=timeout
      elif grep -q "E0406" "$WORK/out"; then verdict=deadlock
      elif grep -q "W0407" "$WORK/out"; then verdict=unknown
      elif grep -q "0 errors, 0 warnings" "$WORK/out"; then verdict=free
      else verdict="other: $(tail -1 "$WORK/out")"; fi
      wall="$(awk -F': ' '/Elapsed \(wall clock\)/ { n = split($2, a, ":"); s = 0; for (i = 1; i <= n; i++) s = s * 60 + a[i]; printf "%.2f", s }' "$WORK/time")"
      cpu="$(awk -F': ' '/User time|System time/ { s += $2 } END { printf "%.2f", s }' "$WORK/time")"
      rss="$(awk -F': ' '/Maximum resident set size/ { printf "%.0f", $2 / 1024 }' "$WORK/time")"
      echo "| $n | $seed | $cs | $kind | $verdict | $wall | $cpu | $rss |"
    done
  done
done
