"""The magnetometer's core: the ellipsoid estimators against the Cramér–Rao bound, the
alignment to the accelerometer, the registry's entries and the refusals of bad samples."""

import json

import numpy as np
import pytest

from accelcal.mag import calibrate_magnetometer
from accelcal.mag.align import align, dip_angles, heading_deg
from accelcal.mag.errors import MagDegenerateError, MagDisturbanceError, MagFitError, MagInputError
from accelcal.mag.fit import FieldSamples, crlb, fit_ellipsoid_ml, li_griffiths
from accelcal.mag.model import rotvec_to_matrix, vec_from_sym
from accelcal.mag.registry import MAG_ESTIMATORS
from accelcal.mag.result import MagCalibration
from accelcal.mag.trust import coverage, prepare

A_TRUE = np.linalg.inv(np.array([[0.35, 0.01, -0.005], [0.01, 0.33, 0.008], [-0.005, 0.008, 0.38]]))
A_TRUE = (A_TRUE + A_TRUE.T) / 2
B_TRUE = np.array([0.12, -0.25, 0.05])
SIGMA = np.array([0.002, 0.003, 0.0025])  # per axis: the weights must follow it


def _directions(rng, n, hemisphere=False):
    h = rng.normal(size=(n, 3))
    if hemisphere:
        h[:, 2] = np.abs(h[:, 2]) - 0.3
    return h / np.linalg.norm(h, axis=1)[:, None]


def _raw(h):
    return B_TRUE + h @ np.linalg.inv(A_TRUE).T


def test_closed_form_recovers_a_noise_free_ellipsoid():
    A, b = li_griffiths(_raw(_directions(np.random.default_rng(0), 200)))
    assert np.allclose(A, A_TRUE, atol=1e-9) and np.allclose(b, B_TRUE, atol=1e-9)


def test_ml_error_matches_the_cramer_rao_bound():
    """Monte Carlo of the ML fit on a partial sphere with per-axis noise: its mean squared
    error per parameter over the CRLB lies in [0.75, 1.35] (150 trials: the ratio's own
    scatter is ~0.12), and the reported s.e. equals the bound at the truth within 5 %."""
    rng = np.random.default_rng(7)
    m0 = _raw(_directions(rng, 600, hemisphere=True))
    cov = np.diag(SIGMA**2)
    bound = crlb(A_TRUE, B_TRUE, FieldSamples(m0, noise_cov=cov))
    truth = np.concatenate([B_TRUE, vec_from_sym(A_TRUE)])
    err, se = [], None
    for _ in range(150):
        f = fit_ellipsoid_ml(FieldSamples(m0 + rng.normal(size=m0.shape) * SIGMA, noise_cov=cov))
        err.append(f.theta - truth)
        se = f.se
    ratio = np.mean(np.square(err), axis=0) / np.diag(bound)
    assert np.all((ratio > 0.75) & (ratio < 1.35)), ratio
    assert np.allclose(se / np.sqrt(np.diag(bound)), 1, atol=0.05)


def test_alignment_recovers_rotation_and_dip_and_names_a_planar_set():
    rng = np.random.default_rng(3)
    dip = np.radians(55.0)
    field = np.array([0, np.cos(dip), -np.sin(dip)])
    R = rotvec_to_matrix([0.03, -0.05, 0.1])
    Q = [rotvec_to_matrix(rng.normal(size=3) * 2) for _ in range(12)]
    f = np.array([q @ [0, 0, 1.0] for q in Q])
    h = np.array([R.T @ q @ field for q in Q])
    a = align(f + rng.normal(size=f.shape) * 1e-4, h + rng.normal(size=h.shape) * 1e-4)
    assert abs(a.dip_deg - 55.0) < 0.05 and np.abs(a.R - R).max() < 1e-3 and not a.undetermined
    assert np.allclose(dip_angles(f, h @ a.R.T), 55.0, atol=0.1)
    Qz = [rotvec_to_matrix([0, 0, t]) for t in np.linspace(0, 6, 12)]
    flat = align(np.array([q @ [0, 0, 1.0] for q in Qz]), np.array([R.T @ q @ field for q in Qz]))
    assert any("about z" in u for u in flat.undetermined)
    assert heading_deg(np.array([[0, 0, 1.0]]), np.array([field]))[0] == pytest.approx(90.0)


