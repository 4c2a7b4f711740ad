"""The noise model the colored null estimates jointly with the calibration, as the loop and the report use it.

The linearised colored problem of a fit (:func:`linearise`, :func:`linearise_noise`: the
pose residuals, their Jacobian and the wander's kernels, :mod:`.colored`), the named noise
term as the report's ``noise_model`` (:func:`noise_model_dict`) and the gaps and excess
under it (:func:`colored_summary`).
"""

from __future__ import annotations

import math

import numpy as np

from .. import distributions as dist
from ..errors import AccelcalError
from . import colored as C
from .fit import Fit, PoseData, evaluate
from .stochastic.implication import centred_pose_variance, pose_difference_variance


def intervals(data: PoseData) -> tuple[np.ndarray, np.ndarray, tuple]:
    """Start and duration [s] of each pose (instantaneous poses if the data have no intervals)."""
    if data.has_intervals:
        return data.t_start, np.maximum(data.t_end - data.t_start, C.POINT_DURATION), ()
    return data.t, np.full(len(data), C.POINT_DURATION), (
        "pose intervals not given: the pose means are treated as instantaneous samples of the wander",)


def linearise(data: PoseData, f: Fit, taus=None, common: float | None = 0.0) -> C.Problem:
    """The colored problem of the fit ``f`` on ``data`` (raises :class:`~.colored.WanderError`),
    with the wander's axis correlation ``common`` (:func:`~.colored.axis_gram`; None: not yet
    diagonalised, see :func:`~.colored.problem`)."""
    J = f.J * f.sigma[:, None]  # unweighted
    grad = -J[:, :3]            # ∂r/∂z = −∂r/∂b
    starts, durations, notes = intervals(data)
    return C.problem(f.residuals, J, f.sigma, grad, starts, durations, taus=taus, notes=notes, common=common)


def linearise_noise(data: PoseData, f: Fit) -> tuple[C.Problem, C.Basis, C.WanderFit]:
    """:func:`linearise` at the REML estimate of the wander's axis correlation under the
    fit's own model (:func:`~.colored.fit_common`): the problem, the :class:`~.colored.Basis`
    of its columns and the REML noise (test grid)."""
    prob = linearise(data, f, common=None)
    return C.fit_common(prob, prob.X0)


def noise_model_dict(w: C.WanderFit | None, prob: C.Problem | None, reason: str = "") -> dict:
    """The ``noise_model`` key: the named stochastic term of the joint fit."""
    base = {"method": "REML of the pose residuals' noise s (white + Gauss-Markov bias wander, tau -> inf: random "
                      "walk; the same wander size on every axis, correlated between the axes by axis_correlation, "
                      "a common-mode share), jointly with the calibration; 95 % profile-likelihood intervals",
            "white": "per-pose standard errors of the rests (static detection) times the white scale"}
    if w is None:
        return {**base, "term": "not_estimated", "estimated": False, "reason": reason}
    shortest = float(np.min(prob.durations)) if prob is not None else float("nan")
    white_like = bool(w.present and np.isfinite(w.tau) and w.tau < 0.5 * shortest)
    if not w.present:
        process = "none"
    elif np.isinf(w.tau):
        process = "random_walk"
    else:
        process = "gauss_markov"
    # the wander is time-correlated beyond doubt when its τ interval stays above the poses
    lo = w.tau_ci[0] if w.tau_ci else float("nan")
    correlated = bool(w.present and np.isfinite(lo) and lo >= 0.5 * shortest)
    return {**base, "term": "bias_wander" if w.present else "none", "process": process, "estimated": True,
            "white_like": white_like, "time_correlation_established": correlated,
            "white_excess_N": math.sqrt(2 * w.q_abs * w.tau) if white_like else float("nan"),
            "size": w.size, "size_ci": list(w.size_ci), "tau_s": w.tau if w.present else float("nan"),
            "tau_ci": list(w.tau_ci),
            "white_scale": w.white_scale, "white_scale_ci": list(w.white_scale_ci),
            "random_walk_K": w.K, "random_walk_K_ci": list(w.K_ci), "q_rel": w.q_rel,
            "excess_ci": list(w.excess_ci), "at_bound": list(w.at_bound),
            "axis_correlation": w.common, "axis_correlation_ci": list(w.common_ci),
            "axis_correlation_profile": {f"{phi:g}": v for phi, v in zip(C.COMMON_GRID, w.common_profile)},
            "notes": list(prob.notes) if prob is not None else [],
            "unit": "size: data unit (std of the wander); tau_s: s; random_walk_K: data unit / sqrt(s); "
                    "white_scale: variance of the white part over the rests' prediction; "
                    "axis_correlation: correlation of the wander between any two sensor axes (its common-mode share; "
                    "interval and -2 log REML likelihood on the grid of the tests); "
                    "white_excess_N: data unit * sqrt(s) (when tau is below the poses, white_like: the wander "
                    "acts as white noise the rests' standard errors miss)"}


