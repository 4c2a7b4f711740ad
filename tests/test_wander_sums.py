"""The wander family ``sum`` (issue 34 item 1): a short Gauss–Markov part pinned by the rests.

Each test can fail: the rests' fit against the component that made the samples (and
against inventing one in white noise), the whitened problem against the covariance it
must whiten, and the family against ``flicker`` where the rests show nothing short.
"""

import numpy as np

from accelcal.discrepancy.fit import fit
from accelcal.discrepancy.wander import sums
from accelcal.discrepancy.wander_model import linearise, linearise_noise
from tests.wander_sessions import FS, rest_session


def test_rests_pin_the_short_component_and_invent_none_in_white_noise():
    rng = np.random.default_rng(21)
    data, _, _ = rest_session(rng, {"white": 0.33, "gauss_markov": (2.0, 0.5)})
    sp = sums.fit_short(data.rests.full)
    assert sp is not None and 0.2 <= sp.tau <= 1.25 and 4.0 / 3 <= sp.q_abs <= 4.0 * 3, sp
    assert data.rests.full.taus[0] == 1.0 / FS and data.rests.full.taus.size > data.rests.taus.size
    white, _, _ = rest_session(rng, {"white": 0.33})
    assert sums.fit_short(white.rests.full) is None
    assert sums.fit_short(None) is None


def test_pinned_problem_whitens_the_short_part_and_keeps_its_columns():
    rng = np.random.default_rng(22)
    data, _, _ = rest_session(rng, {"white": 0.33, "gauss_markov": (2.0, 0.5)})
    f = fit(data)
    prob = linearise(data, f, common=None)
    sp = sums.ShortPart(tau=0.5, q_abs=4.0, gain=100.0)
    pp = sums.pinned(prob, sp)
    # in the new contrasts the white part plus the short part is the identity
    P = sums.pose_covariance(sp, prob.starts, prob.durations, prob.grad) / np.outer(prob.sigma, prob.sigma)
    B = pp.L.T @ (np.eye(len(data)) + P) @ pp.L
    assert np.allclose(B, np.eye(pp.m), atol=1e-8)
    J = f.J * f.sigma[:, None]
    assert np.allclose(pp.columns(J[:, 3:]), pp.X0) and np.allclose(pp.L.T @ (f.residuals / prob.sigma), pp.y)
    assert "sum of processes" in pp.notes[-1]
    # in the contrasts it is the exact covariance of the interval means between the poses, with
    # each pose's own variance left to its standard error (the diagonal zeroed)
    a, T, tau = prob.starts, prob.durations, sp.tau
    E = -np.expm1(-T / tau) / T
    first_end = np.where(a[:, None] <= a[None, :], (a + T)[:, None], (a + T)[None, :])
    gap = np.maximum(np.maximum(a[:, None], a[None, :]) - first_end, 0.0)
    cov = sp.q_abs * tau**2 * np.outer(E, E) * np.exp(-gap / tau) * (prob.grad @ prob.grad.T)
    np.fill_diagonal(cov, 0.0)
    Lw = prob.L / prob.sigma[:, None]
    got = Lw.T @ sums.pose_covariance(sp, prob.starts, prob.durations, prob.grad) @ Lw
    assert np.allclose(got, Lw.T @ cov @ Lw, atol=1e-9 * np.abs(got).max())


def test_sum_family_is_flicker_without_a_short_part_and_pins_one_when_present():
    rng = np.random.default_rng(23)
    white, _, _ = rest_session(rng, {"white": 0.33})
    f = fit(white)
    a, b = linearise_noise(white, f, "sum")[2], linearise_noise(white, f, "flicker")[2]
    assert (a.t, a.q_rel, a.common) == (b.t, b.q_rel, b.common)
    short, _, _ = rest_session(rng, {"white": 0.33, "gauss_markov": (2.0, 0.5)})
    prob, _, w = linearise_noise(short, fit(short), "sum")
    assert any("sum of processes" in n for n in prob.notes) and np.isfinite(w.reml)
