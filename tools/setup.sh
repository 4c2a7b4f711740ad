#!/bin/sh
# Create .venv (if needed) and install accelcal exactly as pinned in environment.lock.
# Idempotent: reinstalls only when the lock changed since the last run.
set -eu
cd "$(dirname "$0")/.."
PY=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
    "$PY" -m venv .venv
fi
stamp=.venv/.accelcal-lock.sha256
want=$(.venv/bin/python -c "import hashlib,sys;print(hashlib.sha256(open('environment.lock','rb').read()).hexdigest())")
if [ ! -f "$stamp" ] || [ "$(cat "$stamp")" != "$want" ]; then
    .venv/bin/python -m pip install -q --disable-pip-version-check --require-hashes --no-deps -r environment.lock
    .venv/bin/python -m pip install -q --disable-pip-version-check --no-deps --no-build-isolation -e .
    echo "$want" > "$stamp"
fi
