import fcntl
import json
import os
import resource
import shutil
import subprocess
import sys
import time
from pathlib import Path

# One BLAS thread per process, set before numpy loads (the workers and the workflow runs
# inherit it): the tests run in parallel on few cores, and a multi-threaded BLAS in two
# processes at once spins for the other's core (as the Snakefile says).
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

# The test modules' assertion-rewritten bytecode is kept (tests/__pycache__, git-ignored)
# even where PYTHONDONTWRITEBYTECODE is set, as tools/setup.sh compiles src/: pytest rewrites
# and compiles every test module in every xdist worker otherwise, at every run (a worker's
# collection: 8.0 s of CPU without the cache, 3.6 s with it, side by side).  This module
# itself is rewritten before the line runs; every test module after it is cached.
sys.dont_write_bytecode = False

import numpy as np
import pytest

from accelcal.simulation import random_directions, sample_truth, simulate_poses

G = 9.8055  # Burkhard et al. (2024), Sec. 2


@pytest.fixture
def rng():
    return np.random.default_rng(20240601)


@pytest.fixture
def truth(rng):
    t = sample_truth(rng, 1)
    return {k: v[0] for k, v in t.items()}


def make_poses(rng, truth, n, noise, identity=False):
    M = np.eye(3) if identity else truth["M"]
    return simulate_poses(random_directions(rng, n), G, M, truth["bias"], noise, rng)


REPO = Path(__file__).resolve().parents[1]
CI_CONFIG = REPO / "config" / "ci.yaml"
#: Upper bound of the CI workflow run inside the tests (it takes minutes on an idle machine).
CI_RUN_TIMEOUT_S = 3600


def run_snakemake(workdir, *args, timeout=1800):
    """The repository's workflow with ``workdir`` as working directory (results go there).
    The timeout is a safety net against a hung run, not a measurement: the CI run took
    more than 10 min on a shared machine at load 12."""
    cmd = [str(Path(sys.executable).with_name("snakemake")), "--snakefile", str(REPO / "Snakefile"),
           "--directory", str(workdir), "--cores", "2", "--scheduler", "greedy", *map(str, args)]
    return subprocess.run(cmd, cwd=REPO, capture_output=True, text=True, timeout=timeout)


def session_shared_dir(tmp_path_factory, worker_id) -> Path:
    """The test session's temporary folder that every xdist worker sees."""
    base = tmp_path_factory.getbasetemp()
    return base if worker_id == "master" else base.parent


