"""The gyroscope's discrepancy loop: which effect beyond ``ω = C (y - b - G f)`` do the motions ask for?

The gyro is fitted to the motions between rests (:mod:`accelcal.gyro.fit`): per motion, the
gravity direction of the rest before, carried over by the integrated gyro, must meet the
direction of the rest after; two residuals per motion, weighted by the covariance the
rests' noise predicts.  Two things make that null hold (:func:`gyro_motions`,
:func:`loop_evaluation`): the rests are the gyro's still samples, not the accelerometer's
(whose rests take in the slow ends of the turns: a rotation the motions lack, which a time
offset, a g-sensitivity or a motion bias would otherwise "explain"), and the error of each
rest's mean reaches every motion that subtracts it (consecutive motions share a rest), not
only one.  Each candidate is a
nested extension of that model, a perturbation of the bias-free gyro samples
``y → y + Σ_j β_j d_j(y)`` (:data:`CANDIDATES`):

==================  ==  ==========================================================
``g_sensitivity``    9  ``- G f``: a bias proportional to the specific force
``scale_asymmetry``  3  ``a_k y_k [y_k < 0]``: another scale for negative rates
``rate_nonlinearity`` 3 ``q_k y_k |y_k| / s``: a scale that grows with the rate
``time_offset``      1  ``δ ẏ``: the gyro's clock ``δ`` seconds off the accelerometer's; between
                        the gyro's still rests a shift of its samples leaves every rotation as it
                        is, so ``not_identifiable`` here (it needs rates that do not vanish at the
                        ends of the intervals: a turntable against a reference)
``motion_bias``      3  ``- Δb``: a bias that shifts while the sensor moves
``sample_clock``     1  ``w y (Δt_i/h - 1)``: the rotation integrated over each sample's stamp
                        rather than the nominal rate (or the reverse, when the fit used the stamps)
``clock_rate``       1  ``κ y``: a common clock-rate error; C absorbs it between rests, so it is
                        always ``not_identifiable`` here and says what would fix time
==================  ==  ==========================================================

The directions and their use in ``apply`` are one table: :mod:`accelcal.gyro.effects`.
An integration error from the sample clock is identifiable only where the clock is not
uniform: jittering or late stamps inside the motions (a dropped sample is a time gap, and
the fit leaves its motion out).  A common rate error needs time fixed by something
independent of the gyro (known angles or rates).

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

from ..calibration import calibrate_poses
from ..errors import AccelcalError, NotConvergedError
from ..gyro.calibrate import motion_intervals, motion_noise
from ..gyro.effects import directions as effect_directions
from ..gyro.fit import MotionSet, evaluate, fit_iterative, motion_residuals
from ..gyro.model import GyroModel
from ..gyro.recording import calibrate_recording_gyro
from ..gyro.noise import fit_with_noise
from ..gyro.rests import (MIN_STILL_SAMPLES, RestStatistics, bias_series, fit_bias, gyro_rests, motion_bias_variance,
                          rest_noise, sample_interval, saturated_samples)
from ..summary import Summary
from .nested import MAX_ABSORBED, LoopOutcome, nested_f_test
from .statistics import holm

#: Samples kept on either side of a motion when its columns are integrated (magnus4's cubic reads one).
MARGIN = 3
#: Fewest samples in every rest for the gyro's noise (and its autocorrelation) to be measured:
#: as many as a rest keeps when it is shrunk to where the gyro is still.
MIN_REST_SAMPLES = MIN_STILL_SAMPLES
#: "Moving" (the motion bias's samples): a rate above this many times the rest noise on some axis.
MOVING_SIGMAS = 5.0
#: The loop's noise models (:func:`gyro_motions`): ``common``, the rests' noise times one scale
#: estimated from the residuals; ``components``, the gyro calibration's noise model
#: (:mod:`accelcal.gyro.noise`), a scale per source fitted by REML on these motions: the bias's
#: wander per gyro axis, a per-motion error of C and extra rate noise in the motions (the gyro),
#: the rests' directions (the accelerometer); the F test's common scale stays on top of it.
NOISE_MODELS = ("common", "components")


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
    GyroCandidate("sample_clock", ("w_stamps",), "share",
                  "sample times that differ from the nominal rate inside the motions (jittering or late stamps, a "
                  "clock that skips): with uniform stamps integrating over them or over the nominal rate is the "
                  "same; a dropped sample is a time gap and its motion is left out of the fit"),
    GyroCandidate("clock_rate", ("kappa",), "relative",
                  "an independent time reference: rotations of known angle (a turntable, a Ferraris session with "
                  "--rotation-angle) or a known rate; between rests a common clock-rate error multiplies every "
                  "angle as the scales do and C absorbs it"),
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
    still_rests: bool = False  #: the rests are the gyro's still samples: every motion starts and ends at rest


def gyro_motions(rec, acc_cal, poses, gcal, noise: str = "common") -> GyroMotions:
    """The motion set of :func:`accelcal.gyro.calibrate.calibrate_gyro`'s fit ``gcal``, on the gyro's
    own still rests, with ``C`` refitted there under the rests' noise alone.

    The same rests (:func:`accelcal.gyro.rests.gyro_rests`: the accelerometer's shrunk to where
    the gyro is still, the gravity directions averaged over the same samples), bias mode,
    g-sensitivity, time base and used motions (its table) as the calibration the user gets: the
    accelerometer's rests take in the slow ends of the turns, whose rotation the motions then
    lack, and the loop would name that as an effect of the gyro.  ``noise``: one of
    :data:`NOISE_MODELS`.
    """
    if noise not in NOISE_MODELS:
        raise ValueError(f"gyro loop noise model {noise!r}: one of {', '.join(NOISE_MODELS)}")
    s = gcal.settings
    t, gyro = rec.t, np.asarray(rec.gyro, float)
    tb = sample_interval(t)
    rests = gyro_rests(t, gyro, poses, acc_cal, rec.acc)  # the calibration's own rests
    iv, rs, u, u_cov, f_rest = rests.intervals, rests.stats, rests.u, rests.u_cov, rests.f
    gs = bool(s.get("g_sensitivity"))
    best = fit_bias(rs, s.get("bias_mode", "interpolated"), f_rest if gs else None)
    f = np.asarray(acc_cal.apply(np.asarray(rec.acc, float)), float)
    y = gyro - bias_series(best, rs, t)
    if gs:
        y = y - f @ best.g_sensitivity.T
    starts, stops, before, after, _ = motion_intervals(iv, tb.gaps, saturated_samples(gyro, None))
    h = tb.h if s.get("time_base", {}).get("used", "index") == "index" else t
    mn = motion_noise(rs, best, t, starts, stops, f_rest if gs else None) if noise == "components" else None
    ms = MotionSet(y, h, starts, stops, before, after, u, u_cov, rest_noise(rs),
                   motion_bias_variance(best, rs, before, after), mn)
    used = np.asarray(gcal.motions.get("used", [True] * ms.n_motions), bool)
    integrator = s.get("integrator", "magnus4")
    ms = ms.subset(used)
    C = np.asarray(gcal.model.C, float)
    try:
        if mn is None:
            C = fit_iterative(ms, C, integrator).C
        else:  # the components' sizes by REML on these motions, alternated with C
            fit, ms, _ = fit_with_noise(fit_iterative, ms, C, integrator)
            C = fit.C
    except NotConvergedError:
        pass  # the calibration's C: the tests project out its change to first order anyway
    return GyroMotions(ms, C, integrator, f, float(s.get("nominal", 1.0)), gs, np.asarray(t, float), rs,
                       s.get("bias_mode", "interpolated"), still_rests=True)


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


def _bias_weights(gm: GyroMotions, times) -> np.ndarray:
    """``W`` (len(times), p, 3): the bias removed at ``times`` per unit of rest ``k``'s mean on each
    axis.  The bias is linear in the rests' means (a weighted mean, or interpolated between
    rest centres), axis by axis, so one unit mean per rest gives every weight."""
    rs = gm.rests
    p = len(rs.means)
    W = np.empty((len(times), p, 3))
    for k in range(p):
        unit = replace(rs, means=np.eye(p)[k][:, None] * np.ones(3))
        W[:, k, :] = bias_series(fit_bias(unit, gm.bias_mode), unit, times)
    return W


def bias_error_jacobian(gm: GyroMotions) -> np.ndarray | None:
    """∂r/∂(rest means) (2m, 3p): how the error of each rest's mean reaches the motions' residuals.

    Every motion subtracts a bias made of the rests' means, and consecutive motions share a
    rest (interpolated bias) or all share all of them (a constant bias): the errors of the
    means are common to several motions, and a covariance that keeps only each motion's own
    share of them (block diagonal) makes every effect integrated over several motions (a bias
    during motion, a g-sensitivity) look better measured than it is.  On a motion the bias is
    linear in time, so two responses per axis, to a constant and to a ramp over the motion
    (central differences of the integrated residuals), give every column exactly to first order."""
    if gm.rests is None or gm.t is None:
        return None
    ms = gm.ms
    t = np.asarray(gm.t, float)
    idx, small = compact(ms)
    lo = np.maximum(ms.starts - MARGIN, 0)
    owner = np.repeat(np.arange(ms.n_motions), np.minimum(ms.stops + MARGIN + 1, len(ms.y)) - lo)
    ramp = t[idx] - t[ms.starts][owner]  # time from its motion's start, per compact sample
    eps = 1e-4 * max(float(np.max(np.abs(ms.y))), 1e-300)
    resp = np.empty((2, 3, ms.n_motions, 2))  # (constant | ramp, axis, motion, residual)
    for j, shape in enumerate((np.ones_like(ramp), ramp)):
        for a in range(3):
            d = np.zeros_like(small.y)
            d[:, a] = shape * (eps / max(float(np.max(np.abs(shape))), 1e-300))
            rp = motion_residuals(_with_y(small, small.y + d), gm.C, gm.integrator)
            rm = motion_residuals(_with_y(small, small.y - d), gm.C, gm.integrator)
            resp[j, a] = ((rp - rm) / (2 * eps / max(float(np.max(np.abs(shape))), 1e-300))).reshape(-1, 2)
    W0, W1 = _bias_weights(gm, t[ms.starts]), _bias_weights(gm, t[ms.stops])  # (m, p, 3)
    slope = (W1 - W0) / (t[ms.stops] - t[ms.starts])[:, None, None]
    # δy = -δb(t) = -(W0 + slope (t - t_start)) δmean on each motion
    B = -(np.einsum("mpa,amk->mkpa", W0, resp[0]) + np.einsum("mpa,amk->mkpa", slope, resp[1]))
    return B.reshape(2 * ms.n_motions, -1)


def loop_evaluation(gm: GyroMotions):
    """The fit's residuals and Jacobian with the covariance the loop tests under: the rests' noise
    integrated over each motion, the gravity directions' noise and the errors of the rests' means
    shared by the motions that subtract them (:func:`bias_error_jacobian`), in place of the
    fit's per-motion share of the bias error."""
    B = bias_error_jacobian(gm)
    if B is None:
        return evaluate(gm.ms, gm.C, gm.integrator)
    ev = evaluate(replace(gm.ms, bias_var=np.zeros_like(gm.ms.bias_var)), gm.C, gm.integrator)
    cov = ev.cov + (B * (gm.rests.mean_std ** 2).reshape(-1)) @ B.T
    return replace(ev, cov=cov, chol=np.linalg.cholesky(cov))


