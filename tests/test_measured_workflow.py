"""The measured stage's rules and figures: DAG, a clean failure on a truncated file, figure smoke tests.

The rule file is included into a throwaway Snakefile (with common.smk) in a temporary
folder, so that these tests run the measured stage alone, on a data folder of their own.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from accelcal_repro.measured.data import DATASETS
from tests.configs import ci_config

REPO = Path(__file__).resolve().parents[1]
DATA = REPO.parent / "shared" / "data"
SNAKEMAKE = Path(sys.executable).with_name("snakemake")
pytestmark = pytest.mark.skipif(not DATA.is_dir(), reason="shared/data not available")


def workflow(tmp_path, data_dir) -> Path:
    cfg = ci_config()
    cfg = {"measured": cfg["measured"]}
    cfg["measured"]["data_dir"] = str(data_dir)
    (tmp_path / "config.yaml").write_text(yaml.safe_dump(cfg))
    snakefile = tmp_path / "Snakefile"
    snakefile.write_text("import os, re\n"
                         f"include: {str(REPO / 'workflow' / 'rules' / 'common.smk')!r}\n"
                         f"include: {str(REPO / 'workflow' / 'rules' / 'kernels.smk')!r}\n"  # the compile job
                         f"include: {str(REPO / 'workflow' / 'rules' / 'measured.smk')!r}\n")
    return snakefile


def run(tmp_path, data_dir, *targets):
    sf = workflow(tmp_path, data_dir)
    cmd = [str(SNAKEMAKE), "-s", str(sf), "--directory", str(tmp_path / "work"), "--configfile",
           str(tmp_path / "config.yaml"), "--cores", "1", "--scheduler", "greedy", *targets]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=300)


def test_dag_has_every_figure_target_and_the_claims(tmp_path):
    # the figure targets by name in the same dry run: a name that is not a rule without
    # wildcards (what --list-target-rules lists) fails it ("No rule to produce ...")
    p = run(tmp_path, DATA, "-n", "measured", "measured_static_detection", "measured_calibration",
            "measured_residuals")
    assert p.returncode == 0, p.stderr[-3000:]
    out = p.stdout + p.stderr
    for rule in ("measured_fetch", "measured_calibrate", "measured_peer", "measured_tables",
                 "measured_claims", "measured_figures"):
        assert rule in out, rule


def test_truncated_recording_fails_the_fetch_with_one_line(tmp_path):
    shared = tmp_path / "shared"
    for d in ("imu_tk_xsens",):
        (shared / d).mkdir(parents=True)
        raw = (DATA / d / "xsens_acc.mat").read_bytes()
        (shared / d / "xsens_acc.mat").write_bytes(raw[: len(raw) // 3])
    for d in DATASETS:  # the others intact: the parse-time check passes offline
        if d != "imu_tk_xsens":
            (shared / d).symlink_to(DATA / d)
    p = run(tmp_path, shared, "results/measured/xsens_mti.csv")
    assert p.returncode != 0
    log = (tmp_path / "work" / "results" / "logs" / "measured" / "fetch_xsens_mti.log").read_text()
    assert "DatasetError" in log and "does not match the expected" in log
    assert not (tmp_path / "work" / "results" / "measured" / "xsens_mti.csv").exists()
    assert not (tmp_path / "work" / "results" / "measured" / "data" / "xsens_mti.json").exists()


def test_figures_from_real_tables(tmp_path):
    import pandas as pd

    from accelcal_repro.measured.calibrate import calibrate_recording
    from accelcal_repro.measured.figures import plot_calibration, plot_residuals, plot_static_detection
    from accelcal_repro.measured.sources import fetch_source, read_source, section_list
    from accelcal.plotting import save_figure

    mcs, recs = [], {}
    for name, g, est in (("mpu6050", 9.80665, ["full_lls", "bias_lls"]), ("imucal_ferraris", 9.81, ["bias_lls"])):
        paths = fetch_source(name, DATA)
        rec = read_source(name, paths)
        recs[name] = (rec.t, rec.acc)
        mcs.append(calibrate_recording(name, rec, g=g, estimators=est, sections=section_list(name, paths), n_boot=5))
    cat = {t: pd.concat([getattr(m, t) for m in mcs], ignore_index=True) for t in ("poses", "params", "pose_errors")}
    figs = {"static": plot_static_detection(recs, cat["poses"]), "cal": plot_calibration(cat["params"]),
            "res": plot_residuals(cat["pose_errors"])}
    titles = [ax.get_title(loc="left") for ax in figs["static"].axes]
    assert titles == ["MPU-6050: 10 rests detected, 10 used as poses",
                      "imucal Ferraris session: 13 rests detected, 6 used as poses"]
    assert len(figs["cal"].axes) == 6 and len(figs["cal"].legends) == 1
    res_titles = {ax.get_title(loc="left") for ax in figs["res"].axes}
    assert "imucal Ferraris session: full model" in res_titles
    for k, fig in figs.items():
        png, pdf = save_figure(fig, tmp_path / k)
        assert png.stat().st_size > 5000 and pdf.stat().st_size > 5000
