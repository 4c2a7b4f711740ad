"""Gyro calibration of a multi-position session, from arrays to a :class:`GyroCalibration`.

:func:`calibrate_gyro` takes what the accelerometer side already has — the time column,
the static poses found in the accelerometer (:mod:`accelcal.static`) and the accelerometer
calibration (anything with ``apply(raw) -> m/s²``, e.g. :class:`accelcal.calibration.Calibration`)
— and the gyro samples on the same time base, and:

1. checks the time base (same rows as the accelerometer; jitter: the sample index is
   used; gaps: the motions across them are left out);
2. shrinks the accelerometer's rests to where the gyro is still (:func:`accelcal.gyro.rests.gyro_rests`: the
   ends of a turn are still rotation) and takes the bias from them (:mod:`accelcal.gyro.rests`)
   and the noise that every motion integrates;
3. turns each pair of consecutive rests into a motion; leaves out motions in which the gyro
   reaches its range (saturation) or samples are missing, saying which;
4. fits ``C`` (:mod:`accelcal.gyro.fit`: iterative by default, or the one-step estimate)
   from the nominal model (the unit's factor, a given sensitivity, or for raw counts a
   scalar search);
5. judges the result: χ² of the motion residuals against the noise, the rotation each
   gyro axis saw, the integration error (the two product integrators differ by more than
   a fraction of the noise: the sample rate is too low for the motion), the bias moving
   between rests, jittery timestamps (:mod:`accelcal.gyro.assess`).  Each finding is a
   plain sentence in ``quality.warnings``.

Steps 1-3 do not depend on the noise model: :func:`prepare_session` does them once and
returns a :class:`PreparedSession`, whose ``fit(noise_model)`` does steps 4-5 and
returns one calibration; :func:`calibrate_gyro` is the two in a row.

Bad input raises a typed error (:mod:`accelcal.gyro.errors`) with one line naming the
cause and the fix: no rotation between the rests, a gyro that shows no rotation where
gravity turns, too few usable motions, a saturated gyro, a time base that does not match.
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np

from ..model import dM_dparams, params_from_m
from ..registry import MotionEstimator, estimators
from ..uncertainty import residual_jacobian
from .assess import assess, range_use
from .errors import GyroInputError, NoMotionError, SaturatedGyroError, TooFewMotionsError
from .fit import MIN_MOTIONS, MotionSet, evaluate, initial_scale
from .model import RAW_UNITS, GyroModel
from .noise import MotionNoise, bias_wander, fit_with_noise, g_sensitivity_test, wander_variance
from .rests import (BiasEstimate, GyroRests, TimeBase, bias_series, check_time_base, fit_bias, gyro_rests,
                    motion_bias_variance, rest_noise, sample_interval, saturated_samples)
from .result import RULES, GyroCalibration
from .unit_evidence import unit_from_motions

#: Total rotation [deg] about a gyro axis below which its column of C is not determined.
MIN_AXIS_TURN_DEG = 5.0
#: Fewest rests for fitting the g-sensitivity (12 unknowns from 3 per rest) in 'auto' mode.
MIN_RESTS_G = 10
#: F-test level at which 'auto' fits the g-sensitivity.
G_SENSITIVITY_P = 1e-3
#: Integrated rotation below this many noise standard deviations: the gyro saw no motion.
NO_MOTION_SIGMAS = 5.0


def motion_intervals(intervals, gaps, saturated):
    """Consecutive rests -> motions: (starts, stops, before, after, notes)."""
    iv = np.asarray(intervals)
    starts, stops = iv[:-1, 1] - 1, iv[1:, 0]
    notes = []
    starts = np.minimum(starts, stops - 1)  # overlapping rests: a placeholder, never integrated
    csat = np.concatenate([[0], np.cumsum(saturated)])
    for a, b in zip(starts, stops):
        if b <= a + 1:
            notes.append("rests overlap (no motion between them)")
        elif np.any((gaps >= a) & (gaps < b)):
            notes.append("samples missing (time gap)")
        elif csat[b + 1] - csat[a] > 0:
            notes.append(f"gyro at its range in {int(csat[b + 1] - csat[a])} samples (saturated)")
        else:
            notes.append("")
    before = np.arange(len(starts))
    return starts, stops, before, before + 1, notes


def _check_motion(ms: MotionSet, u) -> None:
    """Typed errors for sessions without rotation (module docstring)."""
    h = float(np.mean(np.diff(ms.h))) if np.ndim(ms.h) else ms.h
    turn = np.array([np.linalg.norm(ms.y[a:b + 1].sum(axis=0) * h) for a, b in zip(ms.starts, ms.stops)])
    noise = np.array([math.sqrt((b - a + 1) * float(np.max(ms.y_var))) * h for a, b in zip(ms.starts, ms.stops)])
    tilt = np.rad2deg(np.arccos(np.clip(np.sum(u[ms.rest_before] * u[ms.rest_after], axis=1), -1, 1)))
    moved = turn > NO_MOTION_SIGMAS * noise
    if not np.any(moved) and tilt.max() < 5.0:
        raise NoMotionError(f"the sensor does not turn between its {len(u)} rests (gravity moves by at most "
                            f"{tilt.max():.2g} deg, the gyro shows no rotation): the gyro needs rotations between "
                            "rests in different orientations; record them, or calibrate the accelerometer alone "
                            "(--no-gyro)")
    if np.sum(moved) < MIN_MOTIONS and tilt.max() >= 5.0:
        raise NoMotionError(f"gravity turns by up to {tilt.max():.0f} deg between rests but the gyro shows rotation "
                            f"in only {int(np.sum(moved))} of {len(turn)} motions (integrated rate within "
                            f"{NO_MOTION_SIGMAS:g} noise std of zero): wrong gyro columns, or a gyro not recorded "
                            "with the accelerometer (--gyro FILE, --columns; --no-gyro to leave it out)")


def _check_axes(ms: MotionSet, nominal: float, h: float) -> None:
    """Every gyro axis must turn: a column of ``C`` whose axis never moves is not determined."""
    turn = np.rad2deg(abs(nominal) * h * np.array([np.abs(ms.y[a:b + 1].sum(axis=0)) for a, b in
                                                    zip(ms.starts, ms.stops)]).sum(axis=0))
    idle = [a for a in range(3) if turn[a] < MIN_AXIS_TURN_DEG]
    if idle:
        raise TooFewMotionsError("the motions never turn the sensor about " + " or ".join(
            f"its {'xyz'[a]} axis ({turn[a]:.1f} deg in all)" for a in idle) + ": that gyro's scale and "
            "misalignment cannot be determined; turn the sensor about every axis between rests")


#: Median ratio of the integrated nominal rate to gravity's turn beyond which the nominal scale is wrong.
UNIT_RATIO = 5.0


def _check_nominal(ms: MotionSet, u, nominal: float, nominal_from: str) -> None:
    """The nominal scale must turn the sensor about as far as gravity turns between the rests.

    Gravity's turn between two rests is a lower bound of the rotation, and for the
    mostly single-axis turns of a hand the integrated rate is near it: a unit or
    sensitivity off by 57.3 (rad vs deg) or more gives a median ratio far outside
    ``[1/UNIT_RATIO, UNIT_RATIO]``.
    """
    if nominal_from.startswith("scalar search"):
        return
    h = float(np.mean(np.diff(ms.h))) if np.ndim(ms.h) else ms.h
    turn = np.array([abs(nominal) * h * np.linalg.norm(ms.y[a:b + 1].sum(axis=0)) for a, b in
                     zip(ms.starts, ms.stops)])
    tilt = np.arccos(np.clip(np.sum(u[ms.rest_before] * u[ms.rest_after], axis=1), -1, 1))
    big = tilt > np.deg2rad(20.0)
    if big.sum() < 3:
        return
    ratio = float(np.median(turn[big] / tilt[big]))
    if not 1.0 / UNIT_RATIO <= ratio <= UNIT_RATIO:
        fix = "--gyro-sensitivity" if "sensitivity" in nominal_from else "--gyro-unit (rad/s, deg/s, counts)"
        raise GyroInputError(f"with the {nominal_from} the gyro turns the sensor {ratio:.3g} times as far as gravity "
                             f"turns between the rests (median of {int(big.sum())} motions): the gyro's unit or "
                             f"sensitivity is wrong; pass {fix}")


def _nominal(raw_unit: str, nominal_sensitivity, ms: MotionSet, integrator: str) -> tuple[float, str]:
    if raw_unit not in RAW_UNITS:
        raise GyroInputError(f"unknown gyro unit {raw_unit!r}; known: {', '.join(RAW_UNITS)}")
    if nominal_sensitivity is not None:
        s = float(nominal_sensitivity)
        if not (math.isfinite(s) and s != 0):
            raise GyroInputError(f"gyro sensitivity must be a non-zero number of {raw_unit} per rad/s, got {s}")
        return 1.0 / s, f"given sensitivity {s:g} {raw_unit} per rad/s"
    k = RAW_UNITS[raw_unit]
    if k is not None:
        return k, f"unit {raw_unit}"
    return initial_scale(ms, integrator), "scalar search (no sensitivity given)"


def _use_g_sensitivity(choice, rs, bias, f_rest, acc) -> tuple[bool, dict]:
    """Whether to fit the g-sensitivity: as given, or for 'auto' by the nested F test on the
    rest means with the bias's wander in their covariance (:func:`accelcal.gyro.noise.g_sensitivity_test`:
    a wandering bias is not mistaken for ``G f``)."""
    if choice != "auto":
        return bool(choice), {"decided": "given"}
    p = len(rs.means)
    if acc is None or p < MIN_RESTS_G or bias == "first":
        return False, {"decided": "auto", "reason": "no raw accelerometer samples" if acc is None else
                       f"{p} rests (< {MIN_RESTS_G})" if p < MIN_RESTS_G else "bias from the first rest"}
    test = g_sensitivity_test(rs.means, rs.mean_std, rs.t_mid, f_rest)
    return test["p_value"] < G_SENSITIVITY_P, {"decided": "auto", **test}


def accel_direction_cov(accel, f_rest) -> np.ndarray | None:
    """Joint covariance (3p, 3p) of the rests' gravity directions from the accelerometer
    calibration's own uncertainty (its parameters' ``σ̂² (JᵀJ)⁻¹``, as
    :func:`accelcal.uncertainty.standard_errors`): the gyro's ``C`` is expressed in the
    accelerometer's frame, so an error of that frame is an error of ``C`` common to every
    motion.  None for a calibration that is not the base model's (``M``, ``bias``, ``g``;
    'full' or 'bias'), or without a degree of freedom left."""

    kind = getattr(accel, "model", None)
    if kind not in ("full", "bias") or not all(hasattr(accel, a) for a in ("M", "bias", "g")):
        return None
    x = np.asarray(f_rest, float)
    M, b = np.asarray(accel.M, float), np.asarray(accel.bias, float)
    z = x @ M.T + b  # the rest means in the calibration's own unit, without its effects' offsets
    J = residual_jacobian(z, M, b, kind)
    n, q = J.shape
    if n <= q:
        return None
    r = np.linalg.norm(x, axis=1) - float(accel.g)
    cov = float(r @ r) / (n - q) * np.linalg.inv(J.T @ J)
    Mi = np.linalg.inv(M)
    dx = [np.broadcast_to(-Mi[:, j], x.shape) for j in range(3)]  # ∂x/∂b_j
    if kind == "full":
        dx += [-(x @ (Mi @ dMk).T) for dMk in dM_dparams(*params_from_m(M))]
    nx = np.linalg.norm(x, axis=1)
    u = x / nx[:, None]
    P = (np.eye(3)[None] - u[:, :, None] * u[:, None, :]) / nx[:, None, None]
    U = np.stack([np.einsum("pij,pj->pi", P, d) for d in dx], axis=2).reshape(-1, q)  # (3p, q)
    return U @ cov @ U.T


def motion_noise(rs, best, t, starts, stops, f_rest, direction_cov=None) -> MotionNoise:
    """The noise model of the motions before its components are fitted: durations and the
    wander's part (:mod:`accelcal.gyro.noise`), for the bias mode of ``best``."""
    q = bias_wander(rs.means, rs.mean_std, rs.t_mid, f_rest if best.g_sensitivity is not None else None)
    p = len(rs.t_mid)
    if best.mode == "interpolated":
        weights = None
    else:  # a constant bias: the weighted mean of the rests, or the first
        a = np.eye(p)[0] if best.mode == "first" else np.mean(1.0 / rs.mean_std ** 2, axis=1)
        a = a / a.sum()
        weights = lambda tt: np.broadcast_to(a, (len(tt), p))  # noqa: E731
    ts, te = t[starts], t[np.minimum(stops, len(t) - 1)]
    windows = np.column_stack([t[rs.intervals[:, 0]], t[rs.intervals[:, 1] - 1]])
    return MotionNoise(durations=np.maximum(te - ts, 0.0), wander_q=q, direction_cov=direction_cov,
                       wander_var=wander_variance(q, rs.t_mid, ts, te, weights, windows))