def _integrated_over(gm: GyroMotions) -> str:
    return "index" if np.ndim(gm.ms.h) == 0 else "timestamps"


def effect_constants(name: str, gm: GyroMotions) -> dict:
    """What fixed a candidate's direction at the fit, for ``apply`` (:func:`accelcal.gyro.effects.correct`)."""
    h = float(gm.ms.h) if np.ndim(gm.ms.h) == 0 else float(np.mean(np.diff(gm.ms.h)))
    c = {"h": h, "integrated_over": _integrated_over(gm)}
    if name == "rate_nonlinearity":
        c["nominal"] = abs(gm.nominal)
    if name == "motion_bias":
        c["threshold"] = (MOVING_SIGMAS * np.sqrt(np.asarray(gm.ms.y_var, float))).tolist()
    return c


def _directions(name: str, gm: GyroMotions) -> list[np.ndarray] | None:
    """The perturbations ``d_j(y)`` (n, 3) of a candidate (:func:`accelcal.gyro.effects.directions`),
    or None when it cannot be formed."""
    if (name == "g_sensitivity" and gm.g_sensitivity_in_base) or (name == "time_offset" and gm.still_rests):
        return None
    c = effect_constants(name, gm)
    inside = None
    if name == "motion_bias":  # a motion's interval also holds the still ends its rests' trim left out
        inside = np.zeros(len(gm.ms.y), bool)
        for a, b in zip(gm.ms.starts, gm.ms.stops):
            inside[a:b + 1] = True
    t = gm.t if name == "sample_clock" else (None if np.ndim(gm.ms.h) == 0 else gm.ms.h)
    return effect_directions(name, gm.ms.y, f=gm.f, t=t, h=c["h"], nominal=gm.nominal, threshold=c.get("threshold"),
                             integrated_over=c["integrated_over"], inside=inside)


