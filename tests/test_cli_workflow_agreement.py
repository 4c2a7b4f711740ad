"""`accelcal calibrate` and the measured stage give the same numbers, to the last digit.

Both read the original file with :func:`accelcal.formats.read` and fit with
:func:`accelcal.calibration.calibrate_poses`; this checks that nothing in between (the
stage's pose selection, unit conversion, table writing, the CLI's JSON) changes a bit.
The stage side is :func:`accelcal_repro.measured.calibrate.calibrate_recording` with the
configured g and estimators, its tables written with the workflow's CSV writer and read
back.  The CLI side runs ``accelcal calibrate`` in this process on the original file with
no option but ``--g`` and ``--method``.

The bias-only models on raw counts are fitted through the nominal sensitivity by the stage;
the CLI refuses them without ``--sensitivity`` (tested) and matches the stage with the data
sheet's numbers given (``--sensitivity 16384`` counts per g for the MPU-6050,
``--sensitivity 415,413,415/m/s2 --zero 32768`` for the Xsens).  The imucal session's
configured pose selection uses its section list; the stage's ``pose_selection='all'``
(every detected rest, what the CLI does) is compared instead.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from accelcal import cli
from accelcal.registry import ESTIMATORS
from accelcal_repro.measured.calibrate import calibrate_recording
from accelcal_repro.measured.sources import SOURCES, fetch_source, read_source, section_list
from tests.configs import load_config

REPO = Path(__file__).resolve().parents[1]
DATA = REPO.parent / "shared" / "data"
pytestmark = pytest.mark.skipif(not DATA.is_dir(), reason="shared/data not available")
sys.path.insert(0, str(REPO / "workflow" / "scripts"))
from _helpers import write_csv  # noqa: E402  (the workflow's CSV writer)

CONFIG = load_config()["measured"]["recordings"]


def _stage_tables(name, tmp_path):
    s = CONFIG[name]
    paths = fetch_source(name, DATA)
    selection = "all" if name == "imucal_ferraris" else s.get("pose_selection", "section_list")
    mc = calibrate_recording(name, read_source(name, paths), g=float(s["g"]), estimators=list(s["estimators"]),
                             sections=section_list(name, paths), pose_selection=selection, n_boot=0)
    out = {}
    for t in ("params", "summary"):
        write_csv(getattr(mc, t), tmp_path / f"{t}.csv")
        out[t] = pd.read_csv(tmp_path / f"{t}.csv")
    return out


#: The data sheet's numbers, as a user would pass them (the stage's nominal conversions).
NOMINAL = {"xsens_mti": ["--sensitivity", "415,413,415/m/s2", "--zero", "32768"],
           "mpu6050": ["--sensitivity", "16384"]}


def _cli(name, method, tmp_path, capsys, *extra):
    src = SOURCES[name]
    out = tmp_path / f"{method}.json"
    code = cli.main(["calibrate", str(DATA / src.dataset / src.data_file), "--g", str(CONFIG[name]["g"]),
                     "--method", ESTIMATORS[method].cli_name, "--out", str(out), *extra])
    err = capsys.readouterr().err
    return code, err, (json.loads(out.read_text()) if code == 0 else None)


@pytest.mark.parametrize("name", sorted(SOURCES))
def test_cli_json_equals_the_workflow_tables(name, tmp_path, capsys):
    tables = _stage_tables(name, tmp_path)
    params = tables["params"].set_index(["estimator", "parameter"])["value"]
    summary = tables["summary"].set_index("estimator")
    compared = 0
    for method in CONFIG[name]["estimators"]:
        e = ESTIMATORS[method]
        code, err, js = _cli(name, method, tmp_path, capsys)
        nominal = e.model == "bias" and SOURCES[name].unit == "counts"
        if nominal:
            assert code == 2 and "raw counts" in err and "full-lls" in err, err
            code, err, js = _cli(name, method, tmp_path, capsys, *NOMINAL[name])
        assert code == 0, err
        assert js["n_poses"] == summary.loc[method, "n_poses"]
        # the stage tabulates the bias in the file's unit: offset + sensitivity * b
        bias = np.asarray(js["input"]["offset"]) + np.asarray(js["input"]["sensitivity"]) * np.asarray(js["bias"])
        for k, a in enumerate("xyz"):
            assert bias[k] == params[(method, f"bias_{a}")], (method, a)
        if e.model == "full":
            for k, a in enumerate("xyz"):
                assert 1.0 + js["scale_factors"][k] == params[(method, f"sensitivity_{a}")], (method, a)
            for k, a in enumerate(("xy", "zx", "zy")):
                assert js["nonorthogonality_deg"][k] == params[(method, f"nonorth_{a}")], (method, a)
        row = summary.loc[method]
        q = js["quality"]
        assert js["residual_rms"] == row["residual_rms"]
        assert (q["chi2"], q["dof"], q["p_value"]) == (row["chi2"], row["dof"], row["p_value"])
        assert q["excess"] == row["excess"]
        compared += 1
    assert compared >= 1


def test_als_noise_level_is_the_rests_in_both(tmp_path, capsys):
    """ALS is given the RMS of the pose-mean standard errors (the rests), in the CLI too."""
    code, _, js = _cli("xsens_mti", "full_als", tmp_path, capsys)
    assert code == 0 and js["noise_source"].startswith("rests")
    mean_std = np.asarray(js["poses"]["mean_std"])
    assert js["noise_var"] == pytest.approx(np.mean(mean_std ** 2), rel=1e-12)