def motion_estimator(name: str):
    """The registry's entry of a gyro estimator of motions between rests (``gyro_iterative``,
    ``gyro_one_step``, or their CLI spellings); one line naming the known ones otherwise."""

    known = {e.name: e for e in estimators("gyroscope", data="motions")}
    e = known.get(str(name).replace("-", "_"))
    if e is None:
        raise GyroInputError(f"unknown gyro estimator {name!r} for motions between rests; known: "
                             f"{', '.join(known)}")
    return e


def _misalignment_jacobian(C) -> np.ndarray:
    """∂vec(T)/∂vec(C) (9, 9), ``T_ij = C_ij / C_jj`` (zero rows on the diagonal)."""
    Jt = np.zeros((9, 9))
    for i in range(3):
        for j in range(3):
            if i != j:
                Jt[3 * i + j, 3 * i + j] = 1.0 / C[j, j]
                Jt[3 * i + j, 4 * j] = -C[i, j] / C[j, j] ** 2
    return Jt


def _parameter_dof(adj, C) -> dict:
    """Satterthwaite degrees of freedom of ``C``'s entries, of ``T``'s and of the scale
    factors (:class:`accelcal.gyro.noise.AdjustedCovariance`); None (JSON) for infinite."""
    def tidy(v):
        return [None if not np.isfinite(x) else float(x) for x in np.ravel(v)]
    dof_C = adj.dof(np.eye(9))
    Jt = _misalignment_jacobian(C)
    off = [3 * i + j for i in range(3) for j in range(3) if i != j]
    dof_T = np.full(9, np.nan)
    dof_T[off] = adj.dof(Jt[off])
    return {"C": tidy(dof_C), "T": tidy(dof_T), "scale_factors": tidy(dof_C[[0, 4, 8]])}


