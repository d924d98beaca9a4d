#!/usr/bin/env bash
# Edit-to-diagnostics latency and memory of `mcl lsp` (BENCHMARKS.md, "mcl-lsp").
# Builds the release binary, then runs the in-process and end-to-end parts.
set -euo pipefail
cd "$(dirname "$0")/../.."
cargo build --release --bin mcl
cargo bench -p mcl-lsp --bench edit_latency -- --server "$PWD/target/release/mcl"
