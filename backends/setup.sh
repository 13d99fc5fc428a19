#!/usr/bin/env bash
# Create (or refresh) the pinned Python environment ./.venv used by the Mitsuba and Blender
# backends. Idempotent: does nothing when requirements.txt has not changed since the last run.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
venv="$root/.venv"
req="$root/backends/requirements.txt"
stamp="$venv/.poser-requirements.sha256"
# Headless Chromium opens the `poser lesson` pages in the tests (Debian's `chromium`).
if ! command -v chromium >/dev/null 2>&1; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    apt-get update && DEBIAN_FRONTEND=noninteractive apt-get install -y chromium
  else
    echo "error: chromium is missing (the lesson tests screenshot their pages with it)" >&2
    echo "  help: run \`sudo apt-get update && sudo apt-get install -y chromium\`," >&2
    echo "        or run backends/setup.sh as root" >&2
    exit 1
  fi
fi
# A one-node SLURM cluster runs the `poser slurm` test (Debian's `slurm-wlm` and `munge`;
# backends/slurm/start.sh starts it).
if ! command -v slurmctld >/dev/null 2>&1 && [ ! -x /usr/sbin/slurmctld ]; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    apt-get update && DEBIAN_FRONTEND=noninteractive apt-get install -y slurm-wlm munge
  else
    echo "error: slurm-wlm is missing (the \`poser slurm\` test runs a one-node cluster)" >&2
    echo "  help: run \`sudo apt-get update && sudo apt-get install -y slurm-wlm munge\`," >&2
    echo "        or run backends/setup.sh as root" >&2
    exit 1
  fi
fi
# Node with the pinned npm packages of backends/gltf (the Khronos glTF validator and three.js)
# checks the `poser export` files in tests/gltf_view.rs (Debian's `nodejs` and `npm`).
if ! command -v npm >/dev/null 2>&1; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    apt-get update && DEBIAN_FRONTEND=noninteractive apt-get install -y nodejs npm
  else
    echo "error: npm is missing (the glTF export tests run the Khronos validator and three.js)" >&2
    echo "  help: run \`sudo apt-get update && sudo apt-get install -y nodejs npm\`," >&2
    echo "        or run backends/setup.sh as root" >&2
    exit 1
  fi
fi
gltf_dir="$root/backends/gltf"
gltf_stamp="$gltf_dir/node_modules/.poser-package-lock.sha256"
gltf_want="$(sha256sum "$gltf_dir/package-lock.json" | cut -d' ' -f1)"
if [ ! -f "$gltf_stamp" ] || [ "$(cat "$gltf_stamp")" != "$gltf_want" ]; then
  npm ci --prefix "$gltf_dir" --no-audit --no-fund
  echo "$gltf_want" > "$gltf_stamp"
  echo "glTF tools ready: $gltf_dir/node_modules"
fi
want="$(sha256sum "$req" | cut -d' ' -f1)"
if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want" ]; then
  exit 0
fi
python3 -m venv "$venv"
"$venv/bin/python" -m pip install --quiet --upgrade pip
"$venv/bin/python" -m pip install --quiet -r "$req"
echo "$want" > "$stamp"
echo "python environment ready: $venv"