def _standard_errors(C, cov, nominal, excess, bias_est) -> dict:
    k = max(1.0, excess if math.isfinite(excess) else 1.0)
    cov = cov * k * k
    se_C = np.sqrt(np.clip(np.diag(cov), 0, None)).reshape(3, 3)
    Jt = _misalignment_jacobian(C)
    se_T = np.sqrt(np.clip(np.diag(Jt @ cov @ Jt.T), 0, None)).reshape(3, 3)
    kb = max(1.0, bias_est.excess if math.isfinite(bias_est.excess) else 1.0)
    out = {"C": se_C, "T": se_T, "scale_factors": np.diag(se_C) / abs(nominal), "bias": bias_est.bias_se * kb}
    if bias_est.g_sensitivity_se is not None:
        out["g_sensitivity"] = bias_est.g_sensitivity_se * kb
    return out


def calibrate_gyro(t, gyro, poses, accel, *, raw_unit: str = "rad/s", acc=None, t_gyro=None,
                   nominal_sensitivity=None, estimator: str = "gyro_iterative", integrator: str = "magnus4",
                   bias: str = "interpolated", g_sensitivity="auto", gyro_range=None, time_base: str = "auto",
                   noise_model: bool = True) -> GyroCalibration:
    """Calibrate the gyro of a multi-position session (module docstring):
    :func:`prepare_session`, then :meth:`PreparedSession.fit` with ``noise_model``.

    Parameters
    ----------
    t : array_like (n,)
        Time [s] of the accelerometer samples.
    gyro : array_like (n, 3)
        Raw gyro samples in ``raw_unit``, sampled with the accelerometer.
    poses : StaticPoses
        The accelerometer's static poses (``intervals``, ``means``, ``mean_std``).
    accel : object with ``apply(raw) -> m/s²``
        The accelerometer calibration fitted to ``poses``.
    raw_unit : {'rad/s', 'deg/s', 'counts'} or None
        None: not stated; the motions decide it (:mod:`accelcal.gyro.unit_evidence`), or
        a one-line refusal.
    acc : array_like (n, 3), optional
        Raw accelerometer samples (needed with ``g_sensitivity``).
    t_gyro : array_like (n,), optional
        The gyro's own time column, checked against ``t``.
    nominal_sensitivity : float, optional
        Raw units per rad/s (counts); the start and the reference of the scale factors.
    estimator : str
        A gyroscope estimator of motions of the registry (:mod:`accelcal.registry`):
        ``'gyro_iterative'`` (default) or ``'gyro_one_step'``; the calibration is of its class.
    integrator : {'magnus4', 'coning'}
    bias : {'interpolated', 'all', 'first'}
        How the bias is taken from the rests (:mod:`accelcal.gyro.rests`).  Default
        'interpolated': on the eight real sessions it gave the lowest motion χ² in all
        (by up to 2x; the Xsens unit's and the IMU-TK fork's rest means move by 6-18x
        their noise during a session).
    g_sensitivity : bool or 'auto'
        Fit ``G`` (from the rests) with the bias.  'auto' (default): when the raw
        accelerometer samples are given and there are at least ``MIN_RESTS_G`` rests, if
        ``G`` explains the rest means significantly better (F test on the rest means, p <
        0.001; the F test compares the two fits' own scatter, so a noise level that is off
        does not decide it).
    gyro_range : (lo, hi), optional
        Measuring range in raw units (saturation).
    time_base : {'auto', 'index', 'timestamps'}
        Integrate with a constant step (the sample index at the mean rate) or with the
        time column's own steps.  'auto': the index unless the steps jitter (more than
        5 %); then both are fitted and the one whose motion residuals fit the noise better
        (lower χ²) is kept — host receive times jitter while the sensor samples evenly,
        a sensor's own time stamps jitter with its sampling — and the choice is said.
    noise_model : bool
        Fit the noise between the rests (:mod:`accelcal.gyro.noise`: the bias's wander from
        the rests, per-motion rotation errors, extra angle random walk in the motions, rest
        direction errors) and weight the motions and give the ± by it (default).  False:
        the rests' white noise alone, the ± scaled by ``max(1, excess)`` (the former
        behaviour; the 95 % intervals then cover far less than 95 % when the bias wanders).
        Both on one session: :func:`prepare_session` once, then its ``fit`` with each.
    """
    return prepare_session(t, gyro, poses, accel, raw_unit=raw_unit, acc=acc, t_gyro=t_gyro, bias=bias,
                           nominal_sensitivity=nominal_sensitivity, estimator=estimator, integrator=integrator,
                           g_sensitivity=g_sensitivity, gyro_range=gyro_range, time_base=time_base).fit(noise_model)


