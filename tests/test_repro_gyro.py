"""Tests of the reproductions' gyroscope code (accelcal_repro.gyro) against the core's: the
CTU rig's record against the logic of its repository's script, the imucal example against
imucal run as a package, the Monte Carlo of the intervals' coverage and the claims that judge
it.  The core's own gyro tests (test_gyro_*.py) import no reproduction."""

from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path

import numpy as np
import pytest

from accelcal import cli
from accelcal.formats import read
from accelcal.gyro.rotations import calibrate_rotations

CTU = Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "ctu_ferraris" / "measured_angular_rates.mat"
CTU_ANGLES = (361.338, 367.160, 363.6703)


def _cli(*args) -> tuple[int, str]:
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        code = cli.main([str(a) for a in args])
    return code, err.getvalue()


@pytest.fixture(scope="module")
def ctu():
    if not CTU.is_file():
        pytest.skip("../shared/data/ctu_ferraris is absent")
    return read(CTU, variable="x_rotation,y_rotation,z_rotation", columns="gx=1,gy=2,gz=3", rate=100.0,
                gyro_unit="deg/s")


def test_ctu_agrees_with_its_scripts_logic_and_pooling_the_biases_does_not(ctu):
    """The repository's script: offsets from samples 1-2000, its integration windows (the data
    README); ours: each run's rests before and after, the windows found.  Within 1.2 s.e.; with
    the three runs' biases pooled into one, T_zx moves by more than 4 s.e."""
    from accelcal_repro.gyro.ferraris_sessions import ctu_calibration

    per = calibrate_rotations(ctu.t, ctu.gyro, angles_deg=CTU_ANGLES, runs=ctu.runs)
    script = ctu_calibration(CTU).set_index("parameter")
    se_s, se_T = per.standard_errors["scale_factors"], per.standard_errors["T"]
    for a in range(3):
        assert abs(1e6 * per.scale_factors[a] - script.loc[f"s_{'xyz'[a]}", "value"]) < 1.2 * 1e6 * se_s[a]
        for b in range(3):
            if a != b:
                assert abs(1e3 * per.model.T[a, b] - script.loc[f"T_{'xyz'[a]}{'xyz'[b]}", "value"]) < 1.2e3 * se_T[a, b]
    assert [r["samples"] for r in per.settings["runs"]] == [[0, 4001], [4001, 8002], [8002, 12003]]
    pooled = calibrate_rotations(ctu.t, ctu.gyro, angles_deg=CTU_ANGLES)
    assert abs(pooled.model.T[2, 0] - per.model.T[2, 0]) > 4 * se_T[2, 0]


def test_a_section_list_gives_the_ctu_scripts_windows_and_offsets_exactly(ctu, tmp_path):
    """--intervals with the script's offsets (samples 1-2000 of each run) and windows (*_rot,
    the README's, in samples of the joined runs): the script's logic from the command line."""
    from accelcal_repro.gyro.ferraris_sessions import ctu_calibration

    sections = {"x_p": (0, 2000), "x_rot": (2419, 2910), "y_p": (4001, 6001), "y_rot": (6565, 7121),
                "z_p": (8002, 10002), "z_rot": (10976, 11502)}
    path = tmp_path / "sections.json"
    path.write_text(json.dumps({k: {"start": a, "end": b} for k, (a, b) in sections.items()}))
    out = tmp_path / "ctu.json"
    code, err = _cli("calibrate", CTU, "--variable", "x_rotation,y_rotation,z_rotation", "--columns", "gx=1,gy=2,gz=3",
                     "--rate", "100", "--gyro-unit", "deg/s", "--rotation-angle", ",".join(map(str, CTU_ANGLES)),
                     "--intervals", path, "--out", out)
    assert code == 0, err
    g = json.loads(out.read_text())["gyroscope"]
    script = ctu_calibration(CTU).set_index("parameter")
    scale = np.diag(np.array(g["model"]["C"])) - 1.0  # nominal 1 rad/s per rad/s
    np.testing.assert_allclose(1e6 * scale, script.loc[["s_x", "s_y", "s_z"], "value"], rtol=1e-9)
    assert g["motions"]["window"] == [[2419, 2910], [6565, 7121], [10976, 11502]]
    sections["y_rot"] = (6565, 8100)  # into the third run
    path.write_text(json.dumps({k: {"start": a, "end": b} for k, (a, b) in sections.items()}))
    code, err = _cli("calibrate", CTU, "--variable", "x_rotation,y_rotation,z_rotation", "--columns", "gx=1,gy=2,gz=3",
                     "--rate", "100", "--gyro-unit", "deg/s", "--rotation-angle", "360", "--intervals", path, "--out",
                     tmp_path / "bad.json")
    assert code == 2 and "spans two runs" in err and not (tmp_path / "bad.json").exists()



