"""Resilience: a missing measured dataset fails its fetch job, the first job of the run, in
one line (stages that do not need the data run without it: tests/test_workflow_structure.py),
a damaged copy fails the same way, and an atomic writer killed mid-way leaves no output (the
interrupted workflow run: tests/test_workflow_interrupts.py, which uses the helpers here).

No test here depends on timing: the interrupted run is interrupted while a job is held
mid-way by tests/hold_hook, and the subprocess timeouts are safety nets against a hung
run (10 min), not measurements.

Offline is simulated with proxy variables pointing at a closed local port
(http://127.0.0.1:9): urllib honours them, so every download and reachability check is
refused at once, on any machine, without a test-only switch in the code.
"""

import errno
import gzip
import hashlib
import json
import os
import re
import signal
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import pandas as pd
import pytest

from accelcal.atomic import atomic_output, remove_stale_temporaries
from accelcal_repro.measured.data import DATASETS, fetch_file
from accelcal_repro.measured.sources import SOURCES, fetch_source

from tests.configs import ci_config

REPO = Path(__file__).resolve().parents[1]
SNAKEMAKE = Path(sys.executable).with_name("snakemake")
CI = REPO / "config" / "ci.yaml"
SHARED = (REPO / ".." / "shared" / "data").resolve()

_CLOSED_PORT = "http://127.0.0.1:9"
OFFLINE = {"http_proxy": _CLOSED_PORT, "https_proxy": _CLOSED_PORT, "HTTP_PROXY": _CLOSED_PORT,
           "HTTPS_PROXY": _CLOSED_PORT, "no_proxy": "", "NO_PROXY": ""}


def snakemake_cmd(workdir, *args):
    """As tests/test_workflow.py: the repository's workflow (and its profiles/default) with
    `workdir` as working directory."""
    return [str(SNAKEMAKE), "--snakefile", str(REPO / "Snakefile"), "--directory", str(workdir),
            "--scheduler", "greedy", *map(str, args)]


def snakemake(workdir, *args, env=None, timeout=600):
    return subprocess.run(snakemake_cmd(workdir, *args), cwd=REPO, capture_output=True, text=True,
                          timeout=timeout, env=dict(os.environ, **(env or {})))


def measured_overlay(path, data_dir, resources_dir):
    path.write_text(f"measured:\n  data_dir: {data_dir}\n  resources_dir: {resources_dir}\n")
    return path


# --- missing dataset: its fetch job fails first, in one line ---------------------------------


def test_missing_dataset_fails_in_its_fetch_job_before_any_other_job(tmp_path):
    data_dir, cache = tmp_path / "no_data", tmp_path / "no_cache"
    data_dir.mkdir()
    cache.mkdir()
    overlay = measured_overlay(tmp_path / "offline.yaml", data_dir, cache)
    workdir = tmp_path / "work"
    proc = snakemake(workdir, "all", "--configfile", CI, overlay, "--cores", "1", env=OFFLINE, timeout=600)
    out = proc.stdout + proc.stderr
    assert proc.returncode != 0, out
    assert "Traceback" not in out
    # the fetch jobs run first (priority); the first fails and the run stops there
    logs = sorted((workdir / "results" / "logs").rglob("*.log"))
    assert len(logs) == 1 and "fetch" in logs[0].name, logs
    lines = logs[0].read_text().splitlines()
    assert len(lines) == 1, lines
    line = lines[0]
    # the file, where it was looked for, the URL and what to do
    dataset = next(d for d, files in DATASETS.items() for f in files.values() if f.url in line)
    assert f"no shared copy at {data_dir / dataset}" in line and "failed" in line, line
    assert f"copy the dataset folder into {data_dir / dataset}" in line and "network access" in line, line
    made = [p for p in (workdir / "results").rglob("*") if p.is_file()]
    assert all(p.parts[len(workdir.parts) + 1] in ("logs", "benchmarks") for p in made), made
    assert not [p for p in cache.rglob("*") if p.is_file()], "a partial download was left behind"