def prepare_session(t, gyro, poses, accel, *, raw_unit: str = "rad/s", acc=None, t_gyro=None,
                    nominal_sensitivity=None, estimator: str = "gyro_iterative", integrator: str = "magnus4",
                    bias: str = "interpolated", g_sensitivity="auto", gyro_range=None,
                    time_base: str = "auto") -> PreparedSession:
    """Steps 1-3 of the module docstring, which no noise model changes: the time base, the
    gyro's rests and its bias, the usable motions with their noise, the unit and the
    nominal scale — checked, with bad input refused here.  The parameters are
    :func:`calibrate_gyro`'s; the result is fitted per noise model by
    :meth:`PreparedSession.fit` (the coverage Monte Carlo fits each trial both ways)."""
    t0 = time.perf_counter()
    t = np.asarray(t, float)
    gyro = np.asarray(gyro, float)
    if gyro.shape != (t.size, 3) or not np.all(np.isfinite(gyro)):
        raise GyroInputError(f"gyro samples must be finite, shape ({t.size}, 3) like the accelerometer's; got "
                             f"{gyro.shape}")
    est = motion_estimator(estimator)
    tb = sample_interval(t)
    if t_gyro is not None:
        check_time_base(t, t_gyro, tb.h)
    if g_sensitivity is True and acc is None:
        raise GyroInputError("the g-sensitivity needs the raw accelerometer samples (acc=)")
    rests = gyro_rests(t, gyro, poses, accel, acc)
    rs, u, f_rest = rests.stats, rests.u, rests.f
    g_sensitivity, g_test = _use_g_sensitivity(g_sensitivity, rs, bias, f_rest, acc)
    best = fit_bias(rs, bias, f_rest if g_sensitivity else None)
    y = gyro - bias_series(best, rs, t)
    if g_sensitivity:
        y = y - np.asarray(accel.apply(np.asarray(acc, float)), float) @ best.g_sensitivity.T
    all_ms, used, notes = _usable_motions(y, t, tb, rests, best, accel, gyro, gyro_range)
    ms = all_ms.subset(used)
    raw_unit, nominal, nominal_from = _unit_and_nominal(raw_unit, nominal_sensitivity, ms, u, integrator, gyro)
    _check_axes(ms, nominal, tb.h)
    return PreparedSession(t=t, gyro=gyro, estimator=est, time_base=tb, n_rests=len(u), bias_fit=best,
                           g_sensitivity=g_sensitivity, g_test=g_test, all_motions=all_ms, used=used, notes=notes,
                           motions=ms, raw_unit=raw_unit, nominal=nominal, nominal_from=nominal_from,
                           bases=_time_bases(time_base, tb, t), integrator=integrator, bias=bias,
                           gyro_range=gyro_range, seconds=time.perf_counter() - t0)


