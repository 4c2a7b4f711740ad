"""Calibration of the real recordings (shared/data): poses, estimators, evaluation, failures.

Skipped when shared/data is absent.  Bootstrap sizes are small here (the workflow's
default config uses 1000 replicates).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from accelcal.errors import AccelcalError, RecordingError, TooFewPosesError
from accelcal_repro.measured.calibrate import FULL_PARAMETERS, calibrate_recording
from accelcal_repro.measured.data import DatasetError, fetch_file
from accelcal_repro.measured.sources import convert, fetch_source, read_source, section_list, source

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
pytestmark = pytest.mark.skipif(not DATA.is_dir(), reason="shared/data not available")
ALL = ["full_lls", "full_als", "full_nlls", "bias_lls", "bias_nlls"]
G = {"xsens_mti": 9.81744, "mpu6050": 9.80665, "imucal_ferraris": 9.81, "imutk_fork_data2": 9.80665,
     "imutk_fork_data3": 9.80665, "imutk_fork_data4": 9.80665, "fxos8700_sample1": 9.80665,
     "fxos8700_sample2": 9.80665}


def run(name, estimators, n_boot=40, seed=7, **kw):
    paths = fetch_source(name, DATA)
    return calibrate_recording(name, read_source(name, paths), g=G[name], estimators=estimators,
                               sections=section_list(name, paths), n_boot=n_boot, seed=seed, **kw)


@pytest.fixture(scope="module")
def xsens():
    return run("xsens_mti", ALL)


@pytest.fixture(scope="module")
def mpu():
    return run("mpu6050", ALL)


@pytest.fixture(scope="module")
def imucal():
    return run("imucal_ferraris", ["bias_lls", "bias_nlls"])


# --------------------------------------------------------------------------- Xsens


def test_xsens_has_at_least_30_static_poses(xsens):
    assert len(xsens.poses) >= 30 and xsens.poses.used.all()
    assert set(xsens.summary.n_poses) == {len(xsens.poses)}


def test_xsens_sensitivities_within_1_percent_of_nominal(xsens):
    """Nominal 415/413/415 counts per m/s² (imu_tk_matlab, data README): a sanity check."""
    nom = xsens.nominal
    assert set(nom.estimator) == {"full_lls", "full_als", "full_nlls"} and len(nom) == 9
    assert (nom.rel_diff_pct.abs() < 1.0).all(), nom
    assert np.allclose(nom.nominal.to_numpy()[:3], 415.0) and (nom.axis == "y").sum() == 3


def test_xsens_residual_rms_is_bounded_by_the_pose_noise(xsens):
    """Bound: residual RMS below 3x what the pose noise alone predicts for the fitted
    residuals, sqrt(mean σ_r²·(n - q)/n), and below one count (1/415 m/s²).

    σ_r of each pose comes from the standard errors of its mean (static detection, with
    the autocorrelation), ~0.15 counts: the noise predicts ~0.5 mm/s².  The session
    shows ~2x that (hand-placed poses, effects the 9-parameter model lacks), so 3x
    leaves room for those and still fails if a pose mean is contaminated by motion or
    the units are mixed up (one count RMS would be 6x the noise).
    """
    s = xsens.summary.set_index("estimator")
    for est in ("full_lls", "full_als", "full_nlls"):
        r = s.loc[est]
        assert r.residual_rms < 1.0 / 415.0
        assert r.rms_ratio < 3.0, (est, r.rms_ratio)
        assert 1.0 < r.excess < 5.0  # the residuals do exceed the noise: reported, not hidden
        assert r.dof == r.n_poses - 9 and 0 <= r.p_value < 1e-6


def test_xsens_full_estimators_agree_and_bias_only_does_not(xsens):
    ag = xsens.agreement
    full = ag[ag.estimator_a.str.startswith("full") & ag.estimator_b.str.startswith("full")]
    assert len(full) == 3 * 9
    # on the same 38 poses the three full estimators differ by < 5 % of a parameter's bootstrap se
    se = xsens.params[xsens.params.estimator == "full_lls"].set_index("parameter").boot_se
    assert (full["diff"].abs().to_numpy() < 0.05 * se[full.parameter].to_numpy()).all()
    s = xsens.summary.set_index("estimator")
    # M = I with the nominal sensitivity leaves residuals tens of times the full model's
    assert s.loc["bias_lls", "residual_rms"] > 10 * s.loc["full_lls", "residual_rms"]


def test_xsens_lopo_and_bootstrap(xsens):
    s = xsens.summary.set_index("estimator")
    pe = xsens.pose_errors
    for est in ALL:
        assert s.loc[est, "lopo_n"] == len(xsens.poses) and s.loc[est, "lopo_note"] == ""
        assert s.loc[est, "boot_valid_fraction"] == 1.0 and s.loc[est, "ci_method"] == "bootstrap_percentile"
    # predicting a left-out pose is worse than fitting it, but of the same order
    assert s.loc["full_lls", "residual_rms"] < s.loc["full_lls", "lopo_rms"] < 3 * s.loc["full_lls", "residual_rms"]
    assert np.isfinite(pe[pe.estimator == "full_lls"].lopo_error).all()
    p = xsens.params
    assert list(p[p.estimator == "full_lls"].parameter) == list(FULL_PARAMETERS)
    assert ((p.ci_low <= p.value) & (p.value <= p.ci_high)).all()


def test_xsens_bootstrap_is_reproducible_from_the_seed():
    a = run("xsens_mti", ["full_lls"], n_boot=30, seed=1).params
    b = run("xsens_mti", ["full_lls"], n_boot=30, seed=1).params
    c = run("xsens_mti", ["full_lls"], n_boot=30, seed=2).params
    assert a.equals(b)
    assert not np.allclose(a.ci_low, c.ci_low)


# --------------------------------------------------------------------------- MPU-6050 and imucal


def test_mpu6050_ten_poses_full_model_cannot_be_cross_validated(mpu):
    s = mpu.summary.set_index("estimator")
    assert (s.n_poses == 10).all()
    for est in ("full_lls", "full_als", "full_nlls"):
        assert s.loc[est, "dof"] == 1 and s.loc[est, "lopo_n"] == 0
        assert s.loc[est, "lopo_note"].startswith("not possible")
        assert s.loc[est, "boot_valid_fraction"] < 0.01 and s.loc[est, "ci_method"] == "linearised_noise"
    for est in ("bias_lls", "bias_nlls"):
        assert s.loc[est, "lopo_n"] == 10 and s.loc[est, "ci_method"] == "bootstrap_percentile"
    p = mpu.params
    assert np.isfinite(p[["ci_low", "ci_high"]]).all().all()
    # the sensitivities are counts per m/s² near 16384 counts per g
    sens = p[p.parameter.str.startswith("sensitivity")].value
    assert ((sens > 0.95 * 16384 / 9.80665) & (sens < 1.05 * 16384 / 9.80665)).all()


def test_imucal_uses_the_six_listed_positions(imucal):
    po = imucal.poses
    assert len(po) >= 6
    used = po[po.used]
    assert list(used.label) == ["x_p", "x_a", "y_p", "y_a", "z_p", "z_a"]
    allp = run("imucal_ferraris", ["bias_lls"], n_boot=0, pose_selection="all")
    assert allp.summary.n_poses.iloc[0] == len(po)


def test_imucal_full_model_is_refused_with_the_recording_named():
    with pytest.raises(TooFewPosesError, match=r"imucal_ferraris, full_lls: 6 static poses.*at least 10"):
        run("imucal_ferraris", ["full_lls"], n_boot=0)


def test_unknown_estimator():
    with pytest.raises(AccelcalError, match="unknown estimator"):
        run("mpu6050", ["full-lls"], n_boot=0)


# --------------------------------------------------------------------------- truncated files


def test_truncated_shared_copy_fails_at_the_checksum(tmp_path):
    d = tmp_path / "imu_tk_xsens"
    d.mkdir()
    full = (DATA / "imu_tk_xsens" / "xsens_acc.mat").read_bytes()
    (d / "xsens_acc.mat").write_bytes(full[: len(full) // 2])
    with pytest.raises(DatasetError, match="sha256 .* does not match") as e:
        fetch_file("imu_tk_xsens", "xsens_acc.mat", tmp_path, tmp_path / "res")
    assert "\n" not in str(e.value)


@pytest.mark.parametrize("name", ["xsens_mti", "mpu6050"])
def test_file_cut_mid_line_fails_cleanly_and_writes_nothing(tmp_path, name):
    src = source(name)
    text = (DATA / src.dataset / src.data_file).read_text()
    cut = tmp_path / src.data_file
    cut.write_text(text[: len(text) // 2 + 3])  # mid-line
    out = tmp_path / "out.csv"
    bad_line = r"(missing value|non-numeric value|empty field).* at line \d+|line \d+ has \d+ fields where"
    with pytest.raises(RecordingError, match=bad_line) as e:
        convert(name, {src.data_file: cut}, out)
    assert "\n" not in str(e.value) and not out.exists()


def test_file_cut_after_a_few_poses_fails_cleanly(tmp_path):
    lines = (DATA / "imu_tk_xsens" / "xsens_acc.mat").read_text().splitlines(True)
    cut = tmp_path / "xsens_acc.mat"
    cut.write_text("".join(lines[:8000]))  # 80 s: the initial rest and two poses
    rec = read_source("xsens_mti", {"xsens_acc.mat": cut})
    with pytest.raises(TooFewPosesError, match="xsens_mti, full_lls: 3 static poses"):
        calibrate_recording("xsens_mti", rec, g=9.81744, estimators=["full_lls"], n_boot=0)


# --------------------------------------------------------------------------- fork sessions, FXOS8700 block logs


@pytest.mark.parametrize("name", ["imutk_fork_data2", "imutk_fork_data3", "imutk_fork_data4"])
def test_fork_sessions_fall_back_to_the_quietest_stretch_and_find_20_poses(name):
    """The three sessions of one IMU do not start at rest; the detection says so and still
    finds at least 20 poses in at least 18 distinct orientations (data README: 40/29/22)."""
    mc = run(name, ["full_lls", "bias_lls"], n_boot=0)
    p = mc.poses
    assert len(p) >= 20 and p.used.all() and set(p.noise_reference) == {"quietest_stretch"}
    z = p[["mean_x", "mean_y", "mean_z"]].to_numpy()
    u = z / np.linalg.norm(z, axis=1, keepdims=True)
    distinct = []
    for v in u:
        if all(v @ w < np.cos(np.deg2rad(10)) for w in distinct):
            distinct.append(v)
    assert len(distinct) >= 18
    full = mc.summary.set_index("estimator").loc["full_lls"]
    assert full.dof == len(p) - 9 and full.residual_rms < 0.005  # m/s²: a few mm/s², like the pose noise


def test_fork_sessions_are_one_sensor():
    """Same IMU in three sessions: the z bias agrees to within 10 mm/s² (README: ≈ -0.105 m/s²)."""
    bz = [run(n, ["full_lls"], n_boot=0).params.set_index("parameter").loc["bias_z", "value"]
          for n in ("imutk_fork_data2", "imutk_fork_data3", "imutk_fork_data4")]
    assert np.ptp(bz) < 0.01 and -0.12 < np.mean(bz) < -0.09


@pytest.mark.parametrize("name, blocks", [("fxos8700_sample1", 18), ("fxos8700_sample2", 20)])
def test_fxos8700_blocks_are_the_poses(name, blocks):
    mc = run(name, ["full_lls", "bias_lls"], n_boot=0)
    p = mc.poses
    assert len(p) == blocks and p.used.all() and set(p.noise_reference) == {"known_intervals"}
    np.testing.assert_array_equal(p.stop_index - p.start_index, 4000)
    np.testing.assert_array_equal(p.start_index, 4000 * np.arange(blocks))