def test_imucal_example_matches_imucal():
    """accelcal's Ferraris fit, the command line's route (the session's reader at imucal's 102.4 Hz,
    its section list), against imucal run as a package on the same files."""
    pytest.importorskip("imucal")
    from accelcal_repro.gyro.ferraris_sessions import in_raw_unit, run_imucal
    from accelcal_repro.gyro.sessions import SESSIONS, calibrate_session, local_paths

    spec = SESSIONS["imucal_ferraris"]
    paths = local_paths([spec.name])
    r = calibrate_session(spec, paths)
    ours = r["gyro"]
    im = run_imucal(paths[spec.dataset][spec.acc], paths[spec.dataset][spec.intervals])
    from accelcal.gyro.model import GyroModel

    theirs = in_raw_unit(GyroModel.from_imucal(im["K_g"], im["R_g"], im["b_g"]), "rad/s")
    z = (theirs.C - ours.model.C) / ours.standard_errors["C"]
    # the same sums; imucal also removes its g-sensitivity K_ga a during the turns
    assert np.abs(z).max() < 3
    # imucal: the plain mean of all rest samples; accelcal: the rests' means weighted by their noise
    assert np.abs((ours.model.bias - theirs.bias) / ours.standard_errors["bias"]).max() < 0.5
    # the turns integrate to 360 deg at the rate the reader assumes (at 204.8 Hz: about 180)
    np.testing.assert_allclose(ours.settings["nominal_angles_deg"], 360.0, rtol=0.05)



def test_intervals_cover_in_a_small_monte_carlo_with_a_wandering_bias():
    # the full check (0.93-0.97 over 400 trials) is the workflow's claim gyro/interval_coverage;
    # here 10 sessions (90 draws; 300: 0.94 with the noise model, 0.78 with the rest noise alone)
    from accelcal_repro.gyro.coverage import SESSION, coverage, summary

    df = coverage(10, 4, dict(SESSION, acc_noise=0.05))
    new = df[df.noise_model]
    assert np.all(np.isfinite(new.se) & (new.se > 0))
    assert np.all(new.half_width >= 1.96 * new.se)  # t quantiles at finite degrees of freedom
    assert np.all(df[~df.noise_model].half_width <= 1.9600001 * df[~df.noise_model].se)
    s = summary(df).set_index(["noise_model", "parameter"])
    assert s.loc[(True, "all"), "coverage"] >= 0.85, s.loc[(True, "all")]
    assert s.loc[(False, "all"), "coverage"] < 0.9, s.loc[(False, "all")]  # the rest noise alone: too narrow


def test_coverage_and_stability_claims_judge_their_tables():
    import pandas as pd

    from accelcal_repro.gyro.stage import _coverage_claim, _stability_claim

    def cov(c):
        return pd.DataFrame([{"noise_model": True, "parameter": "all", "n": 3600, "coverage": c, "coverage_se": 0.004}])
    assert _coverage_claim(cov(0.95))["verdict"] == "reproduced"
    assert _coverage_claim(cov(0.91))["verdict"] == "not_reproduced"
    assert _coverage_claim(cov(0.95).assign(n=90))["verdict"] == "not_testable_at_this_scale"
    stab = pd.DataFrame([{"group": "g", "parameter": k, "chi2_per_dof": v, "noise_model": True}
                         for k, v in (("s_*", 1.5), ("T_*", 0.7))])
    assert _stability_claim(stab)["verdict"] == "reproduced"
    assert _stability_claim(stab.assign(chi2_per_dof=[2.4, 0.7]))["verdict"] == "not_reproduced"
