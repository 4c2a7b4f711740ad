"""The gyro calibration's one trust verdict (GyroQuality.verdict): computed in the library from
the evidence the warnings name (degrees of freedom, excess, rotation per axis, saturation),
carried in the calibration file and the summary."""

import numpy as np

from accelcal.gyro.calibrate import calibrate_gyro
from accelcal.gyro.result import RULES, GyroCalibration, GyroQuality
from accelcal.gyro.simulate import random_gyro_matrix, simulate_recording
from accelcal.static import detect_static


class _Identity:
    """An accelerometer that needs no calibration (the simulation's is exact)."""

    @staticmethod
    def apply(z):
        return np.asarray(z, float)


def _gyro(n_motions: int, seed: int):
    rng = np.random.default_rng(seed)
    r = simulate_recording(rng, n_motions=n_motions, C=random_gyro_matrix(rng), gyro_bias=[0.01, -0.02, 0.005])
    return calibrate_gyro(r["t"], r["gyro"], detect_static(r["t"], r["acc"]), _Identity(), acc=r["acc"])


def test_a_well_determined_session_is_trusted_and_a_short_one_poorly_determined():
    good, poor = _gyro(24, seed=21), _gyro(7, seed=22)
    assert good.quality.verdict == "trusted" and good.quality.reasons == () and not good.quality.warnings
    assert "trust: trusted" in good.summary()
    q = poor.quality
    assert q.dof == 2 * 7 - 9 < RULES["min_dof"]
    assert q.verdict == "poorly_determined" and "few_dof" in q.flags
    assert q.reasons[0] == f"{q.dof} dof"
    assert any("degrees of freedom" in w for w in q.warnings)  # the CLI's warning says the same
    assert "trust: poorly determined (5 dof" in poor.summary()
    back = GyroCalibration.from_dict(poor.to_dict())  # carried in the calibration file
    assert back.quality.verdict == "poorly_determined" and back.quality.reasons == q.reasons
    assert poor.to_dict()["quality"]["verdict"] == "poorly_determined"


def _quality(**kw):
    base = dict(n_motions=30, n_parameters=9, dof=51, chi2=50.0, p_value=0.5, excess=1.0, residual_rms_deg=0.1,
                predicted_rms_deg=0.1, axis_turn_deg=(900.0, 900.0, 900.0), warnings=(), flags=(),
                scale_rel_se=(0.001, 0.001, 0.001))
    return GyroQuality(**{**base, **kw})


def test_the_verdict_follows_the_flags_determination_first():
    assert _quality().verdict == "trusted"
    misfit = _quality(excess=8.0, warnings=("residuals",), flags=("excess",))
    assert misfit.verdict == "caution" and misfit.reasons == ("excess 8",)
    weak = _quality(excess=9.16, dof=3, warnings=("a", "b", "c"), flags=("excess", "few_dof", "few_axes", "saturated"),
                    scale_rel_se=(0.13, 0.041, 0.085))
    assert weak.verdict == "poorly_determined"
    assert weak.reasons == ("3 dof", "scale x/y/z ± 13/4.1/8.5 %", "excess 9.16", "saturated")
    exact = _quality(dof=0, warnings=("exact",), flags=("exactly_determined",))
    assert exact.verdict == "poorly_determined" and exact.reasons == ("0 dof (exactly determined)",)
    old_file = {k: v for k, v in _quality(dof=4).to_dict().items() if k not in ("scale_rel_se", "verdict")}
    assert GyroQuality.from_dict(old_file).verdict == "poorly_determined"  # a file written before the verdict
