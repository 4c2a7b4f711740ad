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

def session_env(**extra):
    """The small session's environment: the repository importable, and none of this
    session's own xdist variables (a worker's would make the small session's controller
    think it is one)."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("PYTEST_")}
    return dict(env, PYTHONPATH=str(REPO), **extra)


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
    env = session_env(PYTHONFAULTHANDLER="")
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


ORDER_CONFTEST = """\
import os
import pytest

@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config, log):
    from tests.xdist_schedule import OneModuleAhead
    return OneModuleAhead(config, log, after=("test_z_long.py", "test_y_short.py"), gate="test_a_gate.py")

def pytest_runtest_logstart(nodeid, location):
    if os.environ.get("PYTEST_XDIST_WORKER"):
        with open("started.log", "a") as f:
            f.write(nodeid + "\\n")
"""


def test_the_modules_that_read_the_run_go_first_once_it_exists(tmp_path):
    """A stand-in for the CI run: the gate module's first test (1 s).  The two modules
    that read it start only after that test, the longer first, ahead of the light modules
    still queued (not after them, where the forced reruns ended the suite alone)."""
    (tmp_path / "conftest.py").write_text(ORDER_CONFTEST)
    (tmp_path / "test_a_gate.py").write_text("import time\n\ndef test_makes_run(): time.sleep(1)\n\n"
                                             "def test_reads_it(): pass\n")
    for name in "bcdefg":
        (tmp_path / f"test_{name}.py").write_text("import time\n\ndef test_1(): time.sleep(0.2)\n\n"
                                                  "def test_2(): pass\n")
    (tmp_path / "test_z_long.py").write_text("def test_1(): pass\n\ndef test_2(): pass\n")
    (tmp_path / "test_y_short.py").write_text("def test_1(): pass\n")
    env = session_env()
    proc = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-n", "2", "--dist",
                           "loadfile", "-o", "addopts=", "--rootdir", str(tmp_path), str(tmp_path)],
                          cwd=tmp_path, env=env, capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, (proc.stdout + proc.stderr)[-3000:]
    started = (tmp_path / "started.log").read_text().split()
    assert len(started) == 17, started
    gate, long, short, last_light = (started.index(n) for n in ("test_a_gate.py::test_reads_it",
                                                                  "test_z_long.py::test_1", "test_y_short.py::test_1",
                                                                  "test_g.py::test_1"))
    assert gate < long < short < last_light, started