@dataclasses.dataclass(frozen=True, eq=False)
class PreparedSession:
    """A session ready for the fit of ``C`` (:func:`prepare_session`): what every noise model
    starts from.  :meth:`fit` leaves it unchanged, so one session gives each noise model
    the calibration a separate :func:`calibrate_gyro` call gives (imucal's split of the
    algorithm from its result: the data prepared once, fitted into a result object)."""

    t: np.ndarray  #: time [s] of the samples (n,)
    gyro: np.ndarray  #: raw gyro samples (n, 3)
    estimator: MotionEstimator  #: the registry's entry
    time_base: TimeBase  #: the time column's step, rate, jitter and gaps
    n_rests: int
    bias_fit: BiasEstimate  #: the bias (and g-sensitivity) from the rests
    g_sensitivity: bool  #: whether ``G`` is fitted
    g_test: dict  #: how that was decided
    all_motions: MotionSet  #: every motion between the rests, bias removed, with its noise
    used: np.ndarray  #: which motions are usable (bool per motion)
    notes: list  #: why the others are not
    motions: MotionSet  #: the usable motions
    raw_unit: str
    nominal: float  #: rad/s per raw unit
    nominal_from: str  #: where ``nominal`` comes from
    bases: dict  #: the time bases to fit, ``{name: h or t}``
    integrator: str
    bias: str  #: the bias mode
    gyro_range: tuple | None  #: the measuring range given
    seconds: float  #: wall time of the preparation

    def fit(self, noise_model: bool = True) -> GyroCalibration:
        """Steps 4-5 of the module docstring: ``C`` fitted on each time base, the base chosen,
        judged (:func:`accelcal.gyro.assess.assess`); ``noise_model`` as :func:`calibrate_gyro`'s."""
        if not isinstance(noise_model, (bool, np.bool_)):
            raise GyroInputError(f"noise_model must be True or False, got {noise_model!r}: to fit several noise "
                                 "models, prepare the session once (prepare_session) and fit it with each")
        t0 = time.perf_counter()
        best, tb, used = self.bias_fit, self.time_base, self.used
        fits, rest_fits, noises = _fit_time_bases(self.estimator.load(), self.motions, self.bases, self.nominal,
                                                  self.integrator, noise_model)
        chosen = min(rest_fits, key=lambda k: rest_fits[k].chi2)
        fit = fits[chosen]
        noise, adj = noises[chosen]
        all_ms = dataclasses.replace(self.all_motions, h=self.bases[chosen])
        model = GyroModel(fit.C, best.bias, best.g_sensitivity if self.g_sensitivity else None, self.raw_unit)
        se = _standard_errors(fit.C, fit.cov, self.nominal, fit.excess, best)
        chi2_per_dof = {k: f.chi2 / max(f.dof, 1) for k, f in rest_fits.items()}
        quality, table = assess(rest_fits[chosen], all_ms, used, self.notes, self.t, tb, best, self.integrator,
                                chi2_per_dof, chosen, range_use(self.gyro, self.gyro_range, all_ms.subset(used)),
                                se["C"])
        settings = {"estimator": self.estimator.name, "integrator": self.integrator, "bias_mode": self.bias,
                    "nominal": self.nominal, "nominal_from": self.nominal_from, "iterations": fit.iterations,
                    "fit_seconds": fit.seconds, "seconds": self.seconds + time.perf_counter() - t0,
                    "n_rests": self.n_rests,
                    "time_base": {"h": tb.h, "rate": tb.rate, "jitter": tb.jitter, "gaps": int(len(tb.gaps)),
                                  "used": chosen, "chi2_per_dof": chi2_per_dof},
                    "bias_rests": {"chi2": best.chi2, "dof": best.dof, "excess": best.excess},
                    "g_sensitivity": bool(self.g_sensitivity), "g_sensitivity_test": self.g_test,
                    "noise_model": _noise_settings(noise, adj, fit) if noise_model else None}
        return self.estimator.load_calibration()(model, se, quality, table, settings)


