#!/usr/bin/env bash
# Run every test of poser, in its two tiers, each timed:
#  1. the fast tier, plain `cargo test`: unit, doc and the `suite` integration tests, no Python;
#  2. the full tier: sets up the pinned Python environment (bpy, mitsuba, pycolmap, OpenCV,
#     Chromium), builds the Python module's wheel, lints and tests the Python code, then runs
#     the `backends` integration tests, which render with the real Mitsuba and Cycles.
# POSER_FUZZ_SECONDS=N also fuzzes each cargo-fuzz target for N s (nightly; docs/fuzzing.md). The
# stable replay of the fuzz corpus runs in tier 1 either way. Both tiers build with the one `dev`
# profile (optimised, with overflow checks; Cargo.toml), so the dependencies compile once.
set -euo pipefail
cd "$(dirname "$0")"
step() { printf '\n== %s (at %d s)\n' "$1" "$SECONDS"; }
SECONDS=0

# The full tier's environment (apt, npm, pip: mostly downloads and unpacking) is set up in the
# background while the fast tier compiles and runs; its output is shown when the full tier
# starts. A failed fast tier stops it.
setup_log="$(mktemp)"
backends/setup.sh > "$setup_log" 2>&1 &
setup_pid=$!
stop_setup() {
  if [ -n "$setup_pid" ]; then pkill -P "$setup_pid" 2>/dev/null || true; kill "$setup_pid" 2>/dev/null || true; fi
  rm -f "$setup_log"
}
trap stop_setup EXIT

# A fresh checkout (CI's clean clone) has no incremental state to reuse: compiling without
# it skips writing that state (the poser crate is built three times: library, unit tests,
# binary). A checkout that already builds incrementally keeps doing so.
[ -d target/debug/incremental ] || export CARGO_INCREMENTAL=0

step "fast tier: build"
time cargo test --locked --no-run
step "fast tier: plain cargo test"
time cargo test --locked

step "full tier: Python environment (set up in the background since the start)"
if ! wait "$setup_pid"; then
  cat "$setup_log"
  echo "error: backends/setup.sh failed (its output above)" >&2
  exit 1
fi
cat "$setup_log"
setup_pid=""
export POSER_PYTHON="$PWD/.venv/bin/python"
# The Python module (crates/poser-py): build the abi3 wheel with maturin, install it into .venv
# (the Blender add-on's tests use it in-process). Then the full tier's test binary, which also
# builds the `poser` binary the Python tests compare against (target/debug/poser).
step "full tier: the Python module's wheel, the binary and the backends tests"
rm -rf target/wheels
.venv/bin/maturin build --profile dev --locked --quiet \
  -m crates/poser-py/Cargo.toml -o target/wheels -i .venv/bin/python
.venv/bin/pip install --quiet --force-reinstall --no-deps target/wheels/poser-*.whl
time cargo test --locked --test backends --no-run
step "full tier: Python tests (in the background) and cargo test --test backends"
.venv/bin/ruff check backends crates/poser-py
# The Python tests (one process, mostly one core) run beside the backends tests; their output
# is shown, and their result checked, when those finish.
pytest_log="$(mktemp)"
OPENCV_IO_ENABLE_OPENEXR=1 POSER_BIN="$PWD/target/debug/poser" \
  .venv/bin/python -m pytest -q -p no:cacheprovider backends crates/poser-py/tests \
  > "$pytest_log" 2>&1 &
pytest_pid=$!
# Four tests at a time on two cores: most of these wait on single-threaded work (Python and
# Blender start-up, scene building, COLMAP's matching), so two at a time left a core idle
# (measured: 1.07 cores busy on average over the run).
backends_status=0
time cargo test --locked --test backends -- --test-threads 4 || backends_status=$?
step "full tier: the Python tests' output"
pytest_status=0
wait "$pytest_pid" || pytest_status=$?
cat "$pytest_log"
rm -f "$pytest_log"
if [ "$pytest_status" -ne 0 ] || [ "$backends_status" -ne 0 ]; then
  echo "error: the full tier failed (pytest exit $pytest_status, cargo test --test backends exit $backends_status)" >&2
  exit 1
fi

if [ -n "${POSER_FUZZ_SECONDS:-}" ]; then
  step "fuzzing each target for $POSER_FUZZ_SECONDS s"
  fuzz/run.sh "$POSER_FUZZ_SECONDS"
fi
step "all tests passed"
