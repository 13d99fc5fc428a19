#!/usr/bin/env bash
# Create (or refresh) the pinned Python environment ./.venv used by the Mitsuba and Blender
# backends. Idempotent: does nothing when requirements.txt has not changed since the last run.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
venv="$root/.venv"
req="$root/backends/requirements.txt"
stamp="$venv/.poser-requirements.sha256"
want="$(sha256sum "$req" | cut -d' ' -f1)"
if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want" ]; then
  exit 0
fi
python3 -m venv "$venv"
"$venv/bin/python" -m pip install --quiet --upgrade pip
"$venv/bin/python" -m pip install --quiet -r "$req"
echo "$want" > "$stamp"
echo "python environment ready: $venv"
