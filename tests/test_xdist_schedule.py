"""The suite's xdist scheduler (tests/xdist_schedule.py) in a small pytest session of its
own: a worker that dies mid-module fails that one test, and every other test still runs;
the session ends instead of waiting forever (what xdist 3.8's own loadfile scheduler does
after a crash: the whole suite hung once a reader-fuzz example crashed scipy)."""

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]

CONFTEST = """\
import pytest

@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config, log):
    from tests.xdist_schedule import OneModuleAhead
    return OneModuleAhead(config, log)
"""
#: The module whose worker dies (os.abort: no Python clean-up, as a segfault), at its
#: second test of four; the others pass, and a one-test module stands among them.
CRASHING = "import os\n\ndef test_1(): pass\n\ndef test_2(): os.abort()\n\ndef test_3(): pass\n\ndef test_4(): pass\n"
PASSING = "def test_1(): pass\n\ndef test_2(): pass\n\ndef test_3(): pass\n"


@pytest.mark.parametrize("workers", [1, 2])
def test_a_crashed_worker_fails_its_test_and_the_session_ends(tmp_path, workers):
    (tmp_path / "conftest.py").write_text(CONFTEST)
    (tmp_path / "test_a.py").write_text(CRASHING)
    for name in ("b", "c"):
        (tmp_path / f"test_{name}.py").write_text(PASSING)
    (tmp_path / "test_d.py").write_text("def test_only(): pass\n")
    env = dict(os.environ, PYTHONPATH=str(REPO), PYTHONFAULTHANDLER="")
    try:  # a hang is the bug; 60 s is a safety net (the session takes ~2 s of it)
        proc = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-n", str(workers),
                               "--dist", "loadfile", "-o", "addopts=", "--rootdir", str(tmp_path), str(tmp_path)],
                              cwd=tmp_path, env=env, capture_output=True, text=True, timeout=60)
    except subprocess.TimeoutExpired:
        pytest.fail("the session hung after the worker crashed")
    out = proc.stdout + proc.stderr
    assert proc.returncode == 1, out[-3000:]
    assert re.search(r"worker 'gw\d' crashed while running 'test_a\.py::test_2'", out), out[-3000:]
    # the crashed test once (not run again on the replacement), every other test passed
    assert re.search(r"^1 failed, 10 passed in ", out, re.M), out[-3000:]
