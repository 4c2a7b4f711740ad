"""The deterministic layer of the discrepancy workflow: model, fits, identifiability, the loop
(on the reproductions' simulated sessions: tests/test_repro_discrepancy_loop.py)."""

import numpy as np
import pytest
from scipy import stats

from accelcal.discrepancy.detect import discrepancy
from accelcal.effects import EFFECT_IDS, EFFECTS
from accelcal.effects import ADDITIVE, TEMPERATURE, TIME
from accelcal.discrepancy.fit import evaluate, fit, fit_at, forward, lopo, pose_data
from accelcal.discrepancy.identifiability import identifiability
from accelcal.discrepancy.rules import Rules
from accelcal.discrepancy.statistics import critical_noncentrality, holm
from accelcal.evaluation import residual_sigma
from accelcal.model import m_from_params
from accelcal.simulation import classic_directions, random_directions

G = 9.80665
RULES = Rules()


def _design(rng, u, noise=0.14, temp=True, counts=True):
    """Pose-level design like the benchmark's: counts, 8 s per pose, a cycling temperature."""
    n = len(u)
    s = (415.0 - 1) * np.ones(3) if counts else np.zeros(3)
    th = np.deg2rad([0.5, -0.7, 1.0])
    M = m_from_params(s, th)
    b = np.array([32768.0, 32900.0, 32500.0]) if counts else np.array([0.05, -0.02, 0.03])
    t = 20 + 8.0 * np.arange(n)
    T = 25 + 5 * np.sin(4 * np.pi * t / (t[-1] + 4) + 0.3) if temp else None
    return M, b, np.concatenate([b, s, th]), t, T, np.full((n, 3), noise)


# --------------------------------------------------------------------------- model and fits


@pytest.mark.parametrize("effects", [(), ("quadratic",), ("cubic",), ("bias_drift",), ("temperature",),
                                     ("temperature_scale",), ("quadratic", "temperature", "cubic")])
def test_jacobian_matches_finite_differences(effects):
    rng = np.random.default_rng(1)
    u = random_directions(rng, 20)
    M, b, p0, t, T, ms = _design(rng, u)
    d = pose_data(forward(G * u, M, b, {}), G, ms, t, T)
    p = np.concatenate([p0, rng.normal(0, 1, 3 * len(effects))])
    scale = {"quadratic": 1e-4, "cubic": 1e-5, "bias_drift": 1e-2, "temperature": 0.5, "temperature_scale": 1e-4}
    for i, e in enumerate(effects):
        p[9 + 3 * i: 12 + 3 * i] *= scale[e]
    r, J, _ = evaluate(p, d, effects)
    for k in range(len(p)):
        h = 1e-5 / np.abs(J[:, k]).max()  # moves the residuals by ~1e-5 (round-off ~1e-15)
        dp = np.zeros_like(p)
        dp[k] = h
        num = (evaluate(p + dp, d, effects, jacobian=False)[0] - evaluate(p - dp, d, effects, jacobian=False)[0]) / (2 * h)
        np.testing.assert_allclose(J[:, k], num, rtol=1e-6, atol=1e-7 * np.abs(J[:, k]).max())


@pytest.mark.parametrize("eid", EFFECT_IDS)
def test_fit_recovers_injected_effect_without_noise(eid):
    """Noise-free poses from the forward model: the extended fit returns the truth, χ² ≈ 0."""
    rng = np.random.default_rng(2)
    u = random_directions(rng, 24)
    M, b, p_true, t, T, ms = _design(rng, u)
    dt, dT = t - t.mean(), T - T.mean()
    # sized from the entry: the term moves a pose mean by up to 60 noise units (8.4 counts)
    e = EFFECTS[eid]
    c = {None: 1.0, TIME: np.abs(dt).max(), TEMPERATURE: np.abs(dT).max()}[e.covariate]
    gain = 1.0 if e.kind == ADDITIVE else np.linalg.norm(M, axis=1).mean() * G ** e.power
    phi = 60 * ms[0, 0] / (gain * c) * np.resize([1.0, -0.6, 0.3, -0.8, 0.5], e.size)
    z = forward(G * u, M, b, {eid: phi}, dt=dt, dtemp=dT)
    d = pose_data(z, G, ms, t, T)
    f = fit(d, (eid,))
    assert f.chi2 < 1e-12
    np.testing.assert_allclose(f.block(eid), phi, rtol=1e-6)
    np.testing.assert_allclose(f.bias, b, atol=1e-6)
    # the base model cannot: its residuals exceed the pose noise beyond doubt
    assert stats.chi2.sf(fit(d).chi2, len(u) - 9) < 1e-9


