#!/usr/bin/env bash
# Compares mcl-net's explicit-state explorer with SPIN on the large MCC nets.
#
# Usage: benches-scripts/spin-compare.sh [NET ...]
#   NET defaults to the three large nets of shared/data/mcc. Environment:
#   MCC_DIR (default tests/data/mcc, a copy of shared/data/mcc), RUNS (runs per
#   tool and net, best time kept; default 3), THREADS (mcl-net worker
#   threads; default 1), ANALYZE and TO_PROMELA (prebuilt `analyze` and
#   `to_promela` example binaries, e.g. copied to a quiet machine: `cargo build
#   --release -p mcl-net --example analyze --example to_promela`, then
#   target/release/examples/; with both given, cargo is not needed), SYMBOLIC
#   (a prebuilt `symbolic` example binary: adds the columns of
#   `--method symbolic`, decision diagrams on one thread; built here with
#   the others when cargo is used; SYMBOLIC=none leaves them out).
#   Needs spin and gcc (apt-get install -y spin gcc).
#
# For each net: the PNML is written as Promela by the `to_promela` example
# (one variable per place, one atomic guarded update per transition), pan is
# compiled with -DSAFETY -DNOREDUCE and run with a depth limit large enough
# not to truncate the search; mcl-net's `analyze` example (release build)
# explores the same net with the plain P/T semantics. Both rates are each
# tool's own timing of its search (parsing and compilation excluded).
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
MCC_DIR="${MCC_DIR:-$ROOT/tests/data/mcc}"
RUNS="${RUNS:-3}"
THREADS="${THREADS:-1}"
NETS=("$@")
if [ ${#NETS[@]} -eq 0 ]; then
  NETS=(SharedMemory-PT-000010 Kanban-PT-00005 FMS-PT-00005)
fi
for tool in spin gcc; do
  command -v "$tool" >/dev/null || { echo "error: $tool not found (apt-get install -y spin gcc)" >&2; exit 1; }
done

cd "$ROOT"
if [ -z "${ANALYZE:-}" ] || [ -z "${TO_PROMELA:-}" ]; then
  command -v cargo >/dev/null || { echo "error: cargo not found (or give ANALYZE= and TO_PROMELA=)" >&2; exit 1; }
  cargo build --release -q -p mcl-net --example analyze --example to_promela --example symbolic
  TARGET="$(cargo metadata --format-version 1 --no-deps | sed -n 's/.*"target_directory":"\([^"]*\)".*/\1/p')"
  ANALYZE="${ANALYZE:-$TARGET/release/examples/analyze}"
  TO_PROMELA="${TO_PROMELA:-$TARGET/release/examples/to_promela}"
  SYMBOLIC="${SYMBOLIC:-$TARGET/release/examples/symbolic}"
fi
SYMBOLIC="${SYMBOLIC:-none}"
if [ "$SYMBOLIC" != none ] && [ ! -x "$SYMBOLIC" ]; then
  echo "error: $SYMBOLIC is not an executable" >&2
  exit 1
fi
for bin in "$ANALYZE" "$TO_PROMELA"; do
  [ -x "$bin" ] || { echo "error: $bin is not an executable" >&2; exit 1; }
done

WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT

# cpu_seconds CMD...: runs CMD, prints its user+system CPU seconds.
cpu_seconds() {
  local TIMEFORMAT='%U %S' t
  t=$({ time "$@" > /dev/null 2>&1; } 2>&1 | tail -1) || true
  awk -v t="$t" 'BEGIN { split(t, a, " "); print a[1] + a[2] }'
}
min() { awk -v a="$1" -v b="$2" 'BEGIN { print (a == "" || b < a) ? b : a }'; }

echo "best of $RUNS runs; mcl-net threads: $THREADS"
echo "rate = states / time; wall: each tool's own timer of its search; cpu: user+system of the process"
printf '%-24s %10s | %9s %9s %12s %12s | %9s %9s %12s %12s | %6s %6s | %9s %9s %8s %8s\n' \
  net states "spin wall" "spin cpu" "spin st/s" "spin st/cpu" "mcl wall" "mcl cpu" "mcl st/s" "mcl st/cpu" "x wall" "x cpu" \
  "sym wall" "sym cpu" "x wall" "x cpu"
for net in "${NETS[@]}"; do
  pnml="$MCC_DIR/$net.pnml"
  [ -f "$pnml" ] || { echo "$net: $pnml not found" >&2; continue; }
  dir="$WORK/$net"
  mkdir -p "$dir"
  "$TO_PROMELA" "$pnml" > "$dir/net.pml"
  (
    cd "$dir"
    spin -a net.pml > /dev/null
    gcc -O2 -DSAFETY -DNOREDUCE -DMEMLIM=16384 -o pan pan.c 2> /dev/null
  )
  spin_wall="" spin_cpu="" mcl_wall="" mcl_cpu="" sym_wall="" sym_cpu="" sym_states=""
  for _ in $(seq "$RUNS"); do
    # -m: DFS depth limit (the default, 10000, silently truncates the search);
    # -w26: 2^26 hash slots; -E: do not report invalid end states.
    cpu=$(cd "$dir" && cpu_seconds sh -c './pan -m100000000 -w26 -E > pan.out 2>&1')
    spin_cpu=$(min "$spin_cpu" "$cpu")
    if grep -q "max search depth too small" "$dir/pan.out"; then
      echo "warning: $net: pan reached its depth limit; the SPIN count is truncated" >&2
    fi
    spin_states=$(sed -n 's/^ *\([0-9.e+]*\) states, stored.*/\1/p' "$dir/pan.out" | head -1)
    t=$(sed -n 's/^pan: elapsed time \([0-9.e+-]*\) seconds.*/\1/p' "$dir/pan.out" | head -1)
    spin_wall=$(min "$spin_wall" "$t")

    cpu=$(cpu_seconds sh -c "'$ANALYZE' '$pnml' --plain --dead-examples 0 --threads '$THREADS' > '$dir/mcl.json'")
    mcl_cpu=$(min "$mcl_cpu" "$cpu")
    mcl_states=$(sed -n 's/^ *"states": \([0-9]*\),*$/\1/p' "$dir/mcl.json")
    t=$(sed -n 's/^ *"seconds": \([0-9.e+-]*\),*$/\1/p' "$dir/mcl.json")
    mcl_wall=$(min "$mcl_wall" "$t")

    # Decision diagrams (`--method symbolic`): own timer and whole process.
    if [ "$SYMBOLIC" != none ]; then
      cpu=$(cpu_seconds sh -c "'$SYMBOLIC' '$pnml' > '$dir/sym.out'")
      sym_cpu=$(min "$sym_cpu" "$cpu")
      line=$(tail -1 "$dir/sym.out")
      sym_states=$(echo "$line" | awk '{ print $2 }')
      t=$(echo "$line" | awk '{ print $NF }')
      sym_wall=$(min "$sym_wall" "$t")
    fi
  done
  if [ "$spin_states" != "$mcl_states" ]; then
    echo "warning: $net: SPIN stored $spin_states states, mcl-net $mcl_states" >&2
  fi
  if [ "$SYMBOLIC" != none ] && [ "$sym_states" != "$mcl_states" ]; then
    echo "warning: $net: symbolic found $sym_states states, explicit $mcl_states" >&2
  fi
  awk -v n="$net" -v s="$mcl_states" -v sw="$spin_wall" -v sc="$spin_cpu" -v mw="$mcl_wall" -v mc="$mcl_cpu" \
    -v yw="$sym_wall" -v yc="$sym_cpu" 'BEGIN {
    printf "%-24s %10d | %9.2f %9.2f %12.0f %12.0f | %9.2f %9.2f %12.0f %12.0f | %5.1fx %5.1fx",
      n, s, sw, sc, s / sw, s / sc, mw, mc, s / mw, s / mc, sw / mw, sc / mc
    if (yw != "" && yw > 0 && yc > 0) printf " | %9.4f %9.3f %7.0fx %7.0fx", yw, yc, sw / yw, sc / yc
    printf "\n" }'
done
