"""An interrupted run (hard kill or Ctrl-C) leaves only whole files behind and resumes
without redoing finished jobs (the helpers are tests/test_resilience.py's).

A module of its own, dispatched after the CI run is made (tests/conftest.py): every test
starts from a copy of the session's CI run with part of TARGET's jobs undone (the outputs
of REDONE Monte Carlo jobs and of their gather job removed), so the interrupted run is a
multi-job stage (the Monte Carlo jobs two at a time on two cores, then the gather job) and
its reference is the CI run itself, with no run from scratch.

No test here depends on timing: the run is interrupted while a job is held mid-way by
tests/hold_hook, and the subprocess timeouts are safety nets against a hung run (10 min),
not measurements.
"""

import os
import signal
import subprocess
import time

import pytest

from tests.conftest import copy_of_ci_workflow
from tests.snakemake_plan import planned_jobs
from tests.test_resilience import (
    CI,
    HELD_OUTPUT,
    HELD_RULE,
    REPO,
    TARGET,
    TEMPORARY,
    comparable,
    finished_jobs,
    hold_env,
    jobs_in,
    open_when_held,
    sha256,
    snakemake,
    snakemake_cmd,
    survey,
)


#: Monte Carlo jobs of TARGET undone in the copy: more than the two cores run at once, so
#: one waits for a core, and the gather job waits for all of them.
REDONE = 3


@pytest.fixture(scope="module")
def uninterrupted(ci_workflow, tmp_path_factory):
    """The reference: the session's CI run (tests/conftest.py; the same config, so the same
    outputs of TARGET) and the jobs TARGET takes from scratch (a dry run in an empty folder),
    of which the tests undo the gather job and REDONE Monte Carlo jobs."""
    workdir = tmp_path_factory.mktemp("plan")  # `snakemake -n TARGET`, planned in this process
    return ci_workflow, planned_jobs(workdir, [TARGET], [CI])


def partly_undone(ci_workflow, ref_jobs, dest):
    """A copy of the CI run without the outputs of the gather job and of the first REDONE
    Monte Carlo jobs of TARGET: {jobid: (rule, outputs)} of the jobs this leaves to do."""
    workdir = copy_of_ci_workflow(ci_workflow, dest)
    mc = sorted(j for j, (rule, _) in ref_jobs.items() if rule == "burkhard2024_mc")
    undone = {j: ref_jobs[j] for j in mc[:REDONE]}
    undone.update({j: job for j, job in ref_jobs.items() if job[0] == HELD_RULE})
    for _, outputs in undone.values():
        for o in outputs:
            (workdir / o).unlink()
    return undone


#: Where TARGET's jobs write (outputs, logs, benchmarks): the rest of the copy is the CI run's.
WRITTEN = ("burkhard2024", "logs/burkhard2024", "benchmarks/burkhard2024")


def survey_run(results):
    """:func:`survey` of the folders TARGET's jobs write (every file whole), and the
    temporary leftovers anywhere under results/."""
    files = [f for sub in WRITTEN for f in survey(results / sub)[0]]
    return files, [p for p in sorted(results.rglob("*")) if p.is_file() and TEMPORARY.match(p.name)]


