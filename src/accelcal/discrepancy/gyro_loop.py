"""The gyroscope's discrepancy loop: which effect beyond ``ω = C (y - b - G f)`` do the motions ask for?

The gyro is fitted to the motions between rests (:mod:`accelcal.gyro.fit`): per motion, the
gravity direction of the rest before, carried over by the integrated gyro, must meet the
direction of the rest after; two residuals per motion, weighted by the covariance the
rests' noise predicts (the fit's own weights, used as they are).  Each candidate is a
nested extension of that model, a perturbation of the bias-free gyro samples
``y → y + Σ_j β_j d_j(y)`` (:data:`CANDIDATES`):

==================  ==  ==========================================================
``g_sensitivity``    9  ``- G f``: a bias proportional to the specific force
``scale_asymmetry``  3  ``a_k y_k [y_k < 0]``: another scale for negative rates
``rate_nonlinearity`` 3 ``q_k y_k |y_k| / s``: a scale that grows with the rate
``time_offset``      1  ``δ ẏ``: the gyro's clock ``δ`` seconds off the accelerometer's
``motion_bias``      3  ``- Δb``: a bias that shifts while the sensor moves
==================  ==  ==========================================================

Linearised at the fit: the residuals' Jacobian in ``β`` is a central difference of the
integrated residuals (each column one re-integration).  With ``L`` the Cholesky factor of
the residual covariance, ``J`` the Jacobian in ``vec(C)`` and ``X`` in ``β``, a candidate is
tested by ``F = (Δχ²/k) / (χ²₁/(n - 9 - k))``; the common scale of the noise (the motion
residuals exceed the rest noise 1.7-53× on real sessions: what wanders between rests) is
estimated, not assumed, and the p-value comes from a parametric bootstrap of ``F`` under
``N(0, s² Σ)`` (``n_boot`` draws; ``s`` cancels in ``F``, so the bootstrap is exact for the
linearised model), Holm-adjusted over the identifiable candidates of a round.  The most
significant one is named, refitted (one Gauss-Newton step in ``(vec C, β)``) and the next
round tests the others on top of it.

Identifiability: the share of ``L⁻¹X`` that ``L⁻¹J`` absorbs; a candidate whose columns are
absorbed (> :data:`MAX_ABSORBED`) or whose motions lack what it needs (``needs``: both
senses of rotation per axis, several rates, ...) is ``not_identifiable``, with the motions
it would need.  The minimum detectable effect of each parameter is the size that alone gives
the F test power 0.8 at α over the number of candidates (Holm's first step), in the
parameter's own unit.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from ..gyro.calibrate import _motions, accel_directions
from ..gyro.fit import MotionSet, _residuals, evaluate
from ..gyro.rests import (RestStatistics, bias_series, fit_bias, motion_bias_variance, rest_noise, rest_statistics,
                          sample_interval, saturated_samples)
from .statistics import critical_noncentrality, holm

#: A candidate whose whitened columns the base model absorbs beyond this share is not identifiable.
MAX_ABSORBED = 0.99
#: Fewest degrees of freedom left after a candidate (2 per motion, 9 for C).
MIN_DOF = 4


@dataclass(frozen=True)
class GyroCandidate:
    """One nested extension of the gyro model (module docstring's table)."""

    name: str
    params: tuple[str, ...]
    unit: str
    needs: str  #: the motions it needs to be identifiable, in words


CANDIDATES = (
    GyroCandidate("g_sensitivity", tuple(f"G_{a}{b}" for a in "xyz" for b in "xyz"), "raw/(m/s^2)",
                  "motions in which gravity points along each axis in turn (rests in at least 4 orientations, "
                  "turns about all three axes)"),
    GyroCandidate("scale_asymmetry", ("a_x", "a_y", "a_z"), "relative",
                  "motions that turn each axis both ways (positive and negative rates of 30 deg or more)"),
    GyroCandidate("rate_nonlinearity", ("q_x", "q_y", "q_z"), "relative per rad/s",
                  "motions at different peak rates about each axis (slow and fast turns)"),
    GyroCandidate("time_offset", ("delta_t",), "s",
                  "rates that do not vanish where the rests begin and end (a rest-to-rest rotation is the same for "
                  "any shift of its samples): a continuous rotation against a reference, e.g. a turntable"),
    GyroCandidate("motion_bias", ("db_x", "db_y", "db_z"), "raw",
                  "long motions about each axis at differing orientations (the bias change integrates over the "
                  "motion's duration)"),
)
CANDIDATE_NAMES = tuple(c.name for c in CANDIDATES)


@dataclass(frozen=True)
class GyroMotions:
    """The gyro fit's data (its motions, weights and ``C``) and what the candidates perturb."""

    ms: MotionSet
    C: np.ndarray
    integrator: str
    f: np.ndarray | None  #: (n, 3) calibrated specific force [m/s²] per sample, or None
    nominal: float  #: rad/s per raw unit
    g_sensitivity_in_base: bool
    t: np.ndarray | None = None  #: sample times [s] (for the bias the rests take from a perturbation)
    rests: RestStatistics | None = None  #: the gyro's rests (their weights for that bias)
    bias_mode: str = "interpolated"


def gyro_motions(rec, acc_cal, poses, gcal) -> GyroMotions:
    """Rebuild the motion set :func:`accelcal.gyro.calibrate.calibrate_gyro` fitted ``gcal`` to.

    Same rests, bias mode, g-sensitivity, time base and used motions (its table), so that
    the loop tests the calibration the user gets, with its weights.
    """
    s = gcal.settings
    t, gyro = rec.t, np.asarray(rec.gyro, float)
    tb = sample_interval(t)
    rs = rest_statistics(t, gyro, poses.intervals)
    u, u_cov, f_rest = accel_directions(acc_cal, poses.means, poses.mean_std)
    gs = bool(s.get("g_sensitivity"))
    best = fit_bias(rs, s.get("bias_mode", "interpolated"), f_rest if gs else None)
    f = np.asarray(acc_cal.apply(np.asarray(rec.acc, float)), float)
    y = gyro - bias_series(best, rs, t)
    if gs:
        y = y - f @ best.g_sensitivity.T
    starts, stops, before, after, _ = _motions(poses.intervals, tb.gaps, saturated_samples(gyro, None))
    h = tb.h if s.get("time_base", {}).get("used", "index") == "index" else t
    ms = MotionSet(y, h, starts, stops, before, after, u, u_cov, rest_noise(rs),
                   motion_bias_variance(best, rs, before, after))
    used = np.asarray(gcal.motions.get("used", [True] * ms.n_motions), bool)
    return GyroMotions(ms.subset(used), np.asarray(gcal.model.C, float), s.get("integrator", "magnus4"), f,
                       float(s.get("nominal", 1.0)), gs, np.asarray(t, float), rs, s.get("bias_mode", "interpolated"))


def _moving(gm: GyroMotions, k: float = 5.0) -> np.ndarray:
    """1 where the sensor turns (rate above ``k`` times the rest noise on some axis, inside a
    motion), else 0: the samples a bias change "while moving" acts on (a motion's interval
    also holds the still ends its rests' trim left out)."""
    y = gm.ms.y
    inside = np.zeros(len(y), bool)
    for a, b in zip(gm.ms.starts, gm.ms.stops):
        inside[a:b + 1] = True
    noise = np.sqrt(np.asarray(gm.ms.y_var, float))
    return (inside & np.any(np.abs(y) > k * noise, axis=1)).astype(float)


def _through_bias(gm: GyroMotions, d: np.ndarray) -> np.ndarray:
    """A perturbation as the motions see it: what the rests see of it is taken out with the bias.

    The bias comes from the rests (interpolated between them by default), so an effect
    present at rest (a g-sensitivity) moves the bias too, and only its change between
    the rests reaches the motions.  Linear in ``d``: the rests' means of ``d``, weighted
    as the gyro's own rests are."""
    if gm.rests is None:
        return d
    iv = gm.rests.intervals
    c = np.concatenate([np.zeros((1, 3)), np.cumsum(d, axis=0)])
    means = (c[iv[:, 1]] - c[iv[:, 0]]) / (iv[:, 1] - iv[:, 0])[:, None]
    if not np.any(means):
        return d
    rs = replace(gm.rests, means=means)
    return d - bias_series(fit_bias(rs, gm.bias_mode), rs, gm.t)


def _directions(name: str, gm: GyroMotions) -> list[np.ndarray] | None:
    """The perturbations ``d_j(y)`` (n, 3) of a candidate, or None when it cannot be formed."""
    y, e = gm.ms.y, np.eye(3)
    if name == "g_sensitivity":
        if gm.f is None or gm.g_sensitivity_in_base:
            return None
        return [-np.outer(gm.f[:, b], e[a]) for a in range(3) for b in range(3)]
    if name == "scale_asymmetry":
        return [np.outer(np.where(y[:, k] < 0, y[:, k], 0.0), e[k]) for k in range(3)]
    if name == "rate_nonlinearity":
        return [np.outer(y[:, k] * np.abs(y[:, k]) * abs(gm.nominal), e[k]) for k in range(3)]
    if name == "time_offset":
        h = gm.ms.h if np.ndim(gm.ms.h) == 0 else np.gradient(gm.ms.h)[:, None]
        return [np.gradient(y, axis=0) / h]
    if name == "motion_bias":
        return [-np.outer(_moving(gm), e[k]) for k in range(3)]
    raise KeyError(name)


def candidate_jacobian(name: str, gm: GyroMotions) -> np.ndarray | None:
    """∂r/∂β (2m, k) of a candidate at the fit: central differences of the integrated residuals."""
    dirs = _directions(name, gm)
    if dirs is None:
        return None
    cols = []
    for d in dirs:
        d = _through_bias(gm, d)
        scale = np.max(np.abs(d))
        if not scale > 0:
            cols.append(np.zeros(2 * gm.ms.n_motions))
            continue
        eps = 1e-4 * np.max(np.abs(gm.ms.y)) / scale
        rp = _residuals(_with_y(gm.ms, gm.ms.y + eps * d), gm.C, gm.integrator)
        rm = _residuals(_with_y(gm.ms, gm.ms.y - eps * d), gm.C, gm.integrator)
        cols.append((rp - rm) / (2 * eps))
    return np.column_stack(cols)


def _with_y(ms: MotionSet, y) -> MotionSet:
    return MotionSet(y, ms.h, ms.starts, ms.stops, ms.rest_before, ms.rest_after, ms.u, ms.u_cov, ms.y_var,
                     ms.bias_var)


def _orth(A: np.ndarray) -> np.ndarray:
    """Orthonormal basis of the columns of ``A`` (rank-revealing SVD)."""
    if A.shape[1] == 0:
        return A
    U, s, _ = np.linalg.svd(A, full_matrices=False)
    return U[:, s > s[0] * 1e-10] if s.size and s[0] > 0 else U[:, :0]


def _resid(Q: np.ndarray, A: np.ndarray) -> np.ndarray:
    return A - Q @ (Q.T @ A)


@dataclass(frozen=True)
class GyroLoopResult:
    """The gyro loop's decisions: per round and candidate, the test; named effects; gaps."""

    named: tuple[str, ...]
    rounds: list  #: per round: {candidate: row dict}
    excess_before: float
    excess_after: float
    estimates: dict  #: named candidate -> {param: (value, se)}
    n_motions: int
    alpha: float
    n_boot: int
    notes: tuple[str, ...] = field(default_factory=tuple)

    @property
    def outcome(self) -> str:
        if self.named:
            return "effect"
        rows = self.rounds[0].values() if self.rounds else []
        return "not_identifiable" if any(r["status"] == "not_identifiable" for r in rows) else "none"

    def to_dict(self) -> dict:
        return {"named": list(self.named) or ["none"], "outcome": self.outcome, "candidates": self.rounds,
                "excess_before": self.excess_before, "excess_after": self.excess_after,
                "estimates": {k: {p: {"value": v, "se": s} for p, (v, s) in e.items()}
                              for k, e in self.estimates.items()},
                "n_motions": self.n_motions, "alpha": self.alpha, "n_boot": self.n_boot,
                "noise_model": "the gyro fit's weights (rest noise integrated over each motion, the bias error, the "
                               "gravity directions' noise) times one common scale estimated from the residuals "
                               "(what wanders between rests)",
                "notes": list(self.notes)}

    def summary(self) -> str:
        named = ", ".join(self.named) or "none"
        return (f"gyroscope: {self.n_motions} motions; effect named: {named}; excess {self.excess_before:.3g} -> "
                f"{self.excess_after:.3g}")


def _sign_coverage(gm: GyroMotions, min_deg: float = 30.0) -> list[str]:
    """Axes whose motions do not turn both ways by ``min_deg`` (the scale asymmetry's need)."""
    y = gm.ms.y @ gm.C.T
    h = gm.ms.h if np.ndim(gm.ms.h) == 0 else np.gradient(gm.ms.h)[:, None]
    moving = np.zeros(len(y), bool)
    for a, b in zip(gm.ms.starts, gm.ms.stops):
        moving[a:b + 1] = True
    ang = np.rad2deg(y * h)[moving]
    return ["xyz"[k] for k in range(3) if min(ang[ang[:, k] > 0, k].sum(), -ang[ang[:, k] < 0, k].sum()) < min_deg]


def _test(base_w: np.ndarray, Xw: np.ndarray, rw: np.ndarray, E: np.ndarray, alpha: float) -> dict:
    """F test of the whitened columns ``Xw`` on top of ``base_w``, bootstrap p-value (null draws ``E``).

    ``alpha``: the level the MDE is computed at (the caller passes α over the number of
    candidates, the Bonferroni level Holm's first rejection needs)."""
    n = len(rw)
    Qb = _orth(base_w)
    Xp = _resid(Qb, Xw)
    absorbed = 1.0 - np.sum(Xp ** 2, axis=0) / np.maximum(np.sum(Xw ** 2, axis=0), 1e-300)
    Z = _orth(Xp)
    k, dof = Z.shape[1], n - Qb.shape[1] - Z.shape[1]
    row = {"absorbed": absorbed.tolist(), "k": int(Xw.shape[1]), "dof": int(dof)}
    if k < Xw.shape[1] or np.any(absorbed > MAX_ABSORBED) or dof < MIN_DOF:
        return {**row, "status": "not_identifiable"}
    r0 = _resid(Qb, rw)
    num = float(np.sum((Z.T @ r0) ** 2))
    den = float(r0 @ r0) - num
    F = (num / k) / (den / dof)
    E0 = _resid(Qb, E)
    nb = np.sum((Z.T @ E0) ** 2, axis=0)
    Fb = (nb / k) / ((np.sum(E0 ** 2, axis=0) - nb) / dof)
    p = (1.0 + np.sum(Fb >= F)) / (1.0 + E.shape[1])
    s = np.sqrt(den / dof)  # the noise scale under the extended model
    lam = critical_noncentrality(k, dof, alpha, 0.8)
    mde = s * np.sqrt(lam) / np.linalg.norm(Xp, axis=0)
    return {**row, "status": "tested", "F": F, "p_value": float(p), "mde": mde.tolist(), "noise_scale": float(s),
            "excess_after": float(np.sqrt(den / dof))}


def gyro_discrepancy(gm: GyroMotions, *, alpha: float = 0.05, n_boot: int = 999, seed: int = 20240708,
                     candidates=CANDIDATE_NAMES, max_rounds: int = 3) -> GyroLoopResult:
    """Run the gyro loop (module docstring) on the motions of a gyro fit."""
    ev = evaluate(gm.ms, gm.C, gm.integrator)
    Jw, rw = ev.whitened()
    n = len(rw)
    excess0 = float(np.sqrt(ev.chi2 / max(n - 9, 1)))
    cols = {c: candidate_jacobian(c, gm) for c in candidates}
    Xws = {c: (ev.whiten(X) if X is not None else None) for c, X in cols.items()}
    E = np.random.default_rng(seed).standard_normal((n, n_boot))
    named, rounds, base, notes = [], [], Jw, []
    wrong_way = _sign_coverage(gm)
    for _ in range(max_rounds):
        rows = {}
        n_candidates = sum(1 for c in candidates if c not in named and Xws[c] is not None)
        for c in candidates:
            if c in named:
                continue
            info = next(x for x in CANDIDATES if x.name == c)
            if Xws[c] is None:
                rows[c] = {"status": "in_base_model" if c == "g_sensitivity" and gm.g_sensitivity_in_base else
                           "not_identifiable", "needs": info.needs, "params": list(info.params), "unit": info.unit}
                continue
            row = _test(base, Xws[c], rw, E, alpha / max(1, n_candidates))
            if c == "scale_asymmetry" and wrong_way and row["status"] == "tested":
                row = {**row, "status": "not_identifiable", "axes_lacking": wrong_way}
            rows[c] = {**row, "needs": info.needs, "params": list(info.params), "unit": info.unit}
        tested = [c for c, r in rows.items() if r["status"] == "tested"]
        adj = holm([rows[c]["p_value"] for c in tested])
        for c, pa in zip(tested, adj):
            rows[c]["p_adjusted"] = float(pa)
        rounds.append(rows)
        sig = [c for c in tested if rows[c]["p_adjusted"] < alpha]
        if not sig:
            break
        best = min(sig, key=lambda c: (rows[c]["p_value"], -rows[c]["F"]))
        named.append(best)
        base = np.column_stack([base, Xws[best]])
    est, excess1 = _refit(Jw, rw, [Xws[c] for c in named], named, n)
    return GyroLoopResult(tuple(named), rounds, excess0, excess1 if named else excess0, est, gm.ms.n_motions, alpha,
                          n_boot, tuple(notes))


def _refit(Jw, rw, Xs, named, n):
    """One Gauss-Newton step in (vec C, β of the named): estimates, standard errors, excess after."""
    if not named:
        return {}, float(np.sqrt(rw @ rw / max(n - 9, 1)))
    A = np.column_stack([Jw, *Xs])
    step, *_ = np.linalg.lstsq(A, -rw, rcond=None)
    res = rw + A @ step
    dof = max(n - A.shape[1], 1)
    s2 = float(res @ res) / dof
    cov = np.linalg.pinv(A.T @ A) * max(s2, 1.0)
    out, j = {}, 9
    for c, X in zip(named, Xs):
        info = next(x for x in CANDIDATES if x.name == c)
        out[c] = {p: (float(step[j + i]), float(np.sqrt(cov[j + i, j + i]))) for i, p in enumerate(info.params)}
        j += X.shape[1]
    return out, float(np.sqrt(s2))




def gyro_layer(rec, g: float, poses, *, alpha: float = 0.05, n_boot: int = 999, seed: int = 20240708):
    """The gyro loop of a recording on the accelerometer's poses: ``(result, None)``, or
    ``(None, reason)`` in one line when the gyro cannot be calibrated from them (no gyro,
    rests too short for its noise, too few motions...): the accelerometer's loop runs anyway.

    The gyro is calibrated as ``accelcal calibrate`` does, but with the g-sensitivity left
    to the loop (a candidate decided by the motions' evidence, not switched on by default).
    """
    from ..calibration import calibrate_poses
    from ..errors import AccelcalError
    from ..gyro.recording import calibrate_recording_gyro

    if rec.gyro is None:
        return None, "no gyro in the recording"
    if rec.rotations:
        return None, "a Ferraris session (rotations of known angle): the gyro loop tests motions between rests"
    try:
        acc = calibrate_poses(poses, g, "full_lls", unit=rec.unit)
        gcal = calibrate_recording_gyro(rec, acc, poses, g_sensitivity=False)
        return gyro_discrepancy(gyro_motions(rec, acc, poses, gcal), alpha=alpha, n_boot=n_boot, seed=seed), None
    except AccelcalError as e:
        return None, f"gyroscope not tested: {str(e).splitlines()[0]}"


__all__ = ["CANDIDATES", "CANDIDATE_NAMES", "GyroCandidate", "GyroLoopResult", "GyroMotions", "candidate_jacobian",
           "gyro_discrepancy", "gyro_layer", "gyro_motions"]
