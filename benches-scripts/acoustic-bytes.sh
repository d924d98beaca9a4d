#!/usr/bin/env bash
# Bytes on the wire per coordinated mission: the JSON of the TCP link
# against the compact encoding of docs/acoustic.md.
#
# Usage: benches-scripts/acoustic-bytes.sh [VEHICLES]
#   VEHICLES: the size of the generated fleet (default 6). Environment: MCL
#   (the binary; default target/release/mcl, built here), LOSS (the loss
#   probability of the lossy run; default 0.3), SEED (default 1). Needs
#   python3.
#
# For examples/auv-asc.mcl (with examples/scenarios/auv-asc.toml) and a
# generated fleet of VEHICLES missions (each `Void() : s ; Goto( ... ) : go ;
# Surface()`, the `go` of each after the `s` of the previous one, and at most
# two `go`s at once: a mutex with a single holder), prints
#   * the link report's frame size and its bound on messages per run;
#   * a dry run over `--link acoustic:bitrate=80,loss=0,delay=2`: the
#     messages sent, their bytes as JSON (the TCP link's bodies) and in the
#     compact encoding (data frames; with the acknowledgements);
#   * the same over a lossy link (LOSS): frames, retransmissions, losses and
#     bytes on the air.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
N="${1:-6}"
LOSS="${LOSS:-0.3}"
SEED="${SEED:-1}"
if [ -z "${MCL:-}" ]; then
  (cd "$ROOT" && cargo build --release --quiet)
  MCL="$ROOT/target/release/mcl"
fi
WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT

# The generated fleet.
cp "$ROOT/examples/vehicle.mcl" "$WORK/"
{
  echo 'import "vehicle.mcl";'
  for i in $(seq 1 "$N"); do
    echo "mission : v$i { Void() : s ; Goto( [$((i * 100)), 0] ) : go ; Surface() }"
  done
  echo 'constraints {'
  for i in $(seq 2 "$N"); do
    echo "    order { v$((i - 1)):s, v$i:go }"
  done
  gos=$(for i in $(seq 1 "$N"); do printf 'v%s:go, ' "$i"; done)
  echo "    mutex { ${gos%, } } = 2"
  echo '}'
} > "$WORK/fleet.mcl"

measure() { # NAME FILE SCENARIO...
  local name="$1" file="$2"
  shift 2
  "$MCL" compile --link-report --format json "$file" > "$WORK/report.json" 2> /dev/null || true
  "$MCL" run --mock --virtual-time -q "$file" "$@" --seed "$SEED" \
    --link "acoustic:bitrate=80,loss=0,delay=2" --trace "$WORK/clean.jsonl" 2> /dev/null || true
  "$MCL" run --mock --virtual-time -q "$file" "$@" --seed "$SEED" \
    --link "acoustic:bitrate=80,loss=$LOSS,delay=2" --trace "$WORK/lossy.jsonl" 2> /dev/null || true
  python3 - "$name" "$WORK/report.json" "$WORK/clean.jsonl" "$WORK/lossy.jsonl" "$LOSS" <<'PY'
import json, sys
name, report, clean, lossy, loss = sys.argv[1:]
r = json.load(open(report))
bound = [m["messages"] for m in r["missions"]]
total = "unbounded" if any(b["bound"] != "bounded" for b in bound) else sum(b["max"] for b in bound)
def stats(path):
    recs = [json.loads(l) for l in open(path)]
    send = [x for x in recs if x["kind"] == "link_send"]
    data = [x for x in send if x["what"] != "ack"]
    first = [x for x in data if x["attempt"] == 1]
    out = [x for x in recs if x["kind"] == "outcome"]
    return dict(messages=len(first), json=sum(x["json_bytes"] for x in first),
                compact=sum(x["bytes"] for x in first), air=sum(x["bytes"] for x in send),
                frames=len(send), resent=sum(1 for x in data if x["attempt"] > 1),
                lost=sum(1 for x in recs if x["kind"] == "link_lost"),
                ok=all(x["result"] == "ok" for x in out), t=max((x["t"] for x in recs), default=0))
c, l = stats(clean), stats(lossy)
print(f"{name}: frame {r['frame_bits']} bits = {r['frame_bytes']} bytes; at most {total} messages per run")
print(f"  lossless: {c['messages']} messages, JSON {c['json']} B, compact {c['compact']} B "
      f"({c['json'] / max(c['compact'], 1):.0f}x smaller), with acks {c['air']} B; missions ok: {c['ok']}, ended at {c['t']:.0f} s")
print(f"  loss {loss}: {l['frames']} frames ({l['resent']} retransmissions, {l['lost']} lost), {l['air']} B on the air; "
      f"missions ok: {l['ok']}, ended at {l['t']:.0f} s")
PY
}

measure "examples/auv-asc.mcl" "$ROOT/examples/auv-asc.mcl" --scenario "$ROOT/examples/scenarios/auv-asc.toml"
measure "fleet of $N" "$WORK/fleet.mcl"