def test_lopo_batched_equals_independent_refits():
    rng = np.random.default_rng(3)
    u = random_directions(rng, 18)
    M, b, _, t, T, ms = _design(rng, u)
    z = forward(G * u, M, b, {"quadratic": [3e-4, 0, -2e-4]}) + 0.14 * rng.standard_normal((18, 3))
    d = pose_data(z, G, ms, t, T)
    for effects in ((), ("quadratic",), ("quadratic", "bias_drift")):
        f = fit(d, effects)
        got = lopo(f, d)
        ref = []
        for i in range(len(d)):
            keep = np.arange(len(d)) != i
            fi = fit(d.subset(keep), effects, max_iter=500)  # from the LLS start, not warm
            ref.append(evaluate(fi.p, d.subset(np.array([i])), effects, jacobian=False)[0][0] / d.sigma[i])
        np.testing.assert_allclose(got, ref, rtol=1e-4, atol=1e-5)


def test_holm_adjusted_p_values():
    np.testing.assert_allclose(holm([0.01, 0.04, 0.03, np.nan]), [0.03, 0.06, 0.06, np.nan])
    np.testing.assert_allclose(holm([0.01, 0.04, 0.03], "bonferroni"), [0.03, 0.12, 0.09])
    np.testing.assert_allclose(holm([0.01, 0.04], "none"), [0.01, 0.04])


def test_critical_noncentrality_gives_the_power():
    for k, dof, level, power in ((3, 12, 0.01, 0.8), (3, 30, 0.05 / 5, 0.5), (1, 5, 0.05, 0.95)):
        lam = critical_noncentrality(k, dof, level, power)
        assert stats.ncf.sf(stats.f.isf(level, k, dof), k, dof, lam) == pytest.approx(power, abs=1e-8)
    assert critical_noncentrality(3, 0, 0.05, 0.8) == np.inf


# --------------------------------------------------------------------------- identifiability


def _ident_on(u, eid, temp=True, const_temp=False):
    rng = np.random.default_rng(4)
    M, b, p, t, T, ms = _design(rng, u, temp=temp)
    if const_temp:
        T = np.full_like(t, 27.3)
    z = forward(G * u, M, b, {})
    d = pose_data(z, G, ms, t, T, sigma=residual_sigma(z, ms, M, b))
    return identifiability(d, fit_at(d, (), p), eid, RULES, 5)


def test_quadratic_not_identifiable_on_the_six_faces_but_on_the_24_pose_design():
    """On u = ±e_j the quadratic term's residual signature -g²u_j³ equals the bias's -u_j."""
    faces = np.tile(classic_directions(6), (3, 1))  # 18 poses: enough degrees of freedom
    q6 = _ident_on(faces, "quadratic")
    assert not q6.identifiable and q6.absorbed > 1 - 1e-9
    assert any("absorbs" in r or "rank" in r for r in q6.reasons)
    c6 = _ident_on(faces, "cubic")  # -g³u_j⁴ equals the scale factor's -g u_j² there
    assert not c6.identifiable
    q24 = _ident_on(classic_directions(24), "quadratic")
    assert q24.identifiable and q24.absorbed < 0.99 and np.all(np.isfinite(q24.mde))
    # drift does not care about the orientations
    assert _ident_on(faces, "bias_drift").identifiable


def test_constant_temperature_is_not_identifiable():
    u = random_directions(np.random.default_rng(5), 24)
    for eid in ("temperature", "temperature_scale"):
        r = _ident_on(u, eid, const_temp=True)
        assert not r.identifiable
        assert any("temperature varies by 0" in x for x in r.reasons)
        assert _ident_on(u, eid).identifiable


