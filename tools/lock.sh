#!/bin/sh
# Regenerate environment.lock from pyproject.toml (+ the build backend), pinned with hashes
# for every platform and Python >= 3.11.  Run after editing the dependencies in pyproject.toml:
#     pip install uv && sh tools/lock.sh
# tests/test_lock.py fails when the lock no longer matches pyproject.toml.
set -eu
cd "$(dirname "$0")/.."
# the current lock is the starting point, so that existing pins change only when they must
cp environment.lock environment.lock.tmp
uv pip compile pyproject.toml tools/build-requirements.in --extra plots --extra fast --extra workflow --extra test --extra peer --extra cluster --extra ros --extra px4 --extra ardupilot --extra rdata --extra mat73 --extra geomag --extra docs \
    --universal --python-version 3.11 --generate-hashes --no-header \
    --index-url https://pypi.org/simple --no-emit-index-url -o environment.lock.tmp -q
python3 tools/lockstamp.py environment.lock.tmp > environment.lock
rm -f environment.lock.tmp