def _noise_settings(noise, adj, fit) -> dict:
    """The noise model between the rests as the calibration's settings keep it."""
    return {**noise.to_dict(), "chi2": fit.chi2, "dof": fit.dof, "chi2_per_dof": fit.chi2 / max(fit.dof, 1),
            "parameter_dof": _parameter_dof(adj, fit.C)}


def _time_bases(time_base: str, tb, t) -> dict:
    """The time bases to fit (``{name: h or t}``): the index, or with jittering steps both (module docstring)."""
    if time_base not in ("auto", "index", "timestamps"):
        raise GyroInputError(f"unknown time base {time_base!r}; known: auto, index, timestamps")
    bases = {"index": tb.h, "timestamps": t}
    tried = ["index"] if (time_base == "auto" and tb.jitter <= RULES["jitter"]) else (
        ["index", "timestamps"] if time_base == "auto" else [time_base])
    return {k: bases[k] for k in tried}


def _unit_and_nominal(raw_unit, nominal_sensitivity, ms, u, integrator, gyro):
    """The raw unit (stated, or decided by the motions) and the nominal rad/s per raw unit, checked."""
    if raw_unit is None and nominal_sensitivity is not None:
        raw_unit = "counts"  # a sensitivity is counts per rad/s
    if raw_unit is None:  # not stated: the motions decide it (unit_evidence)
        return unit_from_motions(ms, integrator, gyro)
    nominal, nominal_from = _nominal(raw_unit, nominal_sensitivity, ms, integrator)
    _check_nominal(ms, u, nominal, nominal_from)
    return raw_unit, nominal, nominal_from