def candidate_jacobian(name: str, gm: GyroMotions) -> np.ndarray | None:
    """∂r/∂β (2m, k) of a candidate at the fit: central differences of the integrated residuals."""
    dirs = _directions(name, gm)
    if dirs is None:
        return None
    idx, small = compact(gm.ms)
    cols, ymax = [], np.max(np.abs(gm.ms.y))
    for d in dirs:
        d = _through_bias(gm, d)
        scale = np.max(np.abs(d))
        if not scale > 0:
            cols.append(np.zeros(2 * gm.ms.n_motions))
            continue
        eps = 1e-4 * ymax / scale
        rp = motion_residuals(_with_y(small, small.y + eps * d[idx]), gm.C, gm.integrator)
        rm = motion_residuals(_with_y(small, small.y - eps * d[idx]), gm.C, gm.integrator)
        cols.append((rp - rm) / (2 * eps))
    return np.column_stack(cols)


def compact(ms: MotionSet) -> tuple[np.ndarray, MotionSet]:
    """The motions' samples alone, with :data:`MARGIN` neighbours (what the integration reads):
    ``(index into the recording, the same motions on those samples)``.  A 10-minute recording
    is mostly rests; its columns integrate ~10x fewer samples this way, to the same residuals."""
    n = len(ms.y)
    lo, hi = np.maximum(ms.starts - MARGIN, 0), np.minimum(ms.stops + MARGIN + 1, n)
    idx = np.concatenate([np.arange(a, b) for a, b in zip(lo, hi)]) if len(lo) else np.zeros(0, np.int64)
    offset = np.concatenate([[0], np.cumsum(hi - lo)[:-1]]).astype(np.int64)
    h = ms.h if np.ndim(ms.h) == 0 else np.asarray(ms.h)[idx]
    return idx, MotionSet(ms.y[idx], h, offset + ms.starts - lo, offset + ms.stops - lo, ms.rest_before,
                          ms.rest_after, ms.u, ms.u_cov, ms.y_var, ms.bias_var)


