"""The Snakemake workflow: the whole CI configuration end to end, broken configs, dry run,
and deterministic figures.  Generic across stages: each stage's own tables are tested in
tests/test_<stage>_*.py."""

from pathlib import Path

import pandas as pd
import pytest
import yaml

from accelcal_repro.claims import COLUMNS, PAPERS, VERDICTS, verdict_changes
from accelcal.plotting import RC, save_figure

from tests.configs import ci_config

from .conftest import config_error, run_snakemake

REPO = Path(__file__).resolve().parents[1]
CI = REPO / "config" / "ci.yaml"
snakemake = run_snakemake  # the repository's workflow with a working directory (tests/conftest.py)


@pytest.fixture(scope="module")
def ci_run(ci_workflow):
    """The session's CI run (tests/conftest.py); the forced-rerun test works on a copy."""
    return ci_workflow


def test_ci_workflow_makes_every_figure_and_target(ci_run):
    workdir, _, elapsed = ci_run
    figures = workdir / "results" / "figures"
    ids = {p.stem for p in figures.glob("*.png")}
    for paper in PAPERS:  # every paper has figures
        assert any(fid.startswith(paper) for fid in ids), paper
    for fid in ids:
        for ext in ("png", "pdf"):
            f = figures / f"{fid}.{ext}"
            assert f.stat().st_size > 5000, f
    assert not list(figures.glob(".*tmp")), "temporary files left behind"
    # every figure id as a target: a target rule of the same name (a name that is not a
    # rule without wildcards fails the dry run: "No rule to produce ..."), already up to date
    proc = snakemake(workdir, "-n", *sorted(ids), "--configfile", CI)
    out = proc.stdout + proc.stderr
    assert proc.returncode == 0, f"a figure has no target rule of the same name:\n{out[-3000:]}"
    assert "Nothing to be done" in out
    # the CI budget (well under 2-3 minutes on 2 cores) is reported, not asserted: a loaded
    # machine must not fail the tests
    print(f"CI workflow wall time: {elapsed:.1f} s")


def test_ci_workflow_claims_ledger(ci_run):
    workdir = ci_run[0]
    ledger = pd.read_csv(workdir / "results" / "claims.csv", dtype=str, keep_default_na=False)
    assert list(ledger.columns) == list(COLUMNS)
    assert set(ledger["paper"]) <= set(PAPERS) and set(ledger["verdict"]) <= set(VERDICTS)
    assert set(PAPERS) <= set(ledger["paper"])  # every paper has claims
    assert not ledger.duplicated(["paper", "claim_id"]).any()
    for _, r in ledger.iterrows():  # evidence names a table that exists
        if r["verdict"] != "not_reproducible":
            assert (workdir / r["evidence"].split(":")[0]).is_file(), r["evidence"]
    # the ledger is the concatenation of the stages' files
    stages = sorted((workdir / "results" / "claims").glob("*.csv"))
    assert sum(len(pd.read_csv(f)) for f in stages) == len(ledger)


def test_ci_verdicts_match_the_expected_verdicts(ci_run):
    """The CI reproduction check: every claim has a computed verdict and none differs from
    tests/expected_verdicts.ci.csv (rewrite it with tools/expected_verdicts.py only after
    reading why a verdict changed)."""
    ledger = pd.read_csv(ci_run[0] / "results" / "claims.csv", dtype=str, keep_default_na=False)
    assert (ledger["verdict"] != "").all()
    expected = pd.read_csv(REPO / "tests" / "expected_verdicts.ci.csv", dtype=str, keep_default_na=False)
    changes = verdict_changes(ledger, expected)
    assert not changes, "claims ledger differs from the expected verdicts:\n" + "\n".join(changes)


# The ledger script run standalone on a copy of the CI run: tests/test_workflow_structure.py::
# test_a_script_run_standalone_rebuilds_the_workflows_output (byte for byte).


def broken_configs():
    neg = ci_config()
    neg["burkhard2024"]["trials"] = -5
    wrong_type = ci_config()
    wrong_type["burkhard2024"]["experiments"]["fig1a"]["noise_std"] = "1e-3"
    missing = ci_config()
    del missing["burkhard2024"]["g"]
    inverted = ci_config()
    inverted["burkhard2024"]["truth"]["bias_range_mg"] = [1.3, 0.9]
    unknown = ci_config()
    unknown["burkhard2024"]["experiments"]["lls_limit"]["methods"] = ["full_lls", "full_nlls", "full_als", "magic"]
    no_stage = ci_config()
    del no_stage["tereshkov"]
    headline = ci_config()
    headline["burkhard2024"]["timing"]["headline_n_poses"] = 33
    return {
        "negative_trials": (neg, "burkhard2024.trials: -5 is less than the minimum of 1"),
        "wrong_type": (wrong_type, "burkhard2024.experiments.fig1a.noise_std: '1e-3' is not of type 'array'"),
        "missing_key": (missing, "burkhard2024: 'g' is a required property"),
        "inverted_range": (inverted, "burkhard2024.truth.bias_range_mg: low end 1.3 exceeds high end 0.9"),
        "unknown_method": (unknown, "burkhard2024.experiments.lls_limit.methods.3: 'magic' is not a registered estimator; known: full_lls"),
        "missing_stage": (no_stage, "(top level): 'tereshkov' is a required property"),
        "cross_field_rule": (headline, "burkhard2024.timing.headline_n_poses: 33 is not in n_poses"),
    }