def test_too_few_poses_leave_nothing_identifiable():
    u = random_directions(np.random.default_rng(6), 11)
    r = _ident_on(u, "bias_drift")
    assert not r.identifiable and any("degrees of freedom" in x for x in r.reasons)


def test_mde_scales_with_the_noise():
    u = classic_directions(24)
    rng = np.random.default_rng(7)
    M, b, p, t, T, _ = _design(rng, u)
    z = forward(G * u, M, b, {})
    out = []
    for noise in (0.1, 0.4):
        ms = np.full((24, 3), noise)
        d = pose_data(z, G, ms, t, T, sigma=residual_sigma(z, ms, M, b))
        out.append(identifiability(d, fit_at(d, (), p), "bias_drift", RULES, 5).mde_data)
    np.testing.assert_allclose(out[1] / out[0], 4.0, rtol=1e-9)


# --------------------------------------------------------------------------- the loop on raw recordings


NULL_RULES = {"wander": RULES, "white": Rules(null="white")}


@pytest.mark.parametrize("null", sorted(NULL_RULES))
def test_refit_rounds_name_two_effects(null):
    """Two hidden effects: the loop names both, one per round, and stops.  The quadratic is
    0.45 % of g (50 noise units): at 1.5 % its second-order residual (the tangential shift's
    |δ|²/2g, about 1e-3 m/s²) is four times the pose noise, beyond the first-order
    linearisation the round's tests stand on, and second_order and cubic then share it."""
    rng = np.random.default_rng(8)
    u = random_directions(rng, 40)
    M, b, _, t, T, ms = _design(rng, u, noise=0.1)
    dt, dT = t - t.mean(), T - T.mean()
    z = forward(G * u, M, b, {"bias_drift": [0.004, -0.003, 0.002], "quadratic": [4.5e-4, -3e-4, 3e-4]},
                dt=dt, dtemp=dT) + 0.1 * rng.standard_normal((40, 3))
    res = discrepancy(pose_data(z, G, ms, t, T), NULL_RULES[null])
    assert set(res.effects) == {"bias_drift", "quadratic"}
    assert max(c.round for c in res.candidates) == 3  # round 3 tested the rest and named nothing
    assert not any(c.named for c in res.candidates if c.round == 3)


@pytest.mark.parametrize("eid", ["quadratic", "temperature"])
def test_mde_is_detected_with_the_design_power(eid):
    """Pose-level data with the effect at exactly its MDE along a direction: the nested
    F-test at level α/m rejects in about `power` of the trials (exact binomial 99.9 % band),
    and at level α/m in about α/m of the trials without the effect."""
    rng = np.random.default_rng(9)
    u = random_directions(rng, 30)
    M, b, p_true, t, T, ms = _design(rng, u)
    z0 = forward(G * u, M, b, {})
    d0 = pose_data(z0, G, ms, t, T, sigma=residual_sigma(z0, ms, M, b))
    ident = identifiability(d0, fit_at(d0, (), p_true), eid, RULES, 5)
    direction = np.array([1.0, -0.5, 0.3])
    phi = ident.mde_along(direction) * direction / np.linalg.norm(direction)
    z1 = forward(G * u, M, b, {eid: phi}, dt=t - t.mean(), dtemp=T - T.mean())
    level = RULES.alpha / 5
    trials = 300
    hits = {0: 0, 1: 0}
    for k in range(trials):
        e = ms * rng.standard_normal(z0.shape)
        for which, z in ((0, z0), (1, z1)):
            d = pose_data(z + e, G, ms, t, T, sigma=d0.sigma)
            f0, f1 = fit(d), fit(d, (eid,))
            F = ((f0.chi2 - f1.chi2) / 3) / (f1.chi2 / f1.dof)
            hits[which] += stats.f.sf(F, 3, f1.dof) <= level
    for which, p in ((1, RULES.power), (0, level)):
        lo, hi = stats.binom.ppf([0.0005, 0.9995], trials, p)
        assert lo <= hits[which] <= hi, (which, hits[which], lo, hi)
