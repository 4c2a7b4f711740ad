"""The cluster path run for real: the SLURM profile (profiles/slurm/, as the
README's "On a cluster" runs it) against a single-node SLURM 22.05 from Debian's packages,
brought up for this module by tools/slurm/ (no accounting storage: sacct does not work,
as on many small clusters).  Selected by ``pytest -k real_slurm``.

The module installs the packages when they are missing (apt-get, as root), starts the
daemons, and at its end stops exactly those daemons and removes exactly the packages it
installed.  Where SLURM cannot be installed (not root, no apt-get, no network to the
mirror) every test is skipped with a one-line reason.

What is checked: every job that is not a local rule ran inside a SLURM job (by its job id:
SLURM's own record of the job, and the job's log file that SLURM wrote, which holds the
Snakemake jobs it ran) in the partition and with the account set in the profile, and the
results equal the local CI run's (tests/conftest.ci_workflow).  A job cancelled by
``scancel`` or killed at its time limit fails the run with the rule's name and without a
hang, and the same command run again finishes, redoing only the failed SLURM job.  The job
to be cancelled is held by tests/hold_hook (see test_resilience): no timing decides what
is running when the fault comes.
"""

import hashlib
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.conftest import CI_CONFIG, REPO
from tests.test_resilience import comparable, hold_env, open_when_held, survey

SNAKEMAKE = Path(sys.executable).with_name("snakemake")
PROFILE = REPO / "profiles" / "slurm"
TOOLS = REPO / "tools" / "slurm"

#: A small target through the profile: the Burkhard Monte Carlo at CI scale (8 grid
#: points, grouped into 2 SLURM jobs of 6 + 2 points) and its gather job (a third SLURM
#: job, group burkhard2024_post), plus a local rule (measured_fetch), which runs in the
#: Snakemake process on the "login node".  Which rules are local is the profile test's
#: (tests/test_slurm_profile.py: every job of the default config is grouped, local or a
#: timing benchmark, so a rule that lost its `localrule` fails there); the compile job
#: kernel_cache is not a target here: it compiles bias_lls cold at every run (its timing)
#: and checked nothing that measured_fetch does not.
TARGETS = ("results/burkhard2024/summary.csv", "results/measured/data/xsens_mti.json")
LOCAL_RULES = {"measured_fetch"}
#: The job the fault tests hold and then cancel (or time out): the gather job, after all
#: Monte Carlo jobs have finished, between two of its outputs.
HELD_RULE = "burkhard2024_summary"
HELD_OUTPUT = "results/burkhard2024/comparisons.csv"
#: Status checks every few seconds instead of the profile's 40 s (the plugin adds 10 s to
#: the interval after every check that finds no finished job): a shorter test, same code.
FAST_STATUS = ("--seconds-between-status-checks", "2", "--slurm-init-seconds-before-status-checks", "2")


class Cluster:
    """The running single-node SLURM: its state folder and the environment for its commands."""

    def __init__(self, state: Path):
        self.state = state
        self.env = dict(os.environ)
        for line in (state / "env").read_text().splitlines():
            name, value = line.removeprefix("export ").split("=", 1)
            self.env[name] = value.replace("$PATH", os.environ["PATH"])

    def run(self, *cmd, check=True):
        proc = subprocess.run(cmd, env=self.env, capture_output=True, text=True, timeout=60)
        assert not check or proc.returncode == 0, f"{cmd}: {proc.stderr}"
        return proc.stdout

    def jobs(self, run_id):
        """SLURM's record of every job of a Snakemake run (its jobs are named by the run id):
        {job id: {partition, account, state, comment}} (squeue keeps finished jobs for
        MinJobAge = 300 s; sacct is not available without accounting storage)."""
        out = self.run("squeue", "--states=all", "--noheader", "--name", run_id, "--format=%i|%P|%a|%T|%k")
        fields = ("partition", "account", "state", "comment")
        return {line.split("|")[0]: dict(zip(fields, line.split("|")[1:])) for line in out.splitlines()}