@pytest.mark.parametrize("case", sorted(broken_configs()))
def test_broken_config_is_rejected_with_its_key_and_what_is_wrong(tmp_path, case):
    """Rejected while the Snakefile is parsed (in this process, tests/conftest.config_error),
    in one line naming the file, the key and what is wrong."""
    cfg, message = broken_configs()[case]
    path = tmp_path / "broken.yaml"
    error = config_error(cfg, path)
    assert error is not None and "\n" not in error and error.startswith("invalid config"), error
    assert str(path) in error and message in error, error


@pytest.mark.parametrize("case", ["missing_stage", "cross_field_rule"])
def test_broken_config_fails_before_any_job(tmp_path, case):
    cfg, message = broken_configs()[case]
    path = tmp_path / "broken.yaml"
    path.write_text(yaml.safe_dump(cfg))
    workdir = tmp_path / "work"
    workdir.mkdir()
    # replace (not extend) the default config, so that a missing key stays missing
    proc = snakemake(workdir, "all", "--configfile", path, "--replace-workflow-config", timeout=120)
    assert proc.returncode != 0
    out = proc.stdout + proc.stderr  # Snakemake logs to stderr, to stdout in a dry run
    lines = [ln for ln in out.splitlines() if ln.startswith("invalid config")]
    assert len(lines) == 1, out
    assert str(path) in lines[0] and message in lines[0], lines[0]
    assert not (workdir / "results").exists(), "a job ran despite the broken config"


def test_broken_config_overlay_on_the_default_also_fails(tmp_path):
    path = tmp_path / "overlay.yaml"
    path.write_text("burkhard2024:\n  trials: 0\n")
    proc = snakemake(tmp_path, "-n", "all", "--configfile", path, timeout=120)
    assert proc.returncode != 0
    assert "burkhard2024.trials: 0 is less than the minimum of 1" in proc.stdout + proc.stderr


def test_dry_run_on_the_default_config(default_dry_run):
    """The Snakefile's default config (config/config.yaml) passes its checks and plans the
    whole workflow (also the default-config case of tests/test_config_schemas.py; the dry
    run is the session's, tests/conftest.py, which tests/test_burkhard2024_workflow.py reads too)."""
    workdir, error, jobs = default_dry_run
    assert error is None, error
    assert jobs["claims"] == 1 and jobs["all"] == 1  # the ledger job
    assert not (workdir / "results").exists()


def test_ci_config_has_the_keys_of_the_default():
    def keys(d, prefix=""):
        out = set()
        for k, v in d.items():
            out.add(prefix + k)
            if isinstance(v, dict):
                out |= keys(v, prefix + k + ".")
        return out

    default = yaml.safe_load((REPO / "config" / "config.yaml").read_text())
    overlay = yaml.safe_load(CI.read_text())
    assert keys(overlay) <= keys(default), "config/ci.yaml adds keys the default does not have"
    assert keys(ci_config()) == keys(default)


def test_save_figure_is_byte_identical_on_rerun(tmp_path):
    import matplotlib.pyplot as plt
    import numpy as np

    def figure():
        with plt.rc_context(RC):
            fig, ax = plt.subplots(layout="constrained")
            x = np.logspace(-7, -3, 5)
            ax.loglog(x, 0.6 * x, marker="o", label="RMS")
            ax.set(xlabel="noise std [m/s²]", title="a figure")
            ax.legend()
        return fig

    out = {}
    for run in ("a", "b"):
        (tmp_path / run).mkdir()
        paths = [*save_figure(figure(), tmp_path / run / "one"), *save_figure(figure(), tmp_path / run / "two.png")]
        out[run] = {p.name: p.read_bytes() for p in paths}
    assert sorted(out["a"]) == ["one.pdf", "one.png", "two.pdf", "two.png"]
    assert out["a"] == out["b"]
    assert out["a"]["one.png"].startswith(b"\x89PNG") and out["a"]["one.pdf"].startswith(b"%PDF")
    assert b"CreationDate" not in out["a"]["one.pdf"]
    assert sorted(p.name for p in (tmp_path / "a").iterdir()) == sorted(out["a"])  # no temp files left
