"""The Allan check: what the bias wander estimated from the poses implies for the rests.

:func:`allan_check` is the independent check of the wander null (``noise_implication``'s
``allan_check`` key, :mod:`.noise_implication`): the wander the deterministic layer
estimated jointly with the calibration predicts an Allan deviation of the rests; it is
compared with the one the stochastic layer measured, where the wander should be visible.
"""

from __future__ import annotations

import numpy as np

from ..noise.allan import avar_interval, pooled_edf
from .wander_process import process_in


def allan_check(noise_model: dict, stoch, level: float = 0.95, min_share: float = 0.1) -> dict:
    """What the jointly estimated wander implies for the Allan deviation of the rests.

    At averaging times ``τ_A`` much shorter than its correlation time the wander adds
    ``K² τ_A / 3`` to the Allan variance (its short-lag random-walk part, ``K² = 2 s²/τ``;
    the exact Gauss–Markov Allan variance is used).  Per axis, the prediction white (the
    rests' white-only fit) + wander, with the band of the wander's 95 % interval of ``K``,
    is compared with the measured Allan deviation and its ``level`` interval (χ² with the
    Satterthwaite mix of the white- and random-walk-FM edf), at the ``τ_A`` where the
    wander is at least ``min_share`` of the predicted Allan variance (where both layers see
    the same time scales), Bonferroni over those ``τ_A``.  The check is one-sided: the
    wander is *contradicted* on an axis when the rests show less Allan variance than white +
    the lower end of the band at some compared ``τ_A`` (``rests show less``); the rests
    showing more is not a contradiction (short-term noise such as a vibration the rests
    carry in their own standard errors), it is reported as ``more_at``.  ``consistent``
    otherwise; ``not visible in the rests`` when the wander is below ``min_share`` at every
    ``τ_A`` the rests reach.
    """
    found = process_in(noise_model).rest_allan(noise_model)
    if isinstance(found, dict):  # nothing the rests can show
        return found
    K, K_ci, avar = found
    fs = stoch.fs

    def wander_avar(taus, k):
        return avar(taus, k, fs)

    band = (K_ci[0] if np.isfinite(K_ci[0]) else 0.0, K_ci[1] if np.isfinite(K_ci[1]) else np.inf)
    axes = {a.axis: _axis_allan_check(a, stoch, wander_avar, K, band, level, min_share) for a in stoch.axes}
    verdicts = [c["verdict"] for c in axes.values()]
    verdict = verdicts[0] if len(set(verdicts)) == 1 else "; ".join(f"{ax}: {c['verdict']}" for ax, c in axes.items())
    return {"axes": axes, "min_share": min_share, "level": level, "verdict": verdict}


def _axis_allan_check(a, stoch, wander_avar, K: float, band: tuple, level: float, min_share: float) -> dict:
    """:func:`allan_check` on one axis: the measured Allan variance against white + wander
    (``wander_avar(taus, K)``, its band from the ends of ``K``'s interval) where the wander
    is at least ``min_share`` of the prediction."""
    taus = np.asarray(a.taus, float)
    white = a.fit_before["white"]["value"] ** 2 / taus
    wv = wander_avar(taus, K)
    lo_w, hi_w = (wander_avar(taus, k) for k in band)
    share = wv / (white + wv)
    seen = share >= min_share
    m = np.round(taus * stoch.fs).astype(int)
    nu_w, nu_r = pooled_edf(stoch.segment_lengths, m, 0), pooled_edf(stoch.segment_lengths, m, -2)
    nu = (white + wv) ** 2 / (white ** 2 / np.maximum(nu_w, 1e-9) + wv ** 2 / np.maximum(nu_r, 1e-9))
    k = max(int(seen.sum()), 1)
    meas = np.asarray(a.adev_measured, float) ** 2
    lo, hi = avar_interval(meas[:, None], nu[:, None], 1 - (1 - level) / k)
    lo, hi = lo[:, 0], hi[:, 0]
    pred_lo, pred_hi = white + lo_w, white + hi_w
    less = seen & (pred_lo > hi)
    more = seen & (pred_hi < lo)
    if not seen.any():
        v = "not visible in the rests"
    elif less.any():
        v = "rests show less"
    else:
        v = "consistent"
    return {
        "verdict": v, "taus": taus.tolist(), "adev_measured": np.sqrt(meas).tolist(),
        "adev_interval": np.sqrt(np.column_stack([lo, hi])).tolist(),
        "adev_white": np.sqrt(white).tolist(), "adev_predicted": np.sqrt(white + wv).tolist(),
        "adev_predicted_band": np.sqrt(np.column_stack([pred_lo, pred_hi])).tolist(),
        "wander_share": share.tolist(), "compared": seen.tolist(),
        "less_at": taus[less].tolist(), "more_at": taus[more].tolist(),
    }


__all__ = ["allan_check"]