def _with_y(ms: MotionSet, y) -> MotionSet:
    return MotionSet(y, ms.h, ms.starts, ms.stops, ms.rest_before, ms.rest_after, ms.u, ms.u_cov, ms.y_var,
                     ms.bias_var)


@dataclass(frozen=True)
class GyroLoopResult(LoopOutcome):
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
    dC: np.ndarray | None = None  #: the refit's change of ``C`` with the named effects
    calibration: dict | None = None  #: the gyro calibration with the named effects (``apply`` reads it)
    motions: GyroMotions | None = field(default=None, repr=False)  #: the data tested (not in :meth:`to_dict`)
    noise: str = "common"  #: the noise model tested under (:data:`NOISE_MODELS`)

    def to_dict(self) -> dict:
        return {"named": list(self.named) or ["none"], "outcome": self.outcome, "candidates": self.rounds,
                "excess_before": self.excess_before, "excess_after": self.excess_after,
                "estimates": {k: {p: {"value": v, "se": s} for p, (v, s) in e.items()}
                              for k, e in self.estimates.items()},
                "n_motions": self.n_motions, "alpha": self.alpha, "n_boot": self.n_boot,
                "noise_model": "rest noise integrated over each motion, the rests' mean errors shared by the motions "
                               "that subtract them, the gravity directions' noise (rests shrunk to the gyro's still "
                               "samples)" + (", the bias's wander, a per-motion error of C, extra rate noise in the "
                                             "motions and the rests' directions, each with its own size (REML)"
                                             if self.noise == "components" else "") +
                               " times one common scale estimated from the residuals (what wanders between rests)",
                "notes": list(self.notes), "calibration": self.calibration}

    def summary(self, *, written_to=None) -> Summary:
        named = ", ".join(self.named) or "none"
        line = (f"gyroscope: {self.n_motions} motions; effect named: {named}; excess {self.excess_before:.3g} -> "
                f"{self.excess_after:.3g}")
        return Summary([line] + ([f"  written to {written_to}"] if written_to is not None else []))


