"""environment.lock must match pyproject.toml: re-lock with `sh tools/lock.sh` after editing it."""

import re
import sys
from pathlib import Path

import pytest
from packaging.requirements import Requirement
from packaging.version import Version

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))
from lockdigest import requirement_lines, requirements_digest  # noqa: E402


def _lock():
    return (ROOT / "environment.lock").read_text()


def _pins():
    pins = {}
    for m in re.finditer(r"^([A-Za-z0-9_.\-]+)==([^\s;\\]+)", _lock(), re.M):
        pins[m.group(1).lower().replace("_", "-")] = Version(m.group(2))
    return pins


def test_lock_was_made_from_the_current_requirements():
    m = re.search(r"^# requirements-sha256: ([0-9a-f]{64})$", _lock(), re.M)
    assert m, "environment.lock has no requirements digest: regenerate it with `sh tools/lock.sh`"
    assert m.group(1) == requirements_digest(), (
        "pyproject.toml (or tools/build-requirements.in) changed since environment.lock was made: "
        "run `sh tools/lock.sh`")


def test_every_requirement_is_pinned_with_a_satisfying_version():
    pins = _pins()
    for line in requirement_lines():
        if line.startswith("requires-python"):
            continue
        req = Requirement(line)
        name = req.name.lower().replace("_", "-")
        assert name in pins, f"{name} is required but not pinned in environment.lock"
        assert req.specifier.contains(pins[name], prereleases=True), f"{name}=={pins[name]} does not satisfy {req}"


def test_every_pin_has_hashes():
    blocks = re.split(r"^(?=[A-Za-z0-9_.\-]+==)", _lock(), flags=re.M)[1:]
    assert len(blocks) > 20
    for block in blocks:
        assert "--hash=sha256:" in block, f"no hash for {block.splitlines()[0]}"


@pytest.mark.parametrize("name", ["numpy", "scipy", "casadi", "pandas", "matplotlib", "snakemake", "pytest"])
def test_core_packages_are_locked(name):
    assert name in _pins()
