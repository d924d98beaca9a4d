#!/usr/bin/env bash
# Speed-up of mcl-net's explorer with the number of worker threads.
#
# Usage: benches-scripts/explore-threads.sh [NET ...]
#   NET defaults to the three large nets of shared/data/mcc. Environment:
#   THREADS  thread counts to measure (default "1 2 4 8 16");
#   RUNS     runs per net and thread count, best wall time kept (default 3);
#   MCC_DIR  the nets (default tests/data/mcc, a copy of shared/data/mcc);
#   EXACT=1  also measure the level-synchronous engine (exact BFS order);
#   ANALYZE  a prebuilt `analyze` example binary; by default it is built
#            here with cargo.
#
# For a machine without Rust (e.g. 16 cores), build a static binary here
# and copy it there with this script and tests/data/mcc (or set MCC_DIR):
#   RUSTFLAGS="-C target-feature=+crt-static" cargo build --release \
#     -p mcl-net --example analyze --target x86_64-unknown-linux-gnu
#   # -> target/x86_64-unknown-linux-gnu/release/examples/analyze (static
#   #    glibc, glibc's allocator: the one the numbers here were taken with)
# or, with musl (`rustup target add x86_64-unknown-linux-musl` and
# `apt-get install musl-tools`: criterion, a dev-dependency, builds C code):
#   cargo build --release -p mcl-net --example analyze \
#     --target x86_64-unknown-linux-musl
# then on the other machine:
#   ANALYZE=./analyze MCC_DIR=./mcc THREADS="1 2 4 8 16" EXACT=1 \
#     ./explore-threads.sh
#
# One thread runs the sequential BFS; more threads run the unordered engine
# (`Options::exact_order = false`, `mcl-net/src/explore/unordered.rs`: one
# shared lock-free table, work stealing); EXACT=1 adds the level-synchronous
# `parallel.rs`. On a machine shared with other work, compare the "cpu"
# column (total work) rather than the wall times.
# Rates are states / the example's own wall-clock timer of the exploration
# (PNML parsing excluded); "cpu" is the process's user + system time. Every
# run must find the same state and edge counts, or the script says so. The
# machine (cores, model, load average before and after) is printed first:
# quote it with the numbers.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
MCC_DIR="${MCC_DIR:-$ROOT/tests/data/mcc}"
RUNS="${RUNS:-3}"
THREADS="${THREADS:-1 2 4 8 16}"
EXACT="${EXACT:-0}"
NETS=("$@")
if [ ${#NETS[@]} -eq 0 ]; then
  NETS=(SharedMemory-PT-000010 Kanban-PT-00005 FMS-PT-00005)
fi

if [ -z "${ANALYZE:-}" ]; then
  command -v cargo >/dev/null || { echo "error: cargo not found (or give ANALYZE=path)" >&2; exit 1; }
  (cd "$ROOT" && cargo build --release -q -p mcl-net --example analyze)
  TARGET="$(cd "$ROOT" && cargo metadata --format-version 1 --no-deps | sed -n 's/.*"target_directory":"\([^"]*\)".*/\1/p')"
  ANALYZE="$TARGET/release/examples/analyze"
fi
[ -x "$ANALYZE" ] || { echo "error: $ANALYZE is not an executable" >&2; exit 1; }

WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT

echo "machine: $(nproc) cores, $(sed -n 's/^model name[[:space:]]*: //p' /proc/cpuinfo | head -1)"
echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "best of $RUNS runs; threads: $THREADS"

# run_one NET THREADS MODE: prints "states edges wall cpu" of the best run.
run_one() {
  local pnml="$1" n="$2" mode="$3" best_wall="" best_cpu="" states="" edges="" flags=""
  [ "$mode" = unordered ] && flags="--unordered"
  for _ in $(seq "$RUNS"); do
    local TIMEFORMAT='%U %S' t
    t=$({ time "$ANALYZE" "$pnml" --plain --dead-examples 0 --threads "$n" $flags > "$WORK/out.json" 2> /dev/null; } 2>&1 | tail -1)
    local cpu wall
    cpu=$(awk -v t="$t" 'BEGIN { split(t, a, " "); print a[1] + a[2] }')
    wall=$(sed -n 's/^ *"seconds": \([0-9.e+-]*\),*$/\1/p' "$WORK/out.json")
    states=$(sed -n 's/^ *"states": \([0-9]*\),*$/\1/p' "$WORK/out.json")
    edges=$(sed -n 's/^ *"edges": \([0-9]*\),*$/\1/p' "$WORK/out.json")
    best_wall=$(awk -v a="$best_wall" -v b="$wall" 'BEGIN { print (a == "" || b < a) ? b : a }')
    best_cpu=$(awk -v a="$best_cpu" -v b="$cpu" 'BEGIN { print (a == "" || b < a) ? b : a }')
  done
  echo "$states $edges $best_wall $best_cpu"
}

printf '%-24s %-10s %7s %10s %11s %8s %8s %12s %8s\n' net engine threads states edges wall cpu "states/s" speed-up
for net in "${NETS[@]}"; do
  pnml="$MCC_DIR/$net.pnml"
  [ -f "$pnml" ] || { echo "$net: $pnml not found" >&2; continue; }
  modes=(unordered)
  [ "$EXACT" = 1 ] && modes+=(exact)
  base="" ref=""
  for mode in "${modes[@]}"; do
    for n in $THREADS; do
      [ "$mode" = exact ] && [ "$n" = 1 ] && continue
      read -r states edges wall cpu < <(run_one "$pnml" "$n" "$mode")
      [ -z "$ref" ] && ref="$states $edges"
      [ "$ref" != "$states $edges" ] && echo "warning: $net $mode $n threads: $states states $edges edges, expected $ref" >&2
      [ -z "$base" ] && base="$wall"
      engine="$mode"
      [ "$n" = 1 ] && engine="sequential"
      awk -v net="$net" -v e="$engine" -v n="$n" -v s="$states" -v ed="$edges" -v w="$wall" -v c="$cpu" -v b="$base" 'BEGIN {
        printf "%-24s %-10s %7d %10d %11d %8.2f %8.2f %12.0f %7.2fx\n", net, e, n, s, ed, w, c, s / w, b / w }'
    done
  done
done
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