def kill_job_leftovers(root: Path) -> list[int]:
    """Kill the processes of this module's SLURM jobs that outlived them: with
    ``proctrack/linuxproc`` SLURM finds a job's processes through their parents, so a
    process re-parented to init escapes ``scancel`` (seen: the group job's Snakemake of the
    cancelled job, waiting forever).  Found by a SLURM job id in their environment and a
    working directory under this session's temporary folder."""
    killed = []
    for proc in Path("/proc").iterdir():
        if not proc.name.isdigit() or int(proc.name) == os.getpid():
            continue
        try:
            cwd = Path(os.readlink(proc / "cwd"))
            environ = (proc / "environ").read_bytes()
        except OSError:
            continue
        if b"SLURM_JOB_ID=" in environ and str(cwd).startswith(str(root)):
            try:
                os.kill(int(proc.name), 9)
                killed.append(int(proc.name))
            except ProcessLookupError:
                pass
    return killed


@pytest.fixture(scope="module")
def slurm(tmp_path_factory):
    """Install (if missing) and start the single-node SLURM; stop it and remove what was
    installed afterwards.  Prints the time of each step."""
    t0 = time.perf_counter()
    proc = subprocess.run([TOOLS / "install_packages.sh"], capture_output=True, text=True, timeout=1200)
    if proc.returncode == 3:
        pytest.skip(f"real SLURM unavailable: {proc.stderr.strip().splitlines()[-1]}")
    assert proc.returncode == 0, proc.stderr
    installed = proc.stdout.split()
    t1 = time.perf_counter()
    state = tmp_path_factory.mktemp("slurm") / "cluster"
    proc = subprocess.run([TOOLS / "start_single_node.sh", state], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    t2 = time.perf_counter()
    print(f"\nreal SLURM: install {t1 - t0:.1f} s ({len(installed)} packages), bring-up {t2 - t1:.1f} s")
    cluster = Cluster(state)
    try:
        # every CPU of this machine (the fault runs go side by side, one SLURM CPU each)
        cpus = set(cluster.run("sinfo", "-h", "-N", "-o", "%c").split())  # a line per partition
        assert cpus == {str(len(os.sched_getaffinity(0)))}, f"node CPUs {cpus}, this machine {os.sched_getaffinity(0)}"
        yield cluster
    finally:
        t3 = time.perf_counter()
        subprocess.run([TOOLS / "stop_single_node.sh", "--keep", state], timeout=300)  # logs kept for a failure
        left = kill_job_leftovers(tmp_path_factory.getbasetemp())
        if left:
            print(f"\nreal SLURM: killed {len(left)} process(es) of cancelled jobs that SLURM left: {left}")
        if installed:
            subprocess.run(["apt-get", "purge", "-y", "-q", *installed], capture_output=True, timeout=600,
                           env=dict(os.environ, DEBIAN_FRONTEND="noninteractive"))
        print(f"\nreal SLURM: tests {t3 - t2:.1f} s, stop and removal {time.perf_counter() - t3:.1f} s")


def profile_copy(dest: Path, partition=None, account=None) -> Path:
    """profiles/slurm copied to ``dest``, with the partition and account lines that the
    profile and the README tell a user to uncomment, uncommented and set."""
    text = (PROFILE / "config.yaml").read_text()
    for key, value in (("slurm_partition", partition), ("slurm_account", account)):
        if value is not None:
            line = re.search(rf"^(\s*)# ({key}): .*$", text, re.M)
            assert line, f"profiles/slurm/config.yaml has no commented {key} line to uncomment"
            text = text.replace(line.group(0), f'{line.group(1)}{key}: "{value}"')
    dest.mkdir(parents=True)
    (dest / "config.yaml").write_text(text)
    return dest


def snakemake_cmd(workdir, profile, *args):
    return [str(SNAKEMAKE), "--snakefile", str(REPO / "Snakefile"), "--directory", str(workdir),
            "--workflow-profile", str(profile), "--configfile", str(CI_CONFIG), *FAST_STATUS,
            "--slurm-keep-successful-logs", *map(str, args)]


def run_profile(cluster, workdir, profile, timeout=900):
    proc = subprocess.run(snakemake_cmd(workdir, profile, *TARGETS), cwd=REPO, capture_output=True,
                          text=True, timeout=timeout, env=cluster.env)
    return proc, proc.stdout + proc.stderr


_SUBMITTED = re.compile(r"^Job (\S+) has been submitted with SLURM jobid (\d+) \(log: (.+)\)\.$", re.M)
#: Inside a SLURM job the plugin's job-step Snakemake starts each job with `srun` and a
#: Snakemake of its own, which runs it as a local rule and reports it finished.
_RAN_JOB = re.compile(r"^localrule (\w+):\n((?:    .*\n)+)((?:.|\n)*?)(?=^localrule |\Z)", re.M)


def run_id(text):
    return re.search(r"^SLURM run ID: (\S+)$", text, re.M).group(1)


def submitted(text):
    """{SLURM job id: its log file} of a Snakemake run's submissions."""
    return {slurm_id: Path(log) for _, slurm_id, log in _SUBMITTED.findall(text)}


def jobs_in_slurm_log(log: Path):
    """(rule, outputs) of every Snakemake job that ran inside a SLURM job, from the log SLURM
    wrote for that job; each must have finished."""
    jobs = []
    for rule, block, after in _RAN_JOB.findall(log.read_text()):
        assert re.search(rf"^Finished jobid: \d+ \(Rule: {rule}\)", after, re.M), f"{log}: {rule} did not finish"
        outputs = re.search(r"^    output: (.+)$", block, re.M).group(1)
        jobs.append((rule, tuple(o.strip() for o in outputs.split(","))))
    return jobs


def sha256(path):
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def outputs_equal_local_run(results: Path, request):
    """Every result of this run (logs, benchmarks and timings excepted) is byte-identical
    to the same file of the local CI run.  That run (tests/conftest.ci_workflow, shared by
    the session) is asked for only in the module's last test, after every SLURM run:
    another worker is making it meanwhile, and the SLURM runs do not wait for it."""
    ci_workflow = request.getfixturevalue("ci_workflow")
    mine, local = comparable(results), comparable(ci_workflow[0] / "results")
    assert mine and set(mine) <= set(local), sorted(set(mine) - set(local))
    assert [k for k in mine if mine[k] != local[k]] == []


def start_held_run(slurm, workdir: Path, *args) -> dict:
    """TARGETS through the profile in ``workdir`` (with ``args``) with the gather job held
    (tests/hold_hook): the run's working directory, hold FIFO, console file and process."""
    fifo, console = workdir.with_name("hold"), workdir.with_name("console.log")
    os.mkfifo(fifo)
    with open(console, "w") as sink:
        proc = subprocess.Popen(snakemake_cmd(workdir, PROFILE, *TARGETS, *args), cwd=REPO, stdout=sink,
                                stderr=subprocess.STDOUT, start_new_session=True,
                                env=dict(slurm.env, **hold_env(fifo, f"*/{HELD_OUTPUT}")))
    return {"workdir": workdir, "fifo": fifo, "console": console, "proc": proc}


def monte_carlo_outputs(workdir: Path) -> dict:
    """{path: (sha256, mtime)} of the run's Monte Carlo outputs (the gather job's inputs)."""
    finished = {p: (sha256(p), p.stat().st_mtime_ns) for p in (workdir / "results").rglob("mc/*.csv.gz")}
    assert len(finished) == 8, sorted(finished)
    return finished


@pytest.fixture(scope="module")
def profile_run(slurm, tmp_path_factory):
    """TARGETS through the profile as the README says to use it, with the partition and
    account set by uncommenting its two lines: (working directory, Snakemake's output)."""
    tmp = tmp_path_factory.mktemp("profile_run")
    profile = profile_copy(tmp / "profile", partition="other", account="accelcal_test")
    workdir = tmp / "work"
    t0 = time.perf_counter()
    proc, text = run_profile(slurm, workdir, profile)
    assert proc.returncode == 0, text[-5000:]
    print(f"\nreal SLURM: {TARGETS} through the profile: {time.perf_counter() - t0:.1f} s")
    return workdir, text


def test_real_slurm_each_job_runs_as_a_slurm_job_in_the_chosen_partition(slurm, profile_run):
    """Every job not marked local runs in a SLURM job of the run (grouped as the profile
    says), in the chosen partition, with the chosen account, and writes every file it
    planned, whole."""
    workdir, text = profile_run
    jobs = slurm.jobs(run_id(text))
    logs = submitted(text)
    assert set(logs) == set(jobs) and len(jobs) == 3, (sorted(logs), jobs)
    for slurm_id, job in jobs.items():
        assert job["state"] == "COMPLETED", (slurm_id, job)
        assert (job["partition"], job["account"]) == ("other", "accelcal_test"), (slurm_id, job)
        assert logs[slurm_id].name == f"{slurm_id}.log"  # written by SLURM for this job id (--output %j.log)
    # which Snakemake jobs ran in which SLURM job: from the SLURM jobs' own logs
    ran_in = {}
    for slurm_id, log in logs.items():
        for rule, outputs in jobs_in_slurm_log(log):
            for o in outputs:
                assert o not in ran_in, f"{o} made twice ({ran_in[o]} and {slurm_id})"
                ran_in[o] = (rule, slurm_id)
    rules = {rule for rule, _ in ran_in.values()}
    assert rules == {"burkhard2024_mc", HELD_RULE}, rules
    assert sum(1 for o, (r, _) in ran_in.items() if r == "burkhard2024_mc" and o.endswith(".csv.gz")) == 8
    mc_jobs = {s for r, s in ran_in.values() if r == "burkhard2024_mc"}
    assert len(mc_jobs) == 2, mc_jobs  # 6 + 2 points: the profile's group-components
    # the local rule ran in the Snakemake process on the "login node", not in SLURM
    local = set(re.findall(r"^localrule (\w+):", text, re.M))
    assert local == LOCAL_RULES, local
    assert not any(r in LOCAL_RULES for r, _ in ran_in.values())
    # every file the run planned exists and equals the local run's
    files, temporaries = survey(workdir / "results")
    assert not temporaries, temporaries
    assert all((workdir / o).is_file() for o in ran_in)
    # equal to the local run's: test_real_slurm_results_equal_the_local_run, at the end


def slurm_id_of_held_job(text):
    """The SLURM job whose log shows the held rule running."""
    for slurm_id, log in submitted(text).items():
        if log.exists() and re.search(rf"^\s*rule {HELD_RULE}:", log.read_text(), re.M):
            return slurm_id
    raise AssertionError(f"no submitted SLURM job runs {HELD_RULE}:\n{text[-3000:]}")


FAULTS = {  # fault: (what the test does to the held job's SLURM job, SLURM's state afterwards)
    "scancel": (lambda slurm, job: slurm.run("scancel", job), "CANCELLED"),
    # the job outgrows its time limit: the run asks for the shortest there is (SLURM's
    # limits are whole minutes) for the held job (TIME_LIMIT_ARGS), and SLURM ends it
    "time_limit": (None, "TIMEOUT"),
}
#: The time-limit fault's run asks for 1 min for the held job, as a user who asked for too
#: little would (the profile's own runtime is 30 min; the rerun goes without these).  Last on the
#: command line: --set-resources takes every word after it.
TIME_LIMIT_ARGS = ("--set-resources", f"{HELD_RULE}:runtime=1")


def without_gather_outputs(profile_run, workdir: Path) -> dict:
    """A copy of the profile run in ``workdir`` without the gather job's outputs (the
    Monte Carlo's, in mc/, are kept): {path: (sha256, mtime)} of the Monte Carlo outputs."""
    shutil.copytree(profile_run[0], workdir, symlinks=True, ignore=shutil.ignore_patterns("locks"))
    for path in (workdir / "results" / "burkhard2024").iterdir():
        if path.is_file():  # the gather job's outputs (not the Monte Carlo's, in mc/)
            path.unlink()
    return monte_carlo_outputs(workdir)


@pytest.fixture(scope="module")
def faulted_runs(slurm, profile_run, tmp_path_factory):
    """For every fault, side by side (one SLURM CPU each), a run with the gather job held,
    each on its own copy of the profile run without the gather job's outputs (the Monte
    Carlo jobs that ran in SLURM are the profile run's; making them again from scratch for
    a fault run cost a third of the module's CPU and checked nothing more).  The fault hits
    the held job's SLURM job: ``scancel`` by the test, the time limit by SLURM (that run
    asks for 1 min for the held job, TIME_LIMIT_ARGS).  When the run has ended, the same
    command runs again, without the hold (and with the profile's time limit).  Returns per
    fault the working directory, the Monte Carlo outputs (sha256, mtime) before the rerun,
    the faulted run's output and return code, the SLURM job id, and the rerun's output and
    return code.  The time-limit run's held job is never released: SLURM ends it, whenever
    the test gets there (no timing decides the outcome)."""
    runs = {}
    for fault in sorted(FAULTS, key=lambda f: FAULTS[f][0] is not None):  # the time limit first: it waits longest
        workdir = tmp_path_factory.mktemp(fault) / "work"
        finished = without_gather_outputs(profile_run, workdir)
        args = TIME_LIMIT_ARGS if FAULTS[fault][0] is None else ()
        runs[fault] = dict(start_held_run(slurm, workdir, *args), finished=finished)
    try:
        for fault, run in runs.items():
            if FAULTS[fault][0] is None:  # the time limit: SLURM ends the held job by itself
                continue
            run["held"] = open_when_held(run["fifo"], lambda: run["proc"].poll() is None, run["console"].read_text)
            run["slurm_id"] = slurm_id_of_held_job(run["console"].read_text())
            FAULTS[fault][0](slurm, run["slurm_id"])
            run["t0"] = time.perf_counter()
        for fault in sorted(runs, key=lambda f: FAULTS[f][0] is None):  # the time-limit run ends last
            run = runs[fault]
            run["returncode"] = run["proc"].wait(timeout=900)  # no hang: the run ends on its own
            run["text"] = run["console"].read_text()
            if "t0" in run:
                print(f"\nreal SLURM {fault}: the run ended {time.perf_counter() - run['t0']:.1f} s after the fault")
            run.setdefault("slurm_id", slurm_id_of_held_job(run["text"]))
            # the gather job runs only once every Monte Carlo job has finished: these are
            # what the rerun must leave alone
            run.setdefault("finished", monte_carlo_outputs(run["workdir"]))
            # the same command again, without the hold (and the time-limit arguments)
            run["rerun_proc"] = subprocess.Popen(snakemake_cmd(run["workdir"], PROFILE, *TARGETS), cwd=REPO,
                                                 env=slurm.env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                                 text=True)
    finally:
        for run in runs.values():
            if run["proc"].poll() is None:
                os.killpg(run["proc"].pid, 9)
                run["proc"].wait()
            if run.get("held") is not None:
                os.close(run["held"])
    t0 = time.perf_counter()
    for run in runs.values():
        run["rerun"] = run["rerun_proc"].communicate(timeout=900)[0]
        run["rerun_returncode"] = run.pop("rerun_proc").returncode
    print(f"\nreal SLURM: reruns ended {time.perf_counter() - t0:.1f} s after the time-limit run")
    return runs


@pytest.mark.parametrize("fault", list(FAULTS))
def test_real_slurm_cancelled_or_timed_out_job_fails_and_the_rerun_resumes(slurm, faulted_runs, fault):
    """A SLURM job that dies under Snakemake (cancelled by scancel, or killed by SLURM at its
    time limit) is reported as failed with its rule's name; the run stops (no hang); the
    same command again submits only the failed job and leaves the finished ones alone."""
    run = faulted_runs[fault]
    text, slurm_id = run["text"], run["slurm_id"]
    assert run["returncode"] != 0, text[-3000:]
    assert slurm.jobs(run_id(text))[slurm_id]["state"] == FAULTS[fault][1]
    # The error report names the held job's rule and the SLURM job's log (named by its job
    # id), and shows that log, where SLURM wrote why it ended the job.  (Snakemake 9.27
    # drops the plugin's message "SLURM-job 'ID' failed, SLURM status is: 'STATE'" from
    # the report of a group job: GroupJob.log_error does not pass `msg` on.)
    report = text[text.index("Error in "):]
    assert re.search(rf"^Error in group burkhard2024_post\n(?:    .*\n)*?        rule {HELD_RULE}:$", report, re.M), report
    assert f"log: {submitted(text)[slurm_id]} (check log file(s) for error details)" in report, report
    why = "" if fault == "scancel" else " DUE TO TIME LIMIT"
    assert re.search(rf"\*\*\* JOB {slurm_id} ON \S+ CANCELLED AT \S+{why} \*\*\*", report), report

    # the same command again: only the failed SLURM job's jobs ran, the finished ones are kept
    rerun = run["rerun"]
    assert run["rerun_returncode"] == 0, rerun[-5000:]
    again = [r for log in submitted(rerun).values() for r, _ in jobs_in_slurm_log(log)]
    assert again == [HELD_RULE], again
    for p, (digest, mtime) in run["finished"].items():
        assert (sha256(p), p.stat().st_mtime_ns) == (digest, mtime), f"{p} was redone"


@pytest.fixture(scope="module")
def slurm_with_accounting(slurm, tmp_path_factory):
    """A second single-node SLURM, with accounting storage (slurmdbd and MariaDB of its own,
    account accelcal_test, AccountingStorageEnforce=associations).  Its packages are not
    installed by this module (24 packages, MariaDB): skipped where they are missing."""
    missing = [cmd for cmd in ("slurmdbd", "mariadbd") if shutil.which(cmd, path=slurm.env["PATH"] + ":/usr/sbin") is None]
    if missing:
        pytest.skip(f"real SLURM with accounting: {', '.join(missing)} not installed "
                    "(tools/slurm/install_packages.sh --accounting)")
    state = tmp_path_factory.mktemp("slurm_accounting") / "cluster"
    proc = subprocess.run([TOOLS / "start_single_node.sh", "--accounting", state], capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    try:
        yield Cluster(state)
    finally:
        subprocess.run([TOOLS / "stop_single_node.sh", "--keep", state], timeout=300)


def test_real_slurm_with_accounting_the_account_is_checked_and_used(slurm_with_accounting, tmp_path):
    """With accounting storage: the status from squeue follows the jobs; an account set in
    the profile is checked by the plugin and charged; without one the plugin's guess fails
    and SLURM charges the user's default account (sacct works here and says so)."""
    cluster = slurm_with_accounting
    target = "results/measured/xsens_mti.csv"  # one SLURM job (group measured)
    charged = {}
    for account in ("accelcal_test", None):
        profile = profile_copy(tmp_path / f"profile_{account}", account=account)
        proc = subprocess.run(snakemake_cmd(tmp_path / f"work_{account}", profile, target), cwd=REPO,
                              capture_output=True, text=True, timeout=900, env=cluster.env)
        text = proc.stdout + proc.stderr
        assert proc.returncode == 0, text[-5000:]
        (slurm_id,) = submitted(text)
        out = cluster.run("sacct", "-X", "-n", "-P", "-o", "JobID,Account,State", "-j", slurm_id)
        job, charged[account], state = out.strip().split("|")
        assert (job, state) == (slurm_id, "COMPLETED"), out
        if account is None:
            assert "Unable to guess SLURM account. Trying to proceed without." in text
            assert "sacct: invalid option -- '1'" in text  # the plugin's guess (2.8.0)
    assert charged == {"accelcal_test": "accelcal_test", None: "root"}, charged  # root: the default account


def test_real_slurm_results_equal_the_local_run(profile_run, faulted_runs, request):
    """The results of the profile run and of both faulted runs after their reruns equal the
    local CI run's, byte for byte (last in the module: it waits for the local run, which
    another worker makes while the SLURM runs go on)."""
    outputs_equal_local_run(profile_run[0] / "results", request)
    for fault, run in faulted_runs.items():
        outputs_equal_local_run(run["workdir"] / "results", request)