def test_data_in_the_download_cache_needs_no_network(tmp_path):
    """Offline, with the data only in the download cache (resources_dir, relative to the
    working directory): the fetch jobs take it from there.  A network request would be
    refused and fail the job, so this also shows that local data means no request."""
    workdir = tmp_path / "work"
    cache = workdir / "cache"
    cache.mkdir(parents=True)
    for dataset in DATASETS:
        (cache / dataset).symlink_to(SHARED / dataset)  # no copy of the data
    overlay = measured_overlay(tmp_path / "cache.yaml", tmp_path / "no_data", "cache")
    proc = snakemake(workdir, "results/measured/data/xsens_mti.json", "results/discrepancy/adis/data.json",
                     "--configfile", CI, overlay, "--cores", "1", env=OFFLINE, timeout=600)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    for manifest in ("measured/data/xsens_mti.json", "discrepancy/adis/data.json"):
        files = json.loads((workdir / "results" / manifest).read_text())["files"]
        assert all(f["path"].startswith("cache/") for f in files.values()), files


def test_local_data_needs_no_network(tmp_path, monkeypatch):
    def no_network(*args, **kwargs):
        raise AssertionError("network used although the data is local")

    monkeypatch.setattr(urllib.request, "urlopen", no_network)
    for name in SOURCES:
        fetch_source(name, SHARED, tmp_path / "cache")  # the shared copy
    assert fetch_file("smac_adis16405", "adis_16405_imu1.rda", SHARED, tmp_path / "cache").parent.parent == SHARED
    assert not list((tmp_path / "cache").rglob("*"))


def test_fetch_job_fails_in_one_line_on_a_damaged_copy(tmp_path):
    """A shared copy with the wrong sha256: the fetch job stops with one line (no traceback)
    and writes no manifest."""
    data_dir = tmp_path / "data"
    data_dir.mkdir()
    for dataset in {d.name for d in SHARED.iterdir() if d.is_dir()} - {"mpu6050_suarez"}:  # the others whole
        (data_dir / dataset).symlink_to(SHARED / dataset)
    damaged = data_dir / "mpu6050_suarez" / "example_data_calibration.csv"
    damaged.parent.mkdir()
    damaged.write_text("t,ax,ay,az\n0,1,2,3\n")
    overlay = measured_overlay(tmp_path / "damaged.yaml", data_dir, tmp_path / "cache")
    workdir = tmp_path / "work"
    proc = snakemake(workdir, "results/measured/data/mpu6050.json", "--configfile", CI, overlay, "--cores", "1",
                     env=OFFLINE, timeout=600)
    out = proc.stdout + proc.stderr
    assert proc.returncode != 0, out
    assert "Traceback" not in out, out
    assert (workdir / "results" / "logs" / "measured" / "fetch_mpu6050.log").exists(), out[-3000:]
    log = (workdir / "results" / "logs" / "measured" / "fetch_mpu6050.log").read_text().splitlines()
    assert len(log) == 1, log
    assert "recording mpu6050:" in log[0] and str(damaged) in log[0] and "does not match" in log[0], log[0]
    assert not (workdir / "results" / "measured" / "data" / "mpu6050.json").exists()


