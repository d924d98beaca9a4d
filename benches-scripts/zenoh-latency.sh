#!/usr/bin/env bash
# Coordination message latency on loopback: the Zenoh transport
# (mcl-zenoh, two Zenoh peer sessions as two processes would have) against
# the TCP transport (mcl-runtime's authenticated link), in the same run
# (mcl-zenoh/benches/latency.rs). One message at a time from `a` to `b`:
# send → received, and send → acknowledged end to end (what a sender waits
# for before it forgets the message). Percentiles in microseconds, after 50
# messages of warm-up.
#
# Usage: benches-scripts/zenoh-latency.sh [MESSAGES]   (default 1000)
# Optimised build (cargo bench). Run it on a quiet machine; numbers go to
# BENCHMARKS.md by hand.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
cargo bench --quiet -p mcl-zenoh --bench latency -- "${1:-1000}"
