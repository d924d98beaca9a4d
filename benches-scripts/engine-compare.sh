#!/usr/bin/env bash
# Compares the player's firings per second and the explorer's states per
# second of two revisions, in one run, alternating the two builds so that
# both see the same machine load.
#
# Usage: benches-scripts/engine-compare.sh BASE_REV [NEW_REV]
#   NEW_REV defaults to the work tree. Environment: ROUNDS (alternations,
#   default 5), MCC_DIR (default tests/data/mcc, a copy of shared/data/mcc),
#   BASE_DIR (a checkout of BASE_REV with its release builds, reused if
#   given; else a git worktree is made in $TMPDIR). BASE_PLAYER, BASE_ANALYZE,
#   NEW_PLAYER, NEW_ANALYZE: prebuilt binaries (the player bench executable
#   and the `analyze` example), which skip checkouts and builds.
#
# Player: `cargo bench -p mcl-runtime --bench player` restricted to
# `player/virtual`, whose summary prints the firings per second of a whole
# mission (median of 15 runs, wall and thread CPU). Explorer: the `analyze`
# example of mcl-net (release) on the three large MCC nets with the MCL
# semantics off (`--plain`, the oracle's counts) and on (`--mcl`), printing
# its own states per second. Medians over the rounds are printed at the end.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BASE_REV="${1:?usage: $0 BASE_REV [NEW_REV]}"
NEW_REV="${2:-}"
ROUNDS="${ROUNDS:-5}"
MCC_DIR="${MCC_DIR:-$ROOT/tests/data/mcc}"
NETS=(SharedMemory-PT-000010 Kanban-PT-00005 FMS-PT-00005)
TMP="${TMPDIR:-/tmp}/mcl-engine-compare"
mkdir -p "$TMP"

checkout() { # REV DIR
  if [ ! -d "$2" ]; then git -C "$ROOT" worktree add -q --detach "$2" "$1"; fi
}
build() { # DIR -> prints the player bench binary
  (cd "$1" && cargo build --release -q -p mcl-net --example analyze >&2 &&
    cargo bench -q -p mcl-runtime --bench player --no-run --message-format=json 2>/dev/null |
    sed -n 's/.*"executable":"\([^"]*player-[^"]*\)".*/\1/p' | tail -1)
}

declare -A PLAYER ANALYZE
if [ -n "${BASE_PLAYER:-}" ]; then
  PLAYER[base]="$BASE_PLAYER"; ANALYZE[base]="$BASE_ANALYZE"
  PLAYER[new]="$NEW_PLAYER"; ANALYZE[new]="$NEW_ANALYZE"
else
  BASE="${BASE_DIR:-$TMP/base}"
  checkout "$BASE_REV" "$BASE"
  NEW="$ROOT"
  if [ -n "$NEW_REV" ]; then NEW="$TMP/new"; checkout "$NEW_REV" "$NEW"; fi
  for side in base new; do
    dir=$([ $side = base ] && echo "$BASE" || echo "$NEW")
    PLAYER[$side]="$(build "$dir")"
    ANALYZE[$side]="$dir/target/release/examples/analyze"
    echo "$side: $(git -C "$dir" rev-parse --short HEAD)$(git -C "$dir" diff --quiet HEAD || echo ' (+ work tree)')" >&2
  done
fi

OUT="$TMP/results.tsv"
: > "$OUT"
for r in $(seq 1 "$ROUNDS"); do
  for side in base new; do
    line=$(cd "$ROOT/mcl-runtime" && "${PLAYER[$side]}" --bench player/virtual 2>/dev/null | grep '^player (incremental)')
    wall=$(echo "$line" | awk '{print $3}')
    cpu=$(echo "$line" | awk '{print $6}')
    printf 'player\t%s\t%s\t%s\n' "$side" "$wall" "$cpu" >> "$OUT"
    for n in "${NETS[@]}"; do
      for sem in plain mcl; do
        sps=$("${ANALYZE[$side]}" "$MCC_DIR/$n.pnml" --$sem | sed -n 's/.*"states_per_second": *\([0-9.e+]*\).*/\1/p')
        printf '%s/%s\t%s\t%s\t\n' "$n" "$sem" "$side" "$sps" >> "$OUT"
      done
    done
  done
  echo "round $r done" >&2
done

echo "| measure | base (median) | new (median) | change |"
echo "|---|---:|---:|---:|"
median() { sort -g | awk '{a[NR]=$1} END {print (NR%2) ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2}'; }
for key in player "${NETS[@]/%//plain}" "${NETS[@]/%//mcl}"; do
  b=$(awk -F'\t' -v k="$key" '$1==k && $2=="base" {print $3}' "$OUT" | median)
  n=$(awk -F'\t' -v k="$key" '$1==k && $2=="new" {print $3}' "$OUT" | median)
  label=$([ "$key" = player ] && echo "player, firings/s (wall)" || echo "$key, states/s")
  awk -v l="$label" -v b="$b" -v n="$n" 'BEGIN { printf "| %s | %.0f | %.0f | %+.1f %% |\n", l, b, n, (n - b) / b * 100 }'
done
b=$(awk -F'\t' '$1=="player" && $2=="base" {print $4}' "$OUT" | median)
n=$(awk -F'\t' '$1=="player" && $2=="new" {print $4}' "$OUT" | median)
awk -v b="$b" -v n="$n" 'BEGIN { printf "| player, firings/s (CPU) | %.0f | %.0f | %+.1f %% |\n", b, n, (n - b) / b * 100 }'
