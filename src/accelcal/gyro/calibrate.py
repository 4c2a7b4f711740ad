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
   between rests, jittery timestamps.  Each finding is a plain sentence in
   ``quality.warnings``.

Bad input raises a typed error (:mod:`accelcal.gyro.errors`) with one line naming the
cause and the fix: no rotation between the rests, a gyro that shows no rotation where
gravity turns, too few usable motions, a saturated gyro, a time base that does not match.
"""

from __future__ import annotations

import dataclasses
import math
import time
from types import SimpleNamespace

import numpy as np

from .. import distributions as dist
from ..model import dM_dparams, params_from_m
from ..registry import estimators
from ..uncertainty import residual_jacobian
from .errors import GyroInputError, NoMotionError, SaturatedGyroError, TooFewMotionsError
from .fit import MIN_MOTIONS, MotionSet, evaluate, initial_scale, rotation_angles_deg
from .integrate import integrate_intervals, log_so3
from .model import RAW_UNITS, GyroModel
from .noise import MotionNoise, bias_wander, fit_with_noise, g_sensitivity_test, wander_variance
from .rests import (GyroRests, bias_series, check_time_base, fit_bias, gyro_rests, measuring_range,
                    motion_bias_variance, rest_noise, sample_interval, saturated_samples)
from .result import RULES, GyroCalibration, GyroQuality
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
                   noise_model: bool | tuple = True) -> GyroCalibration | tuple[GyroCalibration, ...]:
    """Calibrate the gyro of a multi-position session (module docstring).

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
    noise_model : bool or tuple of bool
        Fit the noise between the rests (:mod:`accelcal.gyro.noise`: the bias's wander from
        the rests, per-motion rotation errors, extra angle random walk in the motions, rest
        direction errors) and weight the motions and give the ± by it (default).  False:
        the rests' white noise alone, the ± scaled by ``max(1, excess)`` (the former
        behaviour; the 95 % intervals then cover far less than 95 % when the bias wanders).
        A tuple: one calibration per value (a tuple), the rests and motions found once.
    """
    t0 = time.perf_counter()
    s = _session(t, gyro, poses, accel, raw_unit, acc, t_gyro, nominal_sensitivity, estimator, integrator, bias,
                 g_sensitivity, gyro_range, time_base)
    prepared_s = time.perf_counter() - t0
    if isinstance(noise_model, tuple):  # one calibration per model; the rests and motions found once
        return tuple(_fit_session(s, m, prepared_s) for m in noise_model)
    return _fit_session(s, noise_model, prepared_s)


def _session(t, gyro, poses, accel, raw_unit, acc, t_gyro, nominal_sensitivity, estimator, integrator, bias,
             g_sensitivity, gyro_range, time_base) -> SimpleNamespace:
    """Steps 1-3 of the module docstring: what the fit of ``C`` starts from, whatever the noise model."""
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
    return SimpleNamespace(t=t, gyro=gyro, est=est, tb=tb, n_rests=len(u), best=best, g_sensitivity=g_sensitivity,
                           g_test=g_test, all_ms=all_ms, used=used, notes=notes, ms=ms, raw_unit=raw_unit,
                           nominal=nominal, nominal_from=nominal_from, bases=_time_bases(time_base, tb, t),
                           integrator=integrator, bias=bias, gyro_range=gyro_range)


def _fit_session(s: SimpleNamespace, noise_model: bool, prepared_s: float) -> GyroCalibration:
    """Steps 4-5 of the module docstring on a :func:`_session`: ``C`` fitted and judged."""
    t0 = time.perf_counter()
    fits, rest_fits, noises = _fit_time_bases(s.est.load(), s.ms, s.bases, s.nominal, s.integrator, noise_model)
    chosen = min(rest_fits, key=lambda k: rest_fits[k].chi2)
    fit, best, tb = fits[chosen], s.best, s.tb
    noise, adj = noises[chosen]
    all_ms = dataclasses.replace(s.all_ms, h=s.bases[chosen])
    model = GyroModel(fit.C, best.bias, best.g_sensitivity if s.g_sensitivity else None, s.raw_unit)
    se = _standard_errors(fit.C, fit.cov, s.nominal, fit.excess, best)
    chi2_per_dof = {k: f.chi2 / max(f.dof, 1) for k, f in rest_fits.items()}
    quality, table = _assess(rest_fits[chosen], all_ms, s.used, s.notes, s.t, tb, best, s.integrator, chi2_per_dof,
                             chosen, _range_use(s.gyro, s.gyro_range, all_ms.subset(s.used)), se["C"])
    settings = {"estimator": s.est.name, "integrator": s.integrator, "bias_mode": s.bias, "nominal": s.nominal,
                "nominal_from": s.nominal_from, "iterations": fit.iterations, "fit_seconds": fit.seconds,
                "seconds": prepared_s + time.perf_counter() - t0, "n_rests": s.n_rests,
                "time_base": {"h": tb.h, "rate": tb.rate, "jitter": tb.jitter, "gaps": int(len(tb.gaps)),
                              "used": chosen, "chi2_per_dof": chi2_per_dof},
                "bias_rests": {"chi2": best.chi2, "dof": best.dof, "excess": best.excess},
                "g_sensitivity": bool(s.g_sensitivity), "g_sensitivity_test": s.g_test,
                "noise_model": _noise_settings(noise, adj, fit) if noise_model else None}
    return s.est.load_calibration()(model, se, quality, table, settings)


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


def _range_use(gyro, gyro_range, ms: MotionSet) -> float:
    """Largest fraction of the measuring range (half-span about its centre) the used motions reach (NaN: unknown)."""
    rng = measuring_range(gyro, gyro_range)
    if rng is None:
        return float("nan")
    centre, half = 0.5 * (rng[0] + rng[1]), 0.5 * (rng[1] - rng[0])
    return max(float(np.max(np.abs(gyro[a:b + 1] - centre))) / half for a, b in zip(ms.starts, ms.stops))


def _assess(fit, all_ms: MotionSet, used, notes, t, tb, best, integrator, base_chi2, chosen, range_use, se_C):
    """Quality, warnings and the per-motion table of a fit (``fit``: judged by the rest noise
    alone; ``se_C`` the standard errors of ``C`` with the noise model)."""
    ev = fit.evaluation
    ms = all_ms.subset(used)
    table, int_err, peak = _motion_table(fit, all_ms, used, notes, t, integrator)
    turn = np.rad2deg(np.sum(np.abs(log_so3(ev.R)), axis=0))
    dof = fit.dof
    p = float(dist.chi2_sf(fit.chi2, dof)) if dof > 0 else float("nan")
    flags, warnings = _fit_warnings(fit, p, turn, se_C)
    more_flags, more_warnings = _data_warnings(ev, notes, tb, best, base_chi2, chosen, range_use, int_err, peak[used])
    quality = GyroQuality(n_motions=ms.n_motions, n_parameters=9, dof=dof, chi2=fit.chi2, p_value=p,
                          excess=fit.excess, residual_rms_deg=float(np.sqrt(np.mean(ev.angles_deg ** 2))),
                          predicted_rms_deg=float(np.sqrt(np.mean(ev.predicted_deg ** 2))),
                          axis_turn_deg=tuple(float(v) for v in turn), warnings=tuple(warnings + more_warnings),
                          flags=tuple(flags + more_flags),
                          scale_rel_se=tuple(float(v) for v in np.diag(se_C) / np.abs(np.diag(fit.C))))
    return quality, table


def _motion_table(fit, all_ms: MotionSet, used, notes, t, integrator):
    """The per-motion table (every motion, used or left out), the difference of the two
    integrators on the used ones [deg] and each motion's peak rate [deg/s]."""
    ev = fit.evaluation
    ms = all_ms.subset(used)
    omega = all_ms.y @ fit.C.T
    R_all = integrate_intervals(omega, all_ms.h, all_ms.starts, all_ms.stops, integrator).R
    other = "coning" if integrator == "magnus4" else "magnus4"
    R_other = integrate_intervals(omega, ms.h, ms.starts, ms.stops, other).R
    int_err = rotation_angles_deg(np.swapaxes(ev.R, -1, -2) @ R_other)
    peak = np.array([np.rad2deg(np.linalg.norm(omega[a:b + 1], axis=1).max()) for a, b in
                     zip(all_ms.starts, all_ms.stops)])
    res_all = np.full(all_ms.n_motions, np.nan)
    pred_all = np.full(all_ms.n_motions, np.nan)
    res_all[used], pred_all[used] = ev.angles_deg, ev.predicted_deg
    table = {"t_start": t[all_ms.starts].tolist(), "t_end": t[all_ms.stops].tolist(),
             "angle_deg": rotation_angles_deg(R_all).tolist(), "peak_rate_dps": peak.tolist(),
             "residual_deg": res_all.tolist(), "predicted_deg": pred_all.tolist(),
             "integration_deg": [None] * all_ms.n_motions, "used": used.tolist(), "note": list(notes)}
    for i, e in zip(np.flatnonzero(used), int_err):
        table["integration_deg"][i] = float(e)
    return table, int_err, peak


