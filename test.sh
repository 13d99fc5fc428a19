#!/usr/bin/env bash
# Run every test of poser: sets up the pinned Python environment (bpy, mitsuba) first, then
# lints and tests the Python back-end code, then runs the Rust test suite, which renders with
# the real Mitsuba and Cycles.
set -euo pipefail
cd "$(dirname "$0")"
backends/setup.sh
export POSER_PYTHON="$PWD/.venv/bin/python"
if [ -d backends ] && ls backends/*/*.py >/dev/null 2>&1; then
  .venv/bin/ruff check backends
  .venv/bin/python -m pytest -q backends
fi
cargo test --release --locked --features backends
# Each fuzz target for a minute, when a nightly toolchain is available (fuzz/run.sh says so and
# skips otherwise; the stable replay of the corpus ran above as `fuzz_replay`).
fuzz/run.sh 60