def test_fetch_runs_before_the_monte_carlo_jobs(tmp_path):
    """measured_fetch has a high priority: with one core and a Monte Carlo job ready at the
    same time, the fetch runs first (a failing download stops the run before the long jobs)."""
    # Without the priority, Snakemake picks among ready jobs in no fixed order: the fetch
    # would come first in about one run of three here.
    workdir = tmp_path / "work"
    mc = ["results/burkhard2024/mc/n24_s0.001_g0.csv.gz", "results/burkhard2024/mc/n4_s0.0001_g0.csv.gz"]
    proc = snakemake(workdir, *mc, "results/measured/data/xsens_mti.json", "--configfile", CI, "--cores", "1",
                     timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    started = re.findall(r"^(?:local)?rule (\w+):", proc.stdout + proc.stderr, flags=re.M)
    # the Monte Carlo jobs run the numpy implementations (mc_kernels: numpy): no compile job
    assert started == ["measured_fetch", "burkhard2024_mc", "burkhard2024_mc"], started


# --- atomic writers: whole or nothing, and a killed writer's temporary is cleaned up -------------


def current_umask():
    mask = os.umask(0)
    os.umask(mask)
    return mask


@pytest.mark.parametrize("interrupt", [ValueError, KeyboardInterrupt])
def test_atomic_output_keeps_the_old_file_when_the_writer_fails(tmp_path, interrupt):
    target = tmp_path / "sub" / "table.csv"
    with atomic_output(target) as tmp:  # creates the folder
        tmp.write_text("old\n")
    with pytest.raises(interrupt), atomic_output(target) as tmp:
        tmp.write_text("half")
        raise interrupt("writer failed")
    assert target.read_text() == "old\n"
    assert [p.name for p in target.parent.iterdir()] == ["table.csv"]  # no temporary left


def test_atomic_output_gives_normal_permissions(tmp_path):
    """mkstemp creates the temporary file private (0o600); an output is for reading, so it
    ends with the mode of a normally created file."""
    target = tmp_path / "report.html"
    with atomic_output(target) as tmp:
        assert tmp.parent == tmp_path and tmp.name.startswith(".report.html.") and tmp.name.endswith(".tmp")
        tmp.write_text("x")
    assert target.stat().st_mode & 0o777 == 0o666 & ~current_umask()


def test_remove_stale_temporaries_takes_only_this_targets_leftovers(tmp_path):
    names = {
        ".table.csv.k1ll3d_0.tmp": False,  # a killed writer's leftover of table.csv: removed
        ".table.csv.k1ll3d_0.part": True,  # other suffix
        ".table.csv.gz.k1ll3d_0.tmp": True,  # temporary of table.csv.gz (may be writing now)
        ".other.csv.k1ll3d_0.tmp": True,  # another file's
        "table.csv": True,  # the target itself
    }
    for n in names:
        (tmp_path / n).write_bytes(b"x")
    remove_stale_temporaries(tmp_path / "table.csv", ".tmp")
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(n for n, kept in names.items() if kept)


_KILLED_WRITER = """
import os, signal, sys
sys.path.insert(0, {scripts!r})
{setup}
if {kill}:
    # a hard kill at the worst moment: the temporary file is complete, the rename not done
    os.replace = lambda src, dst: os.kill(os.getpid(), signal.SIGKILL)
{call}
"""

#: Every atomic writer of the project: (setup, call, target relative to the test's folder).
#: The call is formatted with the target, the input folder ``inputs``, the download cache
#: ``cache`` and the upstream file of the download (``url``, ``sha``).
WRITERS = {
    "write_csv": ("import pandas as pd\nfrom _helpers import write_csv",
                  "write_csv(pd.DataFrame({{'a': range(1000)}}), {target!r})", "out/table.csv"),
    "write_csv_gz": ("import pandas as pd\nfrom _helpers import write_csv",
                     "write_csv(pd.DataFrame({{'a': range(1000)}}), {target!r})", "out/table.csv.gz"),
    "save_figure": ("import matplotlib.pyplot as plt\nfrom accelcal.plotting import save_figure",
                    "save_figure(plt.figure(), {target!r})", "out/figure.png"),
    "write_json_atomic": ("from accelcal.atomic import write_json_atomic",
                          "write_json_atomic({target!r}, {{'a': 1}})", "out/manifest.json"),
    "write_report": ("from accelcal_repro.report import write_report",
                     "write_report('<!DOCTYPE html>\\n<html><body>x</body></html>\\n', {target!r})", "out/report.html"),
    "write_recording": ("import numpy as np\nfrom accelcal.formats import write_recording\nfrom accelcal.recording import Recording",
                        "write_recording({target!r}, Recording(np.arange(500.0), np.full((500, 3), 0.25), None, ''))",
                        "out/recording.csv"),
    "download": ("from accelcal_repro.measured.data import fetch_file",
                 "fetch_file('imu_tk_xsens', 'xsens_acc.mat', resources_dir={cache!r}, url={url!r}, sha256={sha!r})",
                 "cache/imu_tk_xsens/xsens_acc.mat"),
    # the script writes its report (output[0], the writer under test) and then its Summary
    # (output.summaries), as Snakemake's named output list allows: kept outside out/
    "discrepancy_measured": ("import json, os, runpy\nfrom types import SimpleNamespace\n"
                             "class Outputs(list):\n    pass",
                             "out = Outputs([{target!r}]); "
                             "out.summaries = os.path.join(os.path.dirname(os.path.dirname({target!r})), 'summaries.json'); "
                             "runpy.run_path({script!r}, init_globals={{'snakemake': SimpleNamespace(rule='r', "
                             "input=SimpleNamespace(csv={inputs!r} + '/rec.csv'), output=out, "
                             "params=SimpleNamespace(**json.load(open({inputs!r} + '/params.json'))), "
                             "log=[{inputs!r} + '/log'], wildcards=SimpleNamespace(recording='xsens_mti'))}})",
                             "out/xsens_mti.json"),
}


@pytest.fixture(scope="module")
def writer_inputs(tmp_path_factory):
    """Inputs of the writers that read something: the download's upstream file, and the
    recording and parameters of workflow/scripts/discrepancy_measured.py (a quick
    stochastic layer: its bootstrap is the cost)."""
    from accelcal_repro.discrepancy import benchmark as B
    from accelcal.discrepancy.rules import Rules
    from accelcal.formats import write_recording

    inputs = tmp_path_factory.mktemp("inputs")
    upstream = inputs / "upstream.mat"
    upstream.write_text("".join(f"{i} 1 2 3\n" for i in range(2000)))
    session = B.Session()
    rec, _ = B.simulate_case("none", 0.0, 0, seed=5, session=session, rules=Rules())
    write_recording(inputs / "rec.csv", rec)
    cfg = ci_config()["discrepancy"]
    params = {"g": session.g, "rules": cfg["rules"], "stochastic": dict(cfg["stochastic"], n_boot=19, n_resim=1)}
    (inputs / "params.json").write_text(json.dumps(params))
    return {"inputs": str(inputs), "url": upstream.as_uri(), "sha": sha256(upstream),
            "script": str(REPO / "workflow" / "scripts" / "discrepancy_measured.py")}


@pytest.mark.parametrize("writer", sorted(WRITERS))
def test_a_killed_atomic_writer_leaves_no_output_and_the_next_write_cleans_up(tmp_path, writer, writer_inputs):
    """SIGKILL skips a writer's clean-up: what it leaves is a hidden temporary file beside
    the target (never a partial target); the next write of the same file removes it, and
    only it, and writes the target whole with normal permissions."""
    setup, call, rel = WRITERS[writer]
    target = tmp_path / rel
    suffix = ".part" if writer == "download" else ".tmp"
    call = call.format(target=str(target), cache=str(tmp_path / "cache"), **writer_inputs)

    def run(kill):
        code = _KILLED_WRITER.format(scripts=str(REPO / "workflow" / "scripts"), setup=setup, call=call, kill=kill)
        return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600)

    proc = run(kill=True)
    assert proc.returncode == -signal.SIGKILL, proc.stderr
    left = sorted(p.name for p in target.parent.iterdir())
    assert not target.exists() and len(left) == 1 and TEMPORARY.match(left[0]), left
    assert left[0].startswith(f".{target.name}.") and left[0].endswith(suffix), left
    # temporaries of other files: another target's, and one of a target whose name starts
    # with this one's (its writer may be running now); neither is this writer's to remove
    others = [target.parent / f".other.csv.k1ll3d{suffix}", target.parent / f".{target.name}.gz.k1ll3d{suffix}"]
    for other in others:
        other.write_bytes(b"x")
    proc = run(kill=False)
    assert proc.returncode == 0, proc.stderr
    if writer == "download":
        assert sha256(target) == writer_inputs["sha"]
    else:
        check_whole(target)
    assert target.stat().st_mode & 0o777 == 0o666 & ~current_umask()
    assert sorted(p.name for p in target.parent.iterdir() if TEMPORARY.match(p.name)) == sorted(o.name for o in others)


