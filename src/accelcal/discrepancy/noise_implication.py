"""The join of both layers: what the noise terms imply for the pose residuals (``noise_implication``).

Each noise model of the stochastic layer implies, per pose and axis, the variance of the
pose-mean error about the session's common mean
(:func:`accelcal.discrepancy.stochastic.pose_difference_variance`): the white-only
simulator before, the simulator with the named terms after.  Their difference reaches the
scalar residual of pose i as ``Σ_k w_ik² Δv_ik`` with ``w_i = ∂r_i/∂z_i`` (the same
projection that turns the per-pose standard errors into ``σ_i``).  Adding it to ``σ_i²`` gives the residual
scatter the deterministic layer should expect if the noise model is complete; the χ² of
the final residuals against it says whether the named noise terms account for the
excess the white-noise model leaves (:func:`rests_implication`).  Under the wander null
the reading is the jointly estimated wander's, with the Allan check of :mod:`.allan_check`
(:func:`noise_implication`).
"""

from __future__ import annotations

import numpy as np

from .. import distributions as dist
from ..errors import AccelcalError
from ..noise.terms import model_avar
from .allan_check import allan_check
from .results import DiscrepancyResult
from .stochastic.implication import centred_pose_variance, pose_difference_variance


def _pose_mean_variance(model: dict, starts, durations) -> np.ndarray:
    """Expected variance of each pose-mean error about the session's common mean under a
    noise model ``{term: value}`` (:func:`accelcal.discrepancy.stochastic.pose_difference_variance`)."""
    return sum(centred_pose_variance(pose_difference_variance(k, v, starts, durations)) for k, v in model.items())


def _extra_variance(stoch, w: np.ndarray, starts, durations) -> tuple[np.ndarray, np.ndarray]:
    """Additional variance of each pose's residual (gradient rows ``w``) under the rests' named
    terms over their white-only fit: extrapolated over the session, and short-term (each pose
    mean carrying only the extra Allan variance at its own duration, no wander between poses:
    the named terms not extrapolated beyond the rests' τ range, ~10 s)."""
    dv = np.zeros_like(w)
    dshort = np.zeros_like(w)
    for k, a in enumerate(stoch.axes):
        before = {t: v["value"] for t, v in a.fit_before.items()}
        dv[:, k] = _pose_mean_variance(a.model_after, starts, durations) - _pose_mean_variance(before, starts, durations)
        dshort[:, k] = model_avar(a.model_after, durations, stoch.fs) - model_avar(before, durations, stoch.fs)
    return np.sum(w * w * np.clip(dv, 0, None), axis=1), np.sum(w * w * np.clip(dshort, 0, None), axis=1)


def _two_sided(upper: float | None, alpha: float) -> tuple[float, str]:
    """Two-sided p-value from the upper tail ``upper`` of the observed χ² and its verdict
    (``None``: no degrees of freedom)."""
    if upper is None:
        return float("nan"), "no degrees of freedom"
    p = min(1.0, 2 * min(upper, 1 - upper))
    return p, "consistent" if p >= alpha else ("residuals exceed it" if upper < 0.5 else "it over-predicts")


def rests_implication(det: DiscrepancyResult, stoch, starts, durations, alpha: float) -> dict:
    """What the noise terms named from the rests mean for the pose residuals of the final model
    (the terms extrapolated from the rests' τ range to the whole session).

    The simulator's noise model before is the white-only fit of each axis, after it is the
    fit with the named terms; ``extra_i = Σ_k w_ik² (v_after,ik - v_before,ik)`` is the
    additional variance of pose i's residual (``v`` the centred pose-mean variances of the
    model, ``w_i = ∂r_i/∂z_i``).  Comparing after with the white-only *fit*, not with the
    white term inside the final fit, avoids counting short-τ noise twice when the final
    fit moves it from ``white`` into another term.

    Parameters
    ----------
    det : DiscrepancyResult
    stoch : StochasticResult
        Its rests must be the poses of ``det`` (same order).
    starts, durations : array_like
        Start and duration [s] of each pose.
    alpha : float

    Returns
    -------
    dict
        ``named_terms`` per axis; ``expected_excess`` = ``sqrt(mean((σ_i² + extra_i)/σ_i²))``
        (1 without named terms); ``observed_excess`` (of the final deterministic model);
        ``expected_excess_short_term``: the same with each pose mean carrying only the
        extra Allan variance at its own duration (no wander between poses: the named
        terms not extrapolated beyond the rests' τ range);
        ``chi2``, ``dof`` and the two-sided ``p_value`` of the final residuals against
        ``σ_i² + extra_i`` (a noise model that predicts far more scatter than the
        residuals show does not explain them either); ``verdict``; ``gap_with_noise_terms``
        = ``sqrt(χ²/n)`` on that yardstick; ``explains_excess`` = p-value ≥ α;
        ``extra_residual_std`` per pose (unit of g).
    """
    if stoch is None:
        return {}
    f = det.final
    if det.final_data is not None and len(det.final_data) != len(starts):  # outlier poses left the fit
        keep = det.final_data.pose_index
        starts, durations = np.asarray(starts)[keep], np.asarray(durations)[keep]
    w = -(f.J[:, :3] * f.sigma[:, None])  # ∂r/∂z = -∂r/∂b (unweighted)
    if len(starts) != w.shape[0] or len(stoch.axes) != 3:
        raise AccelcalError(f"stochastic layer and deterministic layer disagree on the poses ({len(starts)} "
                            f"rests, {w.shape[0]} poses, {len(stoch.axes)} axes)")
    extra, extra_short = _extra_variance(stoch, w, starts, durations)
    s2 = f.sigma ** 2 + extra
    chi2 = float(np.sum(f.residuals ** 2 / s2))
    p, verdict = _two_sided(float(dist.chi2_sf(chi2, f.dof)) if f.dof > 0 else None, alpha)
    return {
        "named_terms": {a.axis: list(a.named) if a.named else ["none"] for a in stoch.axes},
        "expected_excess": float(np.sqrt(np.mean(s2 / f.sigma ** 2))),
        "expected_excess_short_term": float(np.sqrt(np.mean(1 + extra_short / f.sigma ** 2))),
        "observed_excess": float(np.sqrt(f.chi2 / f.dof)) if f.dof > 0 else float("nan"),
        "chi2": chi2, "dof": int(f.dof), "p_value": p,
        "gap_with_noise_terms": float(np.sqrt(chi2 / f.n)),
        "verdict": verdict,
        "explains_excess": bool(np.isfinite(p) and p >= alpha),
        "extra_residual_std": np.sqrt(extra).tolist(),
    }


