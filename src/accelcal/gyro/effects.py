"""The gyro's effects beyond ``ω = C (y - b - G f)``: how each one moves the bias-free samples.

One table for the loop that names them (:mod:`accelcal.discrepancy.gyro_loop`) and for
``apply``, which corrects with them: each effect ``j`` is a perturbation of the bias-free
samples ``y → y + Σ_j β_j d_j(y)`` (the corrected samples), ``d_j`` given by
:func:`directions`:

=====================  ==========================================================
``g_sensitivity``      ``- f_b e_a``: a bias ``G f`` (applied as the model's ``G``)
``scale_asymmetry``    ``y_k [y_k < 0] e_k``: another scale for negative rates
``rate_nonlinearity``  ``y_k |y_k| s e_k``: a scale that grows with the rate (``s``: rad/s per raw unit)
``time_offset``        ``ẏ``: the gyro's clock ``δ`` seconds off the accelerometer's
``motion_bias``        ``- e_k [moving]``: a bias that shifts while the sensor turns
``sample_clock``       ``y (Δt_i / h - 1)``: the rotation integrated over each sample's own
                       time step (its stamps) rather than the nominal ``h`` (``β = 1``: the
                       stamps are right; the sign flips when the fit integrated over the stamps)
``clock_rate``         ``y``: every step ``(1 + κ)`` long; the same as a common scale, so
                       between rests never identifiable (the scales absorb it)
=====================  ==========================================================

``apply`` needs, beside ``β``, what fixed the direction at the fit (``constants``): the
threshold of "moving" per axis, the nominal step and which time base the fit integrated.
"""

from __future__ import annotations

import numpy as np

#: Effects whose direction needs the sample times (``t``).
NEEDS_TIME = ("time_offset", "sample_clock")


def steps(t) -> np.ndarray:
    """Each sample's own time step (half the span to its neighbours; ends one-sided) [s]."""
    t = np.asarray(t, float)
    return np.gradient(t)


def clock_weights(t, h: float, integrated_over: str) -> np.ndarray:
    """``Δt_i / h - 1`` (fit over the index) or ``h / Δt_i - 1`` (fit over the stamps)."""
    dt = steps(t)
    return dt / h - 1.0 if integrated_over == "index" else h / dt - 1.0


def moving(y, threshold) -> np.ndarray:
    """1 where some axis turns faster than its ``threshold`` (raw unit), else 0."""
    return np.any(np.abs(np.asarray(y, float)) > np.asarray(threshold, float), axis=1).astype(float)


def directions(name: str, y, *, f=None, t=None, h=None, nominal: float = 1.0, threshold=None,
               integrated_over: str = "index", inside=None) -> list[np.ndarray] | None:
    """The perturbations ``d_j(y)`` (n, 3) of effect ``name``; None where it cannot be formed
    (no specific force, no sample times...).  ``inside``: samples that may count as moving
    (default all)."""
    y, e = np.asarray(y, float), np.eye(3)
    if name == "g_sensitivity":
        return None if f is None else [-np.outer(f[:, b], e[a]) for a in range(3) for b in range(3)]
    if name == "scale_asymmetry":
        return [np.outer(np.where(y[:, k] < 0, y[:, k], 0.0), e[k]) for k in range(3)]
    if name == "rate_nonlinearity":
        return [np.outer(y[:, k] * np.abs(y[:, k]) * abs(nominal), e[k]) for k in range(3)]
    if name == "time_offset":
        dt = steps(t)[:, None] if t is not None else h
        return None if dt is None else [np.gradient(y, axis=0) / dt]
    if name == "motion_bias":
        if threshold is None:
            return None
        m = moving(y, threshold) * (1.0 if inside is None else np.asarray(inside, float))
        return [-np.outer(m, e[k]) for k in range(3)]
    if name == "sample_clock":
        if t is None or h is None:
            return None
        w = clock_weights(t, h, integrated_over)
        return None if not np.any(np.abs(w) > 1e-9) else [y * w[:, None]]
    if name == "clock_rate":
        return [y.copy()]
    raise KeyError(name)


def correct(y, effects, *, t=None) -> np.ndarray:
    """The bias-free samples ``y`` corrected by the named ``effects`` (dicts ``{id, values,
    constants}`` as the gyro loop writes them; ``g_sensitivity`` is the model's ``G``, not here)."""
    y = np.asarray(y, float)
    out = y.copy()
    for e in effects:
        if e["id"] == "g_sensitivity":
            continue
        c = e.get("constants", {})
        if e["id"] in NEEDS_TIME and t is None:
            raise ValueError(f"the gyro effect {e['id']} needs the sample times")
        over = c.get("integrated_over", "index")
        tt = t if (e["id"] == "sample_clock" or over != "index") else None  # as the fit formed it
        d = directions(e["id"], y, t=tt, h=c.get("h"), nominal=c.get("nominal", 1.0), threshold=c.get("threshold"),
                       integrated_over=over)
        if d is None:
            continue  # e.g. uniform stamps: the clock effect moves nothing
        out = out + sum(b * dj for b, dj in zip(e["values"], d))
    return out


__all__ = ["NEEDS_TIME", "clock_weights", "correct", "directions", "moving", "steps"]