# --- interrupted run: resume -------------------------------------------------------------------

#: A cheap target at CI scale: 8 Monte Carlo jobs and their gather job (about 10 s on one
#: core), as the real-SLURM tests use it.
TARGET = "results/burkhard2024/summary.csv"
_JOB = re.compile(r"^(?:local)?rule (\w+):\n((?:    .*\n)+)", re.M)


def jobs_in(text):
    """{jobid: (rule, outputs)} of the job blocks Snakemake printed."""
    out = {}
    for rule, body in _JOB.findall(text):
        fields = dict(ln.strip().split(": ", 1) for ln in body.splitlines() if ": " in ln)
        out[int(fields["jobid"])] = (rule, tuple(fields["output"].split(", ")))
    return out


def finished_jobs(text):
    return {int(j) for j in re.findall(r"^Finished jobid: (\d+)", text, flags=re.M)}


def sha256(path):
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


TEMPORARY = re.compile(r"^\..*\.(tmp|part)$")


def check_whole(path):
    """Raise if ``path`` is not a whole file of its type (a truncated file fails)."""
    name = path.name
    if name.endswith(".csv.gz"):
        with gzip.open(path, "rb") as f:  # a truncated gzip stream raises EOFError
            pd.read_csv(f)
    elif name.endswith((".csv", ".tsv")):
        # pandas parses a CSV cut mid-line too; the writers end every line with a newline
        assert path.read_bytes().endswith(b"\n"), f"{path}: ends mid-line"
        pd.read_csv(path, sep="\t" if name.endswith(".tsv") else ",")
    elif name.endswith(".json"):
        json.loads(path.read_text())
    elif name.endswith(".png"):
        assert path.read_bytes().endswith(b"IEND\xaeB`\x82"), f"{path}: PNG without its IEND trailer"
    elif name.endswith(".pdf"):
        assert path.read_bytes().rstrip().endswith(b"%%EOF"), f"{path}: PDF without its %%EOF trailer"
    elif name.endswith(".html"):
        assert path.read_bytes().rstrip().endswith(b"</html>"), f"{path}: HTML without its closing tag"
    elif name.endswith(".log"):
        pass  # logs grow line by line by design: not outputs
    else:
        raise AssertionError(f"{path}: no completeness check for this kind of file")