def noise_implication(det: DiscrepancyResult, stoch, starts, durations, alpha: float) -> dict:
    """Does the named noise model predict the pose residuals' excess over white noise?

    Under the wander null the named noise model is the rests' white per-pose noise plus the
    bias wander estimated jointly with the calibration (``det.noise_model``): the weighted
    χ² of the final least-squares residuals is then distributed as ``Σ μ_k χ²₁``
    (:func:`accelcal.discrepancy.wander.excess_distribution`); the verdict is
    ``consistent`` when the observed χ² lies in its central ``1 − α`` interval (two-sided
    p ≥ α, gamma approximation with the exact mean and variance).  That check uses the
    same residuals the wander was fitted to, so it says that a wander of this family *can*
    account for the excess; ``allan_check`` is the independent one: what the wander implies
    for the Allan deviation of the rests, compared with the measured one where the wander
    should be visible.  ``rests_only`` keeps the reading of the terms named from the rests
    alone (:func:`rests_implication`).  Under the white null, the rests-only reading is
    the implication (as before the wander null existed).

    Returns
    -------
    dict
        ``named_terms``, ``expected_excess``, ``expected_excess_interval``,
        ``expected_excess_short_term``, ``observed_excess``, ``chi2``, ``dof``, ``p_value``,
        ``gap_with_noise_terms``, ``verdict``, ``explains_excess``, ``extra_residual_std``,
        ``model``, ``allan_check``, ``rests_only``.
    """
    rests = rests_implication(det, stoch, starts, durations, alpha) if stoch is not None else {}
    nm = det.noise_model or {}
    if det.rules.null != "wander" or not nm.get("estimated") or not det.wander_summary:
        return rests
    c = det.wander_summary
    f = det.final
    dof = int(c["dof"])
    chi2 = float(np.sum(f.weighted ** 2))
    mean, var = c["chi2_mean"], c["chi2_var"]
    upper = float(dist.gamma_sf(chi2, mean ** 2 / var, scale=var / mean)) if dof > 0 and var > 0 else None
    p, verdict = _two_sided(upper, alpha)
    term = nm.get("term", "none")
    named = {a: [term] for a in "xyz"}
    out = {
        "model": "white per-pose noise (rests) + bias wander (REML, jointly with the calibration)",
        "named_terms": named,
        "expected_excess": c["excess_predicted"],
        "expected_excess_interval": c["excess_predicted_interval"],
        "expected_excess_short_term": rests.get("expected_excess_short_term", float("nan")),
        "observed_excess": c["excess_observed"],
        "chi2": chi2, "dof": dof, "p_value": p,
        "gap_with_noise_terms": c["gap_wander_after"],
        "verdict": verdict,
        "explains_excess": bool(np.isfinite(p) and p >= alpha),
        # beyond the rests' pose noise: the white scale's share and the wander's (or offset's)
        "extra_residual_std": np.sqrt(np.clip(np.square(c["noise_residual_std"])
                                              - np.square(det.data.sigma), 0.0, None)).tolist(),
        "white_scale": nm.get("white_scale"),
        "allan_check": allan_check(nm, stoch) if stoch is not None else {"verdict": "no rests analysed"},
        "rests_only": rests,
    }
    return out


__all__ = ["noise_implication", "rests_implication"]
