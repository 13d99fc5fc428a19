#!/usr/bin/env bash
# Run every test of poser: sets up the pinned Python environment (bpy, mitsuba) first, then
# lints and tests the Python back-end code, then runs the Rust test suite, which renders with
# the real Mitsuba and Cycles.
set -euo pipefail
cd "$(dirname "$0")"
backends/setup.sh
export POSER_PYTHON="$PWD/.venv/bin/python"
# The Python module (crates/poser-py): build the abi3 wheel with maturin, install it into .venv
# (the Blender add-on's tests use it in-process), and the binary its tests compare against.
rm -rf target/wheels
.venv/bin/maturin build --release --locked --quiet -m crates/poser-py/Cargo.toml \
  -o target/wheels -i .venv/bin/python
.venv/bin/pip install --quiet --force-reinstall --no-deps target/wheels/poser-*.whl
cargo build --release --locked --features backends --bin poser
.venv/bin/ruff check backends crates/poser-py
OPENCV_IO_ENABLE_OPENEXR=1 POSER_BIN="$PWD/target/release/poser" \
  .venv/bin/python -m pytest -q -p no:cacheprovider backends crates/poser-py/tests
cargo test --release --locked --features backends
# Each fuzz target for 30 s, when a nightly toolchain is available (fuzz/run.sh says so and
# skips otherwise; the stable replay of the corpus ran above as `fuzz_replay`).
fuzz/run.sh 30
