"""Step 5 of :mod:`accelcal.gyro.calibrate`: a fit of ``C`` judged — its quality, its warnings
and the per-motion table.

The judgement reads the fit and the session's motions; it fits nothing.  Each finding is a
flag and a plain sentence (the thresholds: :data:`accelcal.gyro.result.RULES`): motion
residuals beyond the noise, few degrees of freedom, an axis that barely turns, short
motions, a sample rate low for the motions (the two product integrators differ), saturation
and the measuring range, gaps, jittering time steps, a drifting bias.
"""

from __future__ import annotations

import math

import numpy as np

from .. import distributions as dist
from .fit import MotionSet, rotation_angles_deg
from .integrate import integrate_intervals, log_so3
from .rests import measuring_range
from .result import RULES, GyroQuality


def range_use(gyro, gyro_range, ms: MotionSet) -> float:
    """Largest fraction of the measuring range (half-span about its centre) the used motions reach (NaN: unknown)."""
    rng = measuring_range(gyro, gyro_range)
    if rng is None:
        return float("nan")
    centre, half = 0.5 * (rng[0] + rng[1]), 0.5 * (rng[1] - rng[0])
    return max(float(np.max(np.abs(gyro[a:b + 1] - centre))) / half for a, b in zip(ms.starts, ms.stops))


def assess(fit, all_ms: MotionSet, used, notes, t, tb, best, integrator, base_chi2, chosen, range_use, se_C):
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


__all__ = ["assess", "range_use"]
