#!/usr/bin/env bash
# Throughput of the vehicle simulator (`mcl run --sim --virtual-time`,
# docs/simulator.md): simulated seconds per wall second, for the survey
# (examples/survey.mcl, one vehicle) and for eight vehicles at once
# (examples/sim/fleet8.mcl in examples/sim/fleet8.toml, coordinated by
# mcl-runtime's multi-vehicle loop). Each run is a whole process: loading,
# compiling the mission, simulating, writing nothing (-q, no trace).
#
# Usage: benches-scripts/sim-bench.sh
#   Environment: RUNS (runs per case, default 20), MCL (a built binary to
#   time instead of building target/release/mcl).
# Times with hyperfine when it is installed, else with a loop timed by
# `date +%s.%N` (mean over RUNS). Run it on a quiet machine; numbers go to
# BENCHMARKS.md by hand.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
RUNS="${RUNS:-20}"
if [ -z "${MCL:-}" ]; then
  cargo build --release --quiet --bin mcl
  MCL="$ROOT/target/release/mcl"
fi
TMP="$(mktemp -d "${TMPDIR:-/tmp}/mcl-sim-bench.XXXXXX")"
trap 'rm -rf "$TMP"' EXIT

# Mean wall seconds of one run of the command "$@".
wall() {
  if command -v hyperfine >/dev/null 2>&1; then
    local cmd
    cmd="$(printf '%q ' "$@")"
    hyperfine --warmup 2 --runs "$RUNS" --export-csv "$TMP/h.csv" --style none "$cmd" >/dev/null
    awk -F, 'NR == 2 { print $2 }' "$TMP/h.csv"
  else
    "$@" >/dev/null 2>&1 || true # warm-up
    local t0 t1
    t0="$(date +%s.%N)"
    for _ in $(seq "$RUNS"); do "$@" >/dev/null 2>&1 || true; done
    t1="$(date +%s.%N)"
    awk -v a="$t0" -v b="$t1" -v n="$RUNS" 'BEGIN { printf "%.6f\n", (b - a) / n }'
  fi
}

# NAME ARGS...: one run to read the mission times ("mission `x`: OK at t=..."
# on standard error), then the timing.
bench() {
  local name="$1"
  shift
  local status=0
  "$MCL" run --sim --virtual-time -q "$@" 2>"$TMP/err" >/dev/null || status=$?
  if [ "$status" -ne 0 ]; then
    echo "$name: the run ended with exit status $status:" >&2
    cat "$TMP/err" >&2
    exit 1
  fi
  local times vehicles longest total mean
  times="$(grep -o '^mission `[^`]*`: [A-Z_]* at t=[0-9.]*' "$TMP/err" | sed 's/.*at t=//')"
  vehicles="$(echo "$times" | wc -l)"
  longest="$(echo "$times" | sort -g | tail -1)"
  total="$(echo "$times" | awk '{ s += $1 } END { print s }')"
  mean="$(wall "$MCL" run --sim --virtual-time -q "$@")"
  awk -v n="$name" -v v="$vehicles" -v l="$longest" -v s="$total" -v w="$mean" 'BEGIN {
    printf "%-10s %d vehicle(s), %.1f s of mission time (%.1f vehicle-s), %.4f s wall per run: %.0f simulated s per wall s (%.0f vehicle-s per wall s)\n",
      n, v, l, s, w, l / w, s / w
  }'
}

echo "mcl: $MCL; runs per case: $RUNS; $(command -v hyperfine >/dev/null 2>&1 && echo hyperfine || echo 'date loop')"
bench survey examples/survey.mcl
bench fleet8 examples/sim/fleet8.mcl --world examples/sim/fleet8.toml
