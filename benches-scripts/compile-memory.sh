#!/usr/bin/env bash
# Peak memory and time of `mcl compile` on generated missions of many calls.
#
# Usage: benches-scripts/compile-memory.sh [CALLS ...]
#   CALLS defaults to 100000 1000000 (multiples of 10). Environment: MCL (the
#   binary to measure; default: target/release/mcl, built here), RUNS (runs
#   per size, the lowest peak and time kept; default 1), WORK (a directory
#   for the missions and their PNML; default a temporary one, removed at the
#   end). Needs GNU time (/usr/bin/time: apt-get install -y time) and awk.
#
# The mission (about 16 bytes per call, so that a million calls stay under
# the 16 MiB limit on sources) imports examples/vehicle.mcl and repeats a
# block of ten calls mixing a sequence, try-catch, parallel-or and a
# monitor:
#
#   try{Goto(1);parallel{Depth(0,0)}or{TakeImages()};Goto(2)}catch{Surface()};
#   monitor{Goto(3);Depth(0,1)}condition(Alarm())do{Surface()};Stop();
#
# Each run is `mcl compile mission.mcl -o mission.pnml` under
# `/usr/bin/time -v`: peak resident set size (whole process), wall clock,
# user + system CPU. The PNML (about 7.8 KB per call) is written to WORK
# and removed after each run.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
RUNS="${RUNS:-1}"
SIZES=("$@")
if [ ${#SIZES[@]} -eq 0 ]; then
  SIZES=(100000 1000000)
fi
[ -x /usr/bin/time ] || { echo "error: /usr/bin/time not found (apt-get install -y time)" >&2; exit 1; }

cd "$ROOT"
if [ -z "${MCL:-}" ]; then
  cargo build --release -q --bin mcl
  TARGET="$(cargo metadata --format-version 1 --no-deps | sed -n 's/.*"target_directory":"\([^"]*\)".*/\1/p')"
  MCL="$TARGET/release/mcl"
fi

if [ -z "${WORK:-}" ]; then
  WORK="$(mktemp -d)"
  trap 'rm -rf "$WORK"' EXIT
fi
mkdir -p "$WORK"
cp examples/vehicle.mcl "$WORK/vehicle.mcl"

# mission CALLS FILE: the generated mission of CALLS calls.
mission() {
  awk -v n=$(($1 / 10)) 'BEGIN {
    print "import \"vehicle.mcl\";"; print "mission {";
    for (b = 0; b < n; b++) {
      d = b % 50;
      printf "try{Goto(%d);parallel{Depth(%d,0)}or{TakeImages()};Goto(%d)}catch{Surface()};monitor{Goto(%d);Depth(%d,1)}condition(Alarm())do{Surface()};Stop()%s\n", 10*b+1, d, 10*b+2, 10*b+3, d, (b + 1 < n ? ";" : "");
    }
    print "}";
  }' > "$2"
}

echo "binary: $MCL; best of $RUNS run(s)"
printf '%10s %12s %12s %14s %10s %10s %10s %s\n' calls "source B" "PNML B" "peak RSS KiB" "B/call" "wall s" "cpu s" nodes
for calls in "${SIZES[@]}"; do
  src="$WORK/m$calls.mcl"
  out="$WORK/m$calls.pnml"
  mission "$calls" "$src"
  best_rss="" best_wall="" best_cpu="" size="" nodes=""
  for _ in $(seq "$RUNS"); do
    /usr/bin/time -v -o "$WORK/time.txt" "$MCL" compile "$src" -o "$out" 2> "$WORK/err.txt" \
      || { cat "$WORK/err.txt" >&2; exit 1; }
    rss=$(awk -F': ' '/Maximum resident set size/ { print $2 }' "$WORK/time.txt")
    wall=$(awk -F': ' '/Elapsed \(wall clock\)/ { n = split($2, a, ":"); s = 0; for (i = 1; i <= n; i++) s = s * 60 + a[i]; print s }' "$WORK/time.txt")
    cpu=$(awk -F': ' '/User time/ { u = $2 } /System time/ { s = $2 } END { print u + s }' "$WORK/time.txt")
    size=$(stat -c %s "$out")
    nodes=$(sed -n 's/.*(\(.*\))$/\1/p' "$WORK/err.txt")
    rm -f "$out"
    best_rss=$(awk -v a="$best_rss" -v b="$rss" 'BEGIN { print (a == "" || b < a) ? b : a }')
    best_wall=$(awk -v a="$best_wall" -v b="$wall" 'BEGIN { print (a == "" || b < a) ? b : a }')
    best_cpu=$(awk -v a="$best_cpu" -v b="$cpu" 'BEGIN { print (a == "" || b < a) ? b : a }')
  done
  per_call=$(awk -v r="$best_rss" -v c="$calls" 'BEGIN { printf "%.0f", r * 1024 / c }')
  printf '%10s %12s %12s %14s %10s %10s %10s %s\n' "$calls" "$(stat -c %s "$src")" "$size" "$best_rss" "$per_call" "$best_wall" "$best_cpu" "$nodes"
  rm -f "$src"
done