def default_sigint():
    """Run in the child before Snakemake starts: SIGINT back to its default disposition."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def interrupt(workdir, sig):
    """Start the run in its own process group with the gather job held mid-way (all Monte
    Carlo jobs finished by then), send `sig` to the whole group (a hard crash or a Ctrl-C)
    while it is held, and return the Snakemake output, the finished and the running job ids."""
    console = workdir.with_name(workdir.name + ".console")
    fifo = workdir.with_name(workdir.name + ".hold")
    os.mkfifo(fifo)
    env = dict(os.environ, **hold_env(fifo, f"*/{HELD_OUTPUT}"))
    with open(console, "w") as sink:
        # two cores: the Monte Carlo jobs two at a time; the held gather job needs them all,
        # so it alone runs when the signal comes
        # Ctrl-C as a terminal delivers it: a test run started in the background of a shell
        # without job control inherits SIGINT ignored (POSIX), and so would every process of
        # the run, which then never ends on the signal (the run hung 600 s that way)
        proc = subprocess.Popen(snakemake_cmd(workdir, TARGET, "--configfile", CI, "--cores", "2"), cwd=REPO,
                                stdout=sink, stderr=subprocess.STDOUT, start_new_session=True, env=env,
                                preexec_fn=default_sigint)
    held = None
    try:
        held = open_when_held(fifo, lambda: proc.poll() is None, console.read_text)
        os.killpg(proc.pid, sig)
        proc.wait(timeout=600)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
        if held is not None:
            os.close(held)
    # nothing of the group may survive (a job still writing would spoil the checks); the
    # 2 min are a safety net: a killed or interrupted process ends at once
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        try:
            os.killpg(proc.pid, 0)
        except ProcessLookupError:
            break
        time.sleep(0.1)
    else:
        raise AssertionError("processes of the interrupted run survive")
    text = console.read_text()  # Ctrl-C: Snakemake reports what it cancelled
    jobs, done = jobs_in(text), finished_jobs(text)
    return text, done, set(jobs) - done, jobs


@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGINT], ids=["SIGKILL", "SIGINT"])
def test_interrupted_run_resumes_without_redoing_finished_jobs(tmp_path, uninterrupted, sig):
    ci_workflow, ref_jobs = uninterrupted
    ref_dir = ci_workflow[0]
    workdir = tmp_path / "work"
    undone = partly_undone(ci_workflow, ref_jobs, workdir)
    t0 = time.perf_counter()
    text, done, running, jobs = interrupt(workdir, sig)
    results = workdir / "results"
    # the held job was running; every Monte Carlo job had finished before it could start
    assert [jobs[j][0] for j in running] == [HELD_RULE], text
    assert sum(jobs[j][0] == "burkhard2024_mc" for j in done) == REDONE, text
    # the run did what was undone and nothing else
    assert sorted(o for _, outputs in jobs.values() for o in outputs) == \
        sorted(o for _, outputs in undone.values() for o in outputs), text

    # (a) only whole files; list what the interruption left
    files, temporaries = survey_run(results)
    finished = {o: (sha256(results.parent / o), (results.parent / o).stat().st_mtime_ns)
                for j in done for o in jobs[j][1]}
    assert all((results.parent / o).is_file() for o in finished)
    print(f"{sig.name}: {len(done)} jobs finished, running {[jobs[j][0] for j in running]}; "
          f"{len(files)} whole files, temporaries left: {[str(p.relative_to(results)) for p in temporaries]}")

    # (b) the dry run of the resumed run plans exactly the unfinished jobs
    # (planned in this process: tests/snakemake_plan.py; what the interrupted run printed is
    # still read from its console)
    planned = {o for _, outputs in planned_jobs(workdir, [TARGET], [CI]).values() for o in outputs}
    every = {o for _, outputs in undone.values() for o in outputs}
    assert not planned & set(finished), f"finished jobs planned again: {sorted(planned & set(finished))}"
    assert planned == every - set(finished), sorted(planned ^ (every - set(finished)))
    assert {o for j in running for o in jobs[j][1]} <= planned  # the interrupted job is redone

    # (c) the resumed run completes, leaves the finished outputs alone and equals an
    # uninterrupted run.  Ctrl-C releases Snakemake's lock on the working directory; a hard
    # kill cannot, and Snakemake refuses to start until `--unlock` (its error says so).
    locks = list((workdir / ".snakemake" / "locks").glob("*"))
    if sig == signal.SIGKILL:
        proc = snakemake(workdir, "--unlock", TARGET, "--configfile", CI, timeout=600)
        assert proc.returncode == 0, proc.stderr[-3000:]
    else:
        assert not locks, locks
    proc = snakemake(workdir, TARGET, "--configfile", CI, "--cores", "2")
    assert proc.returncode == 0, proc.stderr[-3000:]
    for o, (digest, mtime) in finished.items():
        p = results.parent / o
        assert (sha256(p), p.stat().st_mtime_ns) == (digest, mtime), f"{o} was rewritten"
    _, temporaries = survey_run(results)
    assert not temporaries, f"temporary files left after the resumed run: {temporaries}"
    mine, ref = comparable(results), comparable(ref_dir / "results")
    assert mine and set(mine) <= set(ref), sorted(set(mine) - set(ref))  # the CI run made more
    assert [k for k in mine if mine[k] != ref[k]] == []
    print(f"{sig.name}: interrupt + dry run + resume {time.perf_counter() - t0:.1f} s")