def _fit_warnings(fit, p: float, turn, se_C) -> tuple[list, list]:
    """Flags and warnings about the fit itself: residuals beyond the noise, scales the motions
    do not determine, motions too short."""
    ev, dof, C = fit.evaluation, fit.dof, fit.C
    warnings, flags = [], []
    if dof > 0 and fit.excess > RULES["excess"] and p < RULES["p_value"]:
        flags.append("excess")
        warnings.append(f"motion residuals are {fit.excess:.3g}x what the rest noise predicts (chi2/dof = "
                        f"{fit.chi2 / dof:.3g} on {dof} dof): the gyro model, the integration or the rests miss "
                        "something (a disturbed rest, saturation, bias drift); the ± carry the noise model fitted to "
                        "the motions (settings: noise_model)")
    if 0 < dof < RULES["min_dof"]:
        flags.append("few_dof")
        warnings.append(f"only {dof} degrees of freedom check the fit (2 per motion less the 9 parameters): a misfit "
                        "hardly shows and the ± it scales are uncertain by "
                        f"{100 * math.sqrt(2 / dof):.0f}%; record at least {math.ceil((RULES['min_dof'] + 9) / 2)} motions "
                        "between rests")
    rel = np.diag(se_C) / np.abs(np.diag(C))
    weak = [a for a in range(3) if rel[a] > RULES["scale_rel_se"] or turn[a] < RULES["min_axis_turn_deg"]]
    if weak:
        flags.append("few_axes")
        warnings.append("the motions turn the sensor little about " + ", ".join(
            f"{'xyz'[a]} ({turn[a]:.0f} deg in all, scale ± {100 * rel[a]:.2g}%)" for a in weak)
            + ": that gyro's scale is poorly determined; add rotations about that axis between rests")
    long = int(np.sum(rotation_angles_deg(ev.R) >= 30.0))
    if long < RULES["min_long_motions"]:
        flags.append("short_motions")
        short = int(np.sum(rotation_angles_deg(ev.R) < RULES["short_deg"]))
        warnings.append(f"only {long} motions turn 30 deg or more ({short} "
                        f"turn less than {RULES['short_deg']:g} deg): short motions hardly determine the scales; "
                        "turn the sensor further between rests")
    return flags, warnings