def test_completeness_check_rejects_truncated_files(tmp_path):
    import matplotlib.pyplot as plt

    from accelcal.plotting import save_figure

    with gzip.open(tmp_path / "t.csv.gz", "wt") as f:
        f.write("a,b\n" + "".join(f"{i},{i * i}\n" for i in range(20000)))
    png, pdf = save_figure(plt.figure(), tmp_path / "f")
    (tmp_path / "m.json").write_text('{"a": [1, 2]}')
    (tmp_path / "r.html").write_text("<!DOCTYPE html>\n<html><body>x</body></html>\n")
    pd.DataFrame({"a": [1.5, 2.25, 3.125]}).to_csv(tmp_path / "t.csv", index=False)
    for p in (tmp_path / "t.csv.gz", png, pdf, tmp_path / "m.json", tmp_path / "r.html", tmp_path / "t.csv"):
        check_whole(p)
        raw = p.read_bytes()
        p.write_bytes(raw[: len(raw) // 2])
        with pytest.raises(Exception):  # noqa: B017 (any reader error: EOFError, AssertionError, ...)
            check_whole(p)


def survey(results):
    """(whole files, temporary leftovers) under results/; every non-temporary file checked."""
    files, temporaries = [], []
    for p in sorted(results.rglob("*")):
        if p.is_file():
            if TEMPORARY.match(p.name):
                temporaries.append(p)
            else:
                check_whole(p)
                files.append(p)
    return files, temporaries


def comparable(results):
    """As test_ci_reruns_are_byte_identical: every result's sha256, except logs, benchmarks,
    wall-time measurements ("timing" in the path) and the speed claims computed from them."""
    out = {}
    for p in sorted(results.rglob("*")):
        rel = p.relative_to(results)
        if not p.is_file() or {"logs", "benchmarks"} & set(rel.parts) or "timing" in str(rel):
            continue
        if rel.parts[0] == "claims":
            ledger = pd.read_csv(p, dtype=str, keep_default_na=False)
            out[rel] = ledger[~ledger["claim_id"].str.startswith("speed_")].to_csv(index=False)
        else:
            out[rel] = sha256(p)
    return out


#: The job held at the interruption: the gather job of the Monte Carlo, held by
#: tests/hold_hook between writing its outputs (after two of them, before the third), so
#: that all 8 Monte Carlo jobs have finished and one job is certainly running when the
#: signal comes, however loaded the machine is.
HELD_RULE = "burkhard2024_summary"
HELD_OUTPUT = "results/burkhard2024/comparisons.csv"
HOLD_HOOK = Path(__file__).with_name("hold_hook")


def hold_env(fifo, output):
    """Environment that makes tests/hold_hook/sitecustomize.py hold every process renaming
    a file onto ``output`` (a glob of absolute paths) until ``fifo`` is opened and closed."""
    return {"PYTHONPATH": os.pathsep.join(filter(None, [str(HOLD_HOOK), os.environ.get("PYTHONPATH")])),
            "ACCELCAL_TEST_HOLD_FIFO": str(fifo), "ACCELCAL_TEST_HOLD_OUTPUT": output}


def open_when_held(fifo, alive, describe, safety_timeout=1800):
    """Wait until a process blocks reading ``fifo`` (held by the hook) and return the write
    end, opened: the held process stays blocked until it is closed.  ``alive()`` false
    means the run ended without reaching the hold (the test fails, saying so).  No
    timing decides anything: the timeout is a safety net against a hung run only."""
    t0 = time.monotonic()
    while True:
        try:
            # a FIFO's write end opens without blocking only while a reader has it open
            return os.open(fifo, os.O_WRONLY | os.O_NONBLOCK)
        except OSError as e:
            if e.errno != errno.ENXIO:
                raise
        assert alive(), "the run ended without reaching the held job:\n" + describe()
        assert time.monotonic() - t0 < safety_timeout, "the held job was not reached (run hung?):\n" + describe()
        time.sleep(0.05)
