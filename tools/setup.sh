#!/bin/sh
# Create .venv (if needed) and install accelcal exactly as pinned in environment.lock.
# Idempotent: reinstalls only when the lock changed since the last run.
#
# The installer is uv, itself pinned with hashes in the lock: pip installs it (one wheel),
# then uv installs the lock (parallel downloads and unpacking: the pip path below costs
# ~28 CPU-s more, measured side by side).
# Where uv cannot be installed or cannot reach the index (an unusual platform, a proxy whose
# certificate uv does not trust), pip installs the lock as before, and says so.
# Neither compiles bytecode: tools/bytecode.py then compiles what the project's processes
# import and skips the packages' own test suites and unused generated MAVLink dialects
# (80 of the 186 MB of installed source; the reasons are in that file).
set -eu
cd "$(dirname "$0")/.."
PY=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
    "$PY" -m venv .venv
fi
stamp=.venv/.accelcal-lock.sha256
want=$(.venv/bin/python -c "import hashlib,sys;print(hashlib.sha256(open('environment.lock','rb').read()).hexdigest())")
# The project's own modules as bytecode too (uv and pip compile only what they install):
# a machine with PYTHONDONTWRITEBYTECODE set would otherwise compile them again in every
# process, ~0.1 s of CPU each, and a workflow run starts hundreds of processes.  Quick
# when nothing changed; a stale file is ignored by Python.
.venv/bin/python -m compileall -q src workflow/scripts >/dev/null
if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want" ]; then
    exit 0
fi
pip_install() {
    .venv/bin/python -m pip install -q --disable-pip-version-check "$@"
}
# uv's pin (its line and the indented hash lines after it) from the lock
awk '/^uv==/ {p = 1; print; next} p && /^ / {print; next} {p = 0}' environment.lock > .venv/uv-requirement.txt
if pip_install --require-hashes --no-deps -r .venv/uv-requirement.txt 2>.venv/uv-install.log &&
    .venv/bin/uv pip install --python .venv/bin/python -q --native-tls --require-hashes --no-deps \
        -r environment.lock 2>>.venv/uv-install.log; then
    .venv/bin/uv pip install --python .venv/bin/python -q --no-deps --no-build-isolation -e .
else
    echo "setup: uv could not install the lock (.venv/uv-install.log: $(tail -n 1 .venv/uv-install.log)); using pip" >&2
    pip_install --no-compile --require-hashes --no-deps -r environment.lock
    pip_install --no-compile --no-deps --no-build-isolation -e .
fi
.venv/bin/python tools/bytecode.py
echo "$want" > "$stamp"