def _unformed(name: str, gm: GyroMotions) -> str:
    """Why a candidate's direction could not be formed on these data."""
    if name == "g_sensitivity":
        return "in the base model" if gm.g_sensitivity_in_base else "no accelerometer samples (specific force)"
    if name == "time_offset" and gm.still_rests:
        return ("every motion starts and ends with the gyro still: a shift of its samples leaves each rest-to-rest "
                "rotation as it is (the column left is the noise's derivative)")
    if name == "sample_clock":
        return ("no sample times" if gm.t is None else
                "the sample times are uniform: integrating over them or over the nominal rate is the same")
    return "its direction cannot be formed from these samples"


def _sign_coverage(gm: GyroMotions, min_deg: float = 30.0) -> list[str]:
    """Axes whose motions do not turn both ways by ``min_deg`` (the scale asymmetry's need)."""
    y = gm.ms.y @ gm.C.T
    h = gm.ms.h if np.ndim(gm.ms.h) == 0 else np.gradient(gm.ms.h)[:, None]
    moving = np.zeros(len(y), bool)
    for a, b in zip(gm.ms.starts, gm.ms.stops):
        moving[a:b + 1] = True
    ang = np.rad2deg(y * h)[moving]
    return ["xyz"[k] for k in range(3) if min(ang[ang[:, k] > 0, k].sum(), -ang[ang[:, k] < 0, k].sum()) < min_deg]


