"""The ADIS16405 reference: the R-data reader, the long-tau fit recovering the terms of a
simulated record, and the session check seeing wander where there is some and none where
there is none."""

from pathlib import Path

import numpy as np
import pytest

from accelcal.errors import RecordingError
from accelcal.noise import simulate_noise
from accelcal_repro.discrepancy import adis as A
from accelcal_repro.discrepancy.benchmark import Session
from accelcal_repro.measured.smac import read_smac_imu, read_smac_rda

REPO = Path(__file__).resolve().parents[1]
RDA = REPO.parent / "shared" / "data" / "smac_adis16405" / "adis_16405_imu1.rda"
FS = 100.0


@pytest.mark.skipif(not RDA.is_file(), reason="shared/data not available")
def test_reads_the_adis_record():
    rec = read_smac_rda(RDA)
    assert rec.acc.shape == (1_000_000, 3) and rec.t[1] == pytest.approx(0.01)
    assert rec.acc[:, 2].mean() == pytest.approx(-1.016, abs=0.01)  # g, the sensor's z axis down
    steps = np.diff(np.unique(rec.acc[:, 0]))
    assert steps.min() == pytest.approx(0.00333, abs=1e-6)  # the ADIS16405's 3.33 mg output step
    imu = read_smac_imu(RDA)  # both sensors, SI units
    assert imu.gyro.shape == (1_000_000, 3) and imu.gyro_unit == "rad/s"
    assert np.abs(imu.gyro.mean(axis=0)).max() < np.deg2rad(1.0)  # at rest: bias only, well below 1 deg/s


def test_reader_errors_are_one_line(tmp_path):
    bad = tmp_path / "x.rda"
    bad.write_text("not R data\n")
    with pytest.raises(RecordingError, match="not a readable R data file") as e:
        read_smac_rda(bad)
    assert "\n" not in str(e.value)
    with pytest.raises(RecordingError, match="no such file"):
        read_smac_rda(tmp_path / "missing.rda")


def _record(terms, n=400_000, seed=0):
    rng = np.random.default_rng(seed)
    return np.column_stack([simulate_noise(rng, n, FS, terms) for _ in range(3)])


def test_long_tau_fit_recovers_the_terms_of_a_simulated_record():
    truth = {"white": 0.005, "bias_instability": 0.002, "random_walk": 3e-4}
    acc = _record(truth)
    av, _ = A.reference_allan(acc, FS)
    models, curves = A.fit_long_tau(av, FS, 1.0, 1400.0)
    chosen = models[models.chosen]
    assert len(chosen) == 3
    for r in chosen.itertuples():
        assert r.max_ratio < 1.5, r
        assert r.coef_white == pytest.approx(0.005, rel=0.1)
    # the wander the model predicts for a session's pose means is the one simulated (within 30 %)
    ref = A.chosen_models(models)
    win, _ = A.session_layout(Session())
    starts, durations = win[:, 0] / FS, (win[:, 1] - win[:, 0]) / FS
    want = A._predicted_scatter(truth, starts, durations)
    got = np.mean([A._predicted_scatter(m, starts, durations) for m in ref])
    assert got == pytest.approx(want, rel=0.3)
    assert set(curves.axis) == {"x", "y", "z"} and curves.fitted.any()


def test_session_check_sees_wander_only_where_there_is_some():
    session = Session()
    white = _record({"white": 0.005}, n=session.n_samples * 12, seed=1)
    chk = A.session_check_summary(A.session_check(white, FS, session, [{"white": 0.005}] * 3, n_layer=0, seed=0,
                                                  n_boot=19, n_resim=1, candidates=("bias_instability",)))
    a = chk[chk.axis == "all"].iloc[0]
    assert a.observed_ci_low <= a.se_var <= a.observed_ci_high  # nothing beyond the pose noise
    assert a.excess_observed == pytest.approx(1.0, abs=0.15)
    assert a.observed_ci_low <= a.reference_var <= a.observed_ci_high
    gm = {"white": 0.005, "gauss_markov": (0.003, 60.0)}
    wander = _record(gm, n=session.n_samples * 12, seed=2)
    chk = A.session_check_summary(A.session_check(wander, FS, session, [gm] * 3, n_layer=0, seed=0, n_boot=19,
                                                  n_resim=1, candidates=("bias_instability",)))
    a = chk[chk.axis == "all"].iloc[0]
    assert a.observed_ci_low > a.se_var and a.excess_observed > 1.2
    assert a.observed_ci_low <= a.reference_var <= a.observed_ci_high  # the true model predicts it