def _usable_motions(y, t, tb, rests: GyroRests, best, accel, gyro, gyro_range):
    """Every motion between the gyro's rests (bias removed from ``y``) with its noise, which are
    usable and why the others are not; one line when too few are."""
    rs, u, u_cov, f_rest = rests.stats, rests.u, rests.u_cov, rests.f
    sat = saturated_samples(gyro, gyro_range)
    starts, stops, before, after, notes = motion_intervals(rests.intervals, tb.gaps, sat)
    all_ms = MotionSet(y, tb.h, starts, stops, before, after, u, u_cov, rest_noise(rs),
                       motion_bias_variance(best, rs, before, after),
                       motion_noise(rs, best, t, starts, stops, f_rest, accel_direction_cov(accel, f_rest)))
    if all_ms.n_motions < MIN_MOTIONS:
        raise TooFewMotionsError(f"{len(u)} rests give {all_ms.n_motions} motions; the gyro's 9 parameters need at "
                                 f"least {MIN_MOTIONS}: record more poses (or shorter still phases: --min-duration)")
    _check_motion(all_ms, u)
    used = np.array([n == "" for n in notes])
    n_sat = sum("saturated" in n for n in notes)
    if used.sum() < MIN_MOTIONS:
        cls = SaturatedGyroError if n_sat else TooFewMotionsError
        raise cls(f"only {int(used.sum())} of {len(notes)} motions are usable ({n_sat} saturated, "
                  f"{sum('missing' in n for n in notes)} with missing samples), {MIN_MOTIONS} needed: turn the sensor "
                  "more slowly between poses, or give the range with --gyro-range if it is wider than the data "
                  "suggest")
    return all_ms, used, notes