def gyro_discrepancy(gm: GyroMotions, *, alpha: float = 0.05, n_boot: int = 999, seed: int = 20240708,
                     candidates=CANDIDATE_NAMES, max_rounds: int = 3) -> GyroLoopResult:
    """Run the gyro loop (module docstring) on the motions of a gyro fit."""
    ev = loop_evaluation(gm)
    Jw, rw = ev.whitened()
    n = len(rw)
    excess0 = float(np.sqrt(ev.chi2 / max(n - 9, 1)))
    cols = {c: candidate_jacobian(c, gm) for c in candidates}
    Xws = {c: (ev.whiten(X) if X is not None else None) for c, X in cols.items()}
    E = np.random.default_rng(seed).standard_normal((n, n_boot))
    named, rounds, base, notes = [], [], Jw, []
    formed = sum(X is not None for X in Xws.values())
    if formed and formed / (n_boot + 1) >= alpha:  # Holm's first step needs p_min * candidates < alpha
        notes.append(f"{n_boot} bootstrap draws cannot name anything: the smallest p-value 1/{n_boot + 1} times "
                     f"{formed} candidates is not below alpha = {alpha:g}; use n_boot >= {int(np.ceil(formed / alpha))}")
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
                           "not_identifiable", "why": _unformed(c, gm), "needs": info.needs,
                           "params": list(info.params), "unit": info.unit}
                continue
            row = nested_f_test(base, Xws[c], rw, E, alpha / max(1, n_candidates))
            if c == "scale_asymmetry" and wrong_way and row["status"] == "tested":
                row = {**row, "status": "not_identifiable", "axes_lacking": wrong_way}
            if c == "scale_asymmetry" and row["status"] == "not_identifiable" and "axes_lacking" in row:
                row["why"] = f"no turns of 30 deg both ways about {', '.join(row['axes_lacking'])}"
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
    est, excess1, dC = _refit(Jw, rw, [Xws[c] for c in named], named, n)
    return GyroLoopResult(tuple(named), rounds, excess0, excess1 if named else excess0, est, gm.ms.n_motions, alpha,
                          n_boot, tuple(notes), dC, noise="common" if gm.ms.noise is None else "components")


def estimate_effects(gm: GyroMotions, names) -> dict:
    """The effects ``names`` fitted together on these motions, named or not: ``{name: {param:
    (value, se)}}`` (for comparing one effect across sessions of a unit); an effect that
    cannot be formed or is absorbed on them is left out."""
    ev = loop_evaluation(gm)
    Jw, rw = ev.whitened()
    keep, Xs = [], []
    for c in names:
        X = candidate_jacobian(c, gm)
        if X is None:
            continue
        Xw = ev.whiten(X)
        if nested_f_test(np.column_stack([Jw, *Xs]), Xw, rw, np.zeros((len(rw), 0)), 0.05)["status"] != "tested":
            continue
        keep.append(c)
        Xs.append(Xw)
    return _refit(Jw, rw, Xs, keep, len(rw))[0]


def _refit(Jw, rw, Xs, named, n):
    """One Gauss-Newton step in (vec C, β of the named): estimates, standard errors, excess after."""
    if not named:
        return {}, float(np.sqrt(rw @ rw / max(n - 9, 1))), np.zeros((3, 3))
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
    return out, float(np.sqrt(s2)), step[:9].reshape(3, 3)




def with_effects(gcal, gm: GyroMotions, res: GyroLoopResult) -> dict:
    """``gcal`` refitted with the named effects, as a calibration's ``gyroscope`` object: ``C``
    after the refit, the g-sensitivity (when named) as the model's ``G``, the bias moved by what
    the rests see of the effects (the rests' bias took it in), and ``settings["effects"]``
    (id, values, standard errors, constants) that ``apply`` corrects with
    (:func:`accelcal.gyro.effects.correct`)."""
    m = gcal.model
    G, effects, shift = m.g_sensitivity, [], np.zeros((len(gm.ms.y), 3))
    for c in res.named:
        est = res.estimates[c]
        values = [est[p][0] for p in est]
        effects.append({"id": c, "values": values, "se": [est[p][1] for p in est], "params": list(est),
                        "constants": effect_constants(c, gm)})
        shift = shift + sum(b * dj for b, dj in zip(values, _directions(c, gm)))
        if c == "g_sensitivity":
            G = np.reshape(values, (3, 3))
    bias = m.bias
    if gm.rests is not None and res.named:
        bias = bias + np.mean([shift[a:b].mean(axis=0) for a, b in gm.rests.intervals], axis=0)
    dC = res.dC if res.dC is not None else np.zeros((3, 3))
    d = gcal.to_dict()
    d["model"] = GyroModel(gm.C + dC, bias, G, m.raw_unit).to_dict()
    d["settings"] = {**d["settings"], "effects": effects, "source": "accelcal discrepancy (gyro loop refit)"}
    return d