def colored_summary(data, base, prob, wander, cur_data, current) -> dict:
    """Gaps and excess under the named noise model (white + bias wander of the final model)."""
    Xf = prob.X0
    # before: the base model on all poses under the final noise model
    s_w = wander.white_scale
    try:
        pb = linearise(data, base, taus=[wander.tau], common=prob.common)
        quad_b = _quad(*C.at(pb, wander), pb.X0) / s_w
        gap_before = math.sqrt(quad_b / len(data))
    except AccelcalError:
        gap_before = float("nan")
    p1, q1 = C.at(prob, wander)
    quad_a = _quad(p1, q1, Xf) / s_w
    mu_rel = C.excess_distribution(p1, Xf, 0, q1, s_w)
    dof = prob.m - Xf.shape[1]
    chi2_obs = float(np.sum(current.weighted ** 2))
    mean, var = float(mu_rel.sum()), float(2 * np.sum(mu_rel ** 2))
    lo, hi = (dist.gamma_ppf([0.025, 0.975], mean ** 2 / var, scale=var / mean) if var > 0 else (mean, mean))
    # per pose (every pose, outliers too): std of the wander's share of the residual about the
    # session's common mean, through the final model's gradient
    starts, durations, _ = intervals(data)
    _, J_all, _ = evaluate(current.p, data, current.effects)
    if wander.present and J_all is not None:
        tau = wander.tau
        D = (pose_difference_variance("random_walk", math.sqrt(wander.q_abs), starts, durations) if np.isinf(tau)
             else pose_difference_variance("gauss_markov", (math.sqrt(wander.q_abs), tau), starts, durations))
        v = centred_pose_variance(D)
        extra = np.sqrt(np.clip(v, 0, None) * C.axis_weight(J_all[:, :3], prob.common))
    else:
        extra = np.zeros(len(data))
    return {
        "gap_colored_before": gap_before,
        "gap_colored_after": math.sqrt(quad_a / len(cur_data)),
        "excess_predicted": math.sqrt(mean / dof) if dof > 0 else float("nan"),
        "excess_predicted_interval": [math.sqrt(lo / dof), math.sqrt(hi / dof)] if dof > 0 else [float("nan")] * 2,
        "excess_observed": math.sqrt(chi2_obs / dof) if dof > 0 else float("nan"),
        "excess_explained": bool(dof > 0 and lo <= chi2_obs <= hi),
        "chi2_mean": mean, "chi2_var": var,
        "wander_residual_std": extra.tolist(),
        "dof": int(dof),
    }


def _quad(prob: C.Problem, q: float, X) -> float:
    """``yᵀ P y`` of a one-τ problem at relative variance ``q`` (unit white scale)."""
    return float(C.profile(prob, X, prob.y[None], np.array([q])).quad[0, 0, 0])


__all__ = ["colored_summary", "intervals", "linearise", "linearise_noise", "noise_model_dict"]
