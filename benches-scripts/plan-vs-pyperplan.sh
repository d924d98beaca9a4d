#!/usr/bin/env bash
# mcl-plan vs pyperplan on the same generated STRIPS problems, in the same run.
# Both sides are timed in-process: parse + ground + search, no interpreter or
# process start-up (ours: best of RUNS; pyperplan: best of PYRUNS). Each pair
# runs the same algorithm: BFS, A* with h_max, A* with h_add.
#
#   python3 -m pip install pyperplan
#   RUNS=5 PYRUNS=1 benches-scripts/plan-vs-pyperplan.sh
set -euo pipefail
cd "$(dirname "$0")/.."
RUNS=${RUNS:-5}
PYRUNS=${PYRUNS:-1}
python3 -c "import pyperplan" 2>/dev/null || { echo "pyperplan is missing: python3 -m pip install pyperplan" >&2; exit 2; }
cargo build --release -q -p mcl-plan --bins --examples
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
GEN=target/release/mcl-plan-gen
OURS=target/release/examples/plan_time
ORACLE=mcl-plan/tests/pyperplan_oracle.py
INSTANCES=(
  "gripper-8:gripper 8"
  "blocks-8:blocksworld 8 11"
  "blocks-9:blocksworld 9 4"
  "logistics-3-2-1-4:logistics 3 2 1 4 9"
  "miconic-6-5:miconic 6 5 2"
  "miconic-8-6:miconic 8 6 3"
)
PAIRS=("bfs:bfs none" "astar-hmax:astar hmax" "astar-hadd:astar hadd")
echo "| problem | search | cost mcl-plan | cost pyperplan | states (mcl-plan) | mcl-plan s | pyperplan s | speed-up |"
echo "|---|---|---:|---:|---:|---:|---:|---:|"
for inst in "${INSTANCES[@]}"; do
  name=${inst%%:*}
  # shellcheck disable=SC2086
  $GEN "$W/$name" ${inst#*:} >/dev/null
  d="$W/$name/domain.pddl"; p="$W/$name/problem.pddl"
  for pair in "${PAIRS[@]}"; do
    ours_alg=${pair%%:*}
    # shellcheck disable=SC2086
    set -- ${pair#*:}
    ours=$($OURS "$d" "$p" "$ours_alg" "$RUNS")
    theirs=""
    for _ in $(seq "$PYRUNS"); do theirs="$theirs$(python3 "$ORACLE" solve "$1" "$2" "$d" "$p")"$'\n'; done
    python3 - "$name" "$ours_alg" "$ours" "$theirs" <<'PY'
import json, sys
name, alg, ours, theirs = sys.argv[1], sys.argv[2], json.loads(sys.argv[3]), [json.loads(l) for l in sys.argv[4].splitlines() if l.strip()]
t = min(x["seconds"] for x in theirs)
print(f"| {name} | {alg} | {ours['cost']} | {theirs[0]['cost']} | {ours['states']:,} | {ours['seconds']:.4f} | {t:.3f} | {t / ours['seconds']:.0f}x |")
PY
  done
done