def _data_warnings(ev, notes, tb, best, base_chi2, chosen, range_use, int_err, peak_used) -> tuple[list, list]:
    """Flags and warnings about the data: the sample rate against the motions, saturation, the
    measuring range, gaps, jittering time steps, a drifting bias."""
    warnings, flags = [], []
    bad_int = int_err > RULES["integration_fraction"] * ev.predicted_deg
    if np.any(bad_int):
        flags.append("sample_rate")
        warnings.append(f"in {int(bad_int.sum())} motions the two integrators differ by up to {int_err.max():.2g} deg "
                        f"(noise {np.median(ev.predicted_deg):.2g} deg): the sample rate ({tb.rate:.4g} Hz) is low "
                        "for these motions (up to {:.0f} deg/s); record faster or turn more slowly".format(
                            np.nanmax(peak_used)))
    n_sat = sum("saturated" in n for n in notes)
    if n_sat:
        flags.append("saturated")
        warnings.append(f"{n_sat} motions left out: the gyro reaches its range in them (saturation); turn the "
                        "sensor more slowly between poses")
    if range_use > RULES["range_fraction"]:
        flags.append("near_range")
        warnings.append(f"the motions reach {100 * range_use:.0f}% of the gyro's measuring range: near saturation the "
                        "scale may not be linear; turn the sensor more slowly, or give the range (--gyro-range)")
    n_gap = sum("missing" in n for n in notes)
    if n_gap:
        flags.append("gaps")
        warnings.append(f"{n_gap} motions left out: samples are missing in them (time gaps)")
    if tb.jitter > RULES["jitter"]:
        flags.append("jitter")
        how = ("with the sample index at the mean rate {:.4g} Hz (host receive times?)".format(tb.rate)
               if chosen == "index" else "with the time stamps' own steps (the sensor's sampling jitters)")
        tried = ", ".join(f"{k} {v:.3g}" for k, v in base_chi2.items())
        warnings.append(f"time steps jitter by {100 * tb.jitter:.0f}% of the step: the motions are integrated {how}"
                        f" (chi2/dof: {tried})")
    if best.mode == "all" and best.dof > 0 and best.excess > RULES["bias_excess"]:
        flags.append("bias_drift")
        warnings.append(f"the gyro's rest means scatter {best.excess:.3g}x their noise: the bias moves during the "
                        "session (warm-up, drift); bias 'interpolated' follows it")
    return flags, warnings


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


__all__ = ["MIN_MOTIONS", "accel_direction_cov", "calibrate_gyro", "evaluate_model", "motion_estimator",
           "motion_intervals", "motion_noise"]