def rest_noise_problem(gyro, intervals, rate: float) -> str | None:
    """Why the rests cannot measure the gyro's noise (the weights of every test), in one line; None
    when they can.  Too short a rest, or a gyro quantised so coarsely that it reads one level at
    rest (its noise below half a step: what the rests show is not the noise the motions carry)."""
    iv = np.asarray(intervals, dtype=np.int64).reshape(-1, 2)
    n = iv[:, 1] - iv[:, 0]
    if n.min() < MIN_REST_SAMPLES:
        return (f"the rests are too short to measure the gyro's noise: the shortest holds {int(n.min())} samples "
                f"(< {MIN_REST_SAMPLES}, {MIN_REST_SAMPLES / rate:.2g} s at {rate:.4g} Hz); record rests of a few "
                "seconds each")
    g = np.asarray(gyro, float)
    std = np.median([g[a:b].std(axis=0) for a, b in iv], axis=0)
    for k in range(3):
        levels = np.unique(g[: min(len(g), 200_000), k])
        q = float(np.min(np.diff(levels))) if len(levels) > 1 else float("inf")
        if std[k] < 0.5 * q:
            return (f"the rests do not measure the gyro's noise: its {'xyz'[k]} axis reads steps of {q:.3g} and "
                    f"varies by {std[k]:.2g} at rest (below half a step: quantised, the noise hidden); give the gyro "
                    "at a finer resolution")
    return None


def gyro_layer(rec, g: float, poses, *, alpha: float = 0.05, n_boot: int = 999, seed: int = 20240708,
               noise: str = "common"):
    """The gyro loop of a recording on the accelerometer's poses: ``(result, None)``, or
    ``(None, reason)`` in one line when the gyro cannot be calibrated from them (no gyro,
    rests too short for its noise, too few motions...): the accelerometer's loop runs anyway.

    The gyro is calibrated as ``accelcal calibrate`` does, but with the g-sensitivity left
    to the loop (a candidate decided by the motions' evidence, not switched on by default).
    """
    if rec.gyro is None:
        return None, "no gyro in the recording"
    if rec.rotations:
        return None, "a Ferraris session (rotations of known angle): the gyro loop tests motions between rests"
    problem = rest_noise_problem(rec.gyro, poses.intervals, rec.rate)
    if problem is not None:
        return None, f"gyroscope not tested: {problem}"
    try:
        acc = calibrate_poses(poses, g, "full_lls", unit=rec.unit)
        gcal = calibrate_recording_gyro(rec, acc, poses, g_sensitivity=False)
        gm = gyro_motions(rec, acc, poses, gcal, noise)
        res = gyro_discrepancy(gm, alpha=alpha, n_boot=n_boot, seed=seed)
        return replace(res, calibration=with_effects(gcal, gm, res), motions=gm), None
    except AccelcalError as e:
        return None, f"gyroscope not tested: {str(e).splitlines()[0]}"


__all__ = ["CANDIDATES", "CANDIDATE_NAMES", "NOISE_MODELS", "GyroCandidate", "GyroLoopResult", "GyroMotions",
           "candidate_jacobian",
           "bias_error_jacobian", "compact", "effect_constants", "estimate_effects", "gyro_discrepancy", "gyro_layer",
           "gyro_motions", "loop_evaluation", "rest_noise_problem", "with_effects"]