def once_per_session(tmp_path_factory, worker_id, name, make):
    """``(workdir, record)``: ``make(workdir)`` (a JSON-able record) run once per test session
    in the session's shared temporary folder.  The first worker that needs it makes it while
    holding a lock; the others wait for it and read its record."""
    shared = session_shared_dir(tmp_path_factory, worker_id)
    workdir, record = shared / name, shared / f"{name}.json"
    with open(shared / f"{name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file closes
        if not record.exists():
            workdir.mkdir()
            record.write_text(json.dumps(make(workdir)))
        return workdir, json.loads(record.read_text())


@pytest.fixture(scope="session")
def ci_workflow(tmp_path_factory, worker_id):
    """`snakemake all` on the CI config, once per test session (the most expensive step of
    the suite): ``(workdir, stderr, wall time [s])``.  Tests that change files work on
    :func:`copy_of_ci_workflow`.

    The tests run in parallel (pytest-xdist, pyproject addopts); the first worker that
    needs the run makes it while holding a lock in the session's shared temporary folder,
    and the others wait for it and reuse it (the run itself uses both cores).
    """
    def make(workdir):
        t0 = time.perf_counter()
        try:  # generous: a loaded machine must make the run slow, not fail it
            proc = run_snakemake(workdir, "all", "--configfile", CI_CONFIG, timeout=CI_RUN_TIMEOUT_S)
            returncode, stderr = proc.returncode, proc.stderr
        except subprocess.TimeoutExpired as e:  # recorded, so the other workers fail the same way
            err = e.stderr.decode(errors="replace") if isinstance(e.stderr, bytes) else e.stderr or ""
            returncode, stderr = -1, f"CI workflow run timed out after {e.timeout} s\n{err}"
        return {"returncode": returncode, "stderr": stderr, "elapsed": time.perf_counter() - t0}

    workdir, run = once_per_session(tmp_path_factory, worker_id, "ci_workflow", make)
    assert run["returncode"] == 0, run["stderr"][-4000:]
    return workdir, run["stderr"], run["elapsed"]


@pytest.fixture(scope="session")
def default_dry_run(tmp_path_factory, worker_id):
    """`snakemake -n all` on the default config (config/config.yaml) in an empty folder,
    planned once per test session in the process of the first worker that needs it
    (tests/snakemake_plan.py; ~1 s of CPU there against ~3 s for a Snakemake process):
    ``(workdir, error, {rule: jobs})``, error the config check's message or None.  Its job
    table is what tests of the default config read (the checks pass, the grid's job count);
    the other workers read its record."""
    def make(workdir):
        # deferred: Snakemake's API (~1.2 s to import) only in the worker that plans
        from snakemake.exceptions import WorkflowError

        from tests.snakemake_plan import planned_jobs, rule_counts
        try:
            return {"error": None, "jobs": rule_counts(planned_jobs(workdir, ["all"]))}
        except WorkflowError as e:
            return {"error": str(e), "jobs": {}}

    workdir, run = once_per_session(tmp_path_factory, worker_id, "default_dry_run", make)
    return workdir, run["error"], run["jobs"]


def copy_of_ci_workflow(ci_workflow, dest: Path) -> Path:
    """A copy of the CI run (results and Snakemake's records, modification times kept) that
    a test may rerun or rewrite without touching the others' view."""
    src = ci_workflow[0]
    shutil.copytree(src / "results", dest / "results")
    shutil.copytree(src / ".snakemake", dest / ".snakemake", ignore=shutil.ignore_patterns("log", "locks"))
    return dest


def write_config(cfg: dict, path: Path) -> Path:
    """``cfg`` written to ``path`` for ``--configfile`` as JSON, which is YAML too: Snakemake
    reads a config file as JSON first, and its YAML path (yte, pure-Python PyYAML) costs
    ~0.04 s of CPU per read of the CI config, twice per parse, ~0.1 s with the dump (of
    ~0.33 s per parse).  The dict Snakemake gets is the same (a test compares)."""
    path.write_text(json.dumps(cfg, indent=1))
    return path


def config_error(cfg: dict, path: Path) -> str | None:
    """The Snakefile parsed in this process with ``cfg`` as the whole config (what
    ``snakemake --configfile PATH --replace-workflow-config`` reads; ``cfg`` is written to
    ``path``): the message of the config error it raises, or None when it parses.

    The config is checked while the Snakefile is parsed (check_config, common.smk), before
    any DAG: what a broken config gets is decided here, without a Snakemake process per
    case (~1.5 s each).  The command line's behaviour on a broken config (one line, no
    traceback, no job) is tested through a subprocess once per stage."""
    from snakemake.api import SnakemakeApi
    from snakemake.exceptions import WorkflowError
    from snakemake.settings.types import (ConfigSettings, DeploymentSettings, OutputSettings, ResourceSettings,
                                          StorageSettings, WorkflowSettings)

    write_config(cfg, path)
    workdir = path.parent / "parse"
    workdir.mkdir(exist_ok=True)
    with SnakemakeApi(OutputSettings(quiet={"all"})) as api:
        try:
            api.workflow(resource_settings=ResourceSettings(cores=1), storage_settings=StorageSettings(),
                         config_settings=ConfigSettings(configfiles=[path], replace_workflow_config=True),
                         workflow_settings=WorkflowSettings(), deployment_settings=DeploymentSettings(),
                         snakefile=REPO / "Snakefile", workdir=workdir)._workflow
        except WorkflowError as e:
            return str(e.args[0]) if e.args else str(e)
    return None


#: Dispatch order (``--dist loadfile --no-loadscope-reorder`` hands whole modules to the
#: workers in collection order; xdist's default hands out the modules with the most tests
#: first, which started the real-SLURM module, 5 tests, last).  First the modules that spend
#: most of their time waiting, each on a worker of its own: the real SLURM (daemons, status
#: polls, a time limit of a minute) and the module whose first test starts the CI run (which
#: uses both cores itself).  Last, the other modules that need the CI run: dispatched early
#: they would hold a worker idle while it runs (with xdist, the scheduler hands them out
#: as soon as the run exists instead: tests/xdist_schedule.py).
FIRST_MODULES = ("test_real_slurm.py", "test_workflow.py")
#: The module whose first test makes the CI run (its worker waits for it).
CI_RUN_MODULE = "test_workflow.py"
#: The modules that need the CI run, longest first: the scheduler (tests/xdist_schedule.py)
#: hands them out ahead of the queue once a test of CI_RUN_MODULE has ended.
LAST_MODULES = ("test_workflow_reruns.py", "test_workflow_interrupts.py", "test_burkhard2024_workflow.py",
                "test_workflow_structure.py", "test_benchmark.py", "test_discrepancy_workflow.py")


def pytest_collection_modifyitems(config, items):
    """The waiting modules first, the modules that need the CI run last (FIRST_MODULES)."""
    def rank(item):
        name = Path(str(item.fspath)).name
        if name in FIRST_MODULES:
            return FIRST_MODULES.index(name)
        return len(FIRST_MODULES) + 1 + LAST_MODULES.index(name) if name in LAST_MODULES else len(FIRST_MODULES)

    items.sort(key=rank)  # stable: the order within a module is kept


@pytest.hookimpl(optionalhook=True)  # xdist's hook: the suite also runs with -p no:xdist
def pytest_xdist_make_scheduler(config, log):
    """``--dist loadfile`` as tests/xdist_schedule.OneModuleAhead hands it out: the next
    module at the last test of the current one, and a crashed worker fails its test
    instead of hanging the run."""
    if config.getvalue("dist") != "loadfile":
        return None
    from tests.xdist_schedule import OneModuleAhead  # xdist is imported only when it runs the suite

    return OneModuleAhead(config, log, after=LAST_MODULES, gate=CI_RUN_MODULE)


@pytest.hookimpl(optionalhook=True)  # xdist's hook: the suite also runs with -p no:xdist
def pytest_xdist_auto_num_workers(config):
    """``-n auto``: one worker per core, and at least three: two of them wait most of their
    time (for SLURM, for the CI run), so two workers on two cores would leave the cores idle."""
    return max(3, os.cpu_count() or 1)


def _timeline(when: str, seconds: float, nodeid: str) -> None:
    """One line of $ACCELCAL_TEST_TIMELINE (see pytest_runtest_logreport), if it is set."""
    folder = os.environ.get("ACCELCAL_TEST_TIMELINE")
    if folder:
        worker = os.environ.get("PYTEST_XDIST_WORKER", "master")
        own, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime
        with open(Path(folder) / f"{worker}.tsv", "a") as f:
            f.write(f"{time.time():.1f}\t{worker}\t{when}\t{seconds:.2f}\t{nodeid}\t{cpu:.2f}\n")


def pytest_runtest_logreport(report):
    """With $ACCELCAL_TEST_TIMELINE set to a folder: one line per test phase (end time,
    worker, phase, seconds, test, and the worker's CPU seconds so far: its own and its
    finished subprocesses') in a file per worker, to see where a run's wall time and CPU
    go (which module waits for what; tools/test_timeline.py makes the per-module table);
    nothing otherwise.  Processes that are not the worker's waited-for children are not
    counted: the real-SLURM module's daemons and its SLURM jobs."""
    _timeline(report.when, report.duration, report.nodeid)


def pytest_collection_finish(session):
    """The timeline's first line of a process: its start-up and collection (so that the
    first test's setup is not charged with them)."""
    _timeline("collect", 0.0, "(collection)")