def _fit_time_bases(fitter, ms, bases: dict, nominal: float, integrator: str, noise_model: bool):
    """The fit on each time base (``{name: h or t}``): the fits, the fits judged by the rest noise
    alone (which chooses the base), and each base's noise model and its small-sample adjustment."""
    fits, rest_fits, noises = {}, {}, {}
    for name, base in bases.items():  # the noise model fitted with C; the time base judged by the rest noise alone
        msb = dataclasses.replace(ms, h=base)
        if noise_model:
            fits[name], noisy, adj = fit_with_noise(fitter, msb, nominal * np.eye(3), integrator)
        else:
            fits[name], noisy, adj = fitter(dataclasses.replace(msb, noise=None), nominal * np.eye(3),
                                            integrator), msb, None
        ev = evaluate(noisy, fits[name].C, integrator, rest_only=True)
        rest_fits[name] = dataclasses.replace(fits[name], chi2=ev.chi2, evaluation=ev)
        noises[name] = (noisy.noise, adj)
    return fits, rest_fits, noises


def evaluate_model(t, gyro, poses, accel, C, bias_vector, *, integrator: str = "magnus4", g_sensitivity=None,
                   acc=None):
    """Per-motion misfit [deg] of *any* gyro calibration (a peer's) on a session: the angle between
    each rest's gravity direction and the previous rest's carried over by the calibrated,
    integrated gyro — the figure of merit no calibration optimises — on the gyro's own rests
    (:func:`accelcal.gyro.rests.gyro_rests`, as the calibration's).  Returns the
    :class:`~accelcal.gyro.fit.Evaluation` and the motion set."""
    tb = sample_interval(t)
    rests = gyro_rests(t, gyro, poses, accel, acc)
    y = np.asarray(gyro, float) - np.asarray(bias_vector, float)
    if g_sensitivity is not None:
        y = y - np.asarray(accel.apply(np.asarray(acc, float)), float) @ np.asarray(g_sensitivity).T
    starts, stops, before, after, _ = motion_intervals(rests.intervals, tb.gaps, np.zeros(len(t), bool))
    ms = MotionSet(y, tb.h, starts, stops, before, after, rests.u, rests.u_cov, rest_noise(rests.stats),
                   np.zeros((len(starts), 3)))
    return evaluate(ms, C, integrator), ms


__all__ = ["MIN_MOTIONS", "PreparedSession", "accel_direction_cov", "calibrate_gyro", "evaluate_model",
           "motion_estimator", "motion_intervals", "motion_noise", "prepare_session"]
