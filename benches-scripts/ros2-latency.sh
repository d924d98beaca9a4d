#!/usr/bin/env bash
# Event-to-action latency through the ROS 2 bridge on loopback (`mcl run
# --ros2` against a Cyclone DDS vehicle in Python), and through the TCP AAC
# (`mcl run --aac` against clients/python/mcl_aac.py) in the same run, with
# the same mission and binary (benches-scripts/ros2-latency.py).
#
# Usage: benches-scripts/ros2-latency.sh [ROUNDS]   (default 500)
# Needs `pip install cyclonedds`. Builds the release binary unless MCL names
# one (MCL=target/debug/mcl). Numbers go to BENCHMARKS.md by hand.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
if [ -z "${MCL:-}" ]; then
    cargo build --quiet --release --bin mcl
    MCL=target/release/mcl
fi
python3 benches-scripts/ros2-latency.py "$MCL" "${1:-500}"