@pytest.mark.parametrize("name", list(MAG_ESTIMATORS))
def test_every_registered_estimator_fits_field_samples(name):
    """Conformance: each entry, called the same way, recovers the hard iron within 4 s.e.
    (a sphere for the nested hard-iron model) and refuses a planar rotation in one line."""
    e = MAG_ESTIMATORS[name]
    rng = np.random.default_rng(11)
    A = A_TRUE if e.n_parameters == 9 else np.eye(3) * 3.0
    h = _directions(rng, 400)
    m = B_TRUE + h @ np.linalg.inv(A).T + rng.normal(size=(400, 3)) * 0.002
    fit = e.fit(FieldSamples(m, noise_cov=np.eye(3) * 0.002**2))
    assert np.all(np.abs(fit.b - B_TRUE) < 4 * fit.se[:3])
    th = np.linspace(0, 2 * np.pi, 300)
    circle = B_TRUE + np.column_stack([np.cos(th), np.sin(th), 0 * th]) @ np.linalg.inv(A).T
    with pytest.raises((MagDegenerateError, MagFitError)) as ei:
        calibrate_magnetometer(circle + rng.normal(size=circle.shape) * 1e-4, estimator=name)
    assert "\n" not in str(ei.value)


def test_bad_columns_are_refused_in_one_line():
    rng = np.random.default_rng(2)
    m = _raw(_directions(rng, 300)) + rng.normal(size=(300, 3)) * 0.002
    lead = np.vstack([np.zeros((1, 3)), m])
    p = prepare(lead)
    assert p.m.shape[0] == 300 and "first 1 row" in p.notes[0]
    const = m.copy()
    const[:, 1] = 0.3
    with pytest.raises(MagInputError, match="constant"):
        prepare(const)
    sat = m.copy()
    sat[:40, 0] = sat[:, 0].max() + 0.1
    with pytest.raises(MagInputError, match="saturated"):
        prepare(sat)


def _session(rng, disturb=False):
    """Ten rests of 100 samples in random orientations, rotations between them; an accelerometer
    that is exact (identity calibration)."""
    dip = np.radians(60)
    field = np.array([0, np.cos(dip), -np.sin(dip)])
    R = rotvec_to_matrix([0.02, 0.04, -0.03])
    mags, accs, intervals, n = [], [], [], 0
    for k in range(12):
        Q = rotvec_to_matrix(rng.normal(size=3) * 2)
        Q2 = rotvec_to_matrix(rng.normal(size=3) * 2)
        for j in range(100):  # a rest, then a turn
            mags.append(R.T @ Q @ field)
            accs.append(Q @ [0, 0, 9.81])
        intervals.append((n, n + 100))
        n += 100
        for s in np.linspace(0, 1, 60):
            q = rotvec_to_matrix(s * rng.normal(size=3) * 3) @ Q2
            mags.append(R.T @ q @ field)
            accs.append(q @ [0, 0, 9.81])
            n += 1
    h = np.array(mags)
    m = _raw(h) + rng.normal(size=h.shape) * 0.002
    if disturb:
        for a, b in intervals:
            m[a + 50:b] += 0.05
    return m, np.array(accs), intervals, R


class _Identity:
    @staticmethod
    def apply(x):
        return np.asarray(x, float)


class _Poses:
    def __init__(self, acc, intervals):
        self.intervals = np.array(intervals)
        self.means = np.array([acc[a:b].mean(axis=0) for a, b in intervals])


def test_session_aligns_and_refuses_a_disturbed_field():
    rng = np.random.default_rng(5)
    m, acc, iv, R = _session(rng)
    mc = calibrate_magnetometer(m, acc_cal=_Identity(), poses=_Poses(acc, iv), raw_unit="gauss")
    assert abs(mc.alignment.dip_deg - 60) < 4 * mc.alignment.se_dip_deg + 0.05
    assert mc.trust["dip_spread_deg"] < 0.1 and 0.5 < mc.trust["chi2_dof"] < 1.5
    back = MagCalibration.from_dict(json.loads(json.dumps(mc.to_dict())))
    assert np.allclose(back.apply(m[:5]), mc.apply(m[:5]))
    m2, acc2, iv2, _ = _session(rng, disturb=True)
    with pytest.raises(MagDisturbanceError, match="changes while the device rests"):
        calibrate_magnetometer(m2, acc_cal=_Identity(), poses=_Poses(acc2, iv2))


def test_coverage_counts_sections_of_the_sphere():
    rng = np.random.default_rng(0)
    assert coverage(_directions(rng, 5000)) == 1.0
    assert coverage(_directions(rng, 5000)[:, [0, 1, 2]] * [1, 1, 0] + [0, 0, 1e-9]) < 0.3


def test_nested_soft_iron_test_names_a_sphere_and_an_ellipsoid():
    """A sphere with noise: p not small; the SNU-like ellipsoid: p tiny (false positive and power)."""
    rng = np.random.default_rng(9)
    h = _directions(rng, 800)
    cov = np.eye(3) * 0.002**2
    sphere = B_TRUE + h * 0.35 + rng.normal(size=h.shape) * 0.002
    ellipsoid = _raw(h) + rng.normal(size=h.shape) * 0.002
    p_sph = calibrate_magnetometer(sphere).trust["soft_iron_p"]
    p_ell = calibrate_magnetometer(ellipsoid).trust["soft_iron_p"]
    assert p_sph > 0.01 and p_ell < 1e-6
    del cov
