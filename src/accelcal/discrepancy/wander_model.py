"""The noise model the wander null estimates jointly with the calibration, as the loop and the report use it.

The linearised wander problem of a fit (:func:`linearise`, :func:`linearise_noise`: the
pose residuals, their Jacobian and the wander's kernels, :mod:`.wander`), the named noise
term as the report's ``noise_model`` (:func:`noise_model_dict`) and the gaps and excess
under it (:func:`wander_summary`).
"""

from __future__ import annotations

import math

import numpy as np

from .. import distributions as dist
from ..errors import AccelcalError
from . import wander as C
from .fit import Fit, PoseData, evaluate
from .wander.sums import fit_short, pinned
from .stochastic.implication import centred_pose_variance
from .wander_process import FAMILIES, process_in, process_of, words_of


def intervals(data: PoseData) -> tuple[np.ndarray, np.ndarray, tuple]:
    """Start and duration [s] of each pose (instantaneous poses if the data have no intervals)."""
    if data.has_intervals:
        return data.t_start, np.maximum(data.t_end - data.t_start, C.POINT_DURATION), ()
    return data.t, np.full(len(data), C.POINT_DURATION), (
        "pose intervals not given: the pose means are treated as instantaneous samples of the wander",)


def linearise(data: PoseData, f: Fit, taus=None, common: float | None = 0.0, rests: bool = False) -> C.Problem:
    """The wander problem of the fit ``f`` on ``data`` (raises :class:`~.wander.WanderError`),
    with the wander's axis correlation ``common`` (:func:`~.wander.axis_gram`; None: not yet
    diagonalised, see :func:`~.wander.problem`); ``rests``: its likelihood joined by the
    rests' (``data.rests``, if the data carry them)."""
    J = f.J * f.sigma[:, None]  # unweighted
    grad = -J[:, :3]            # ∂r/∂z = −∂r/∂b
    starts, durations, notes = intervals(data)
    return C.problem(f.residuals, J, f.sigma, grad, starts, durations, taus=taus, notes=notes, common=common,
                     rests=data.rests if rests else None)


def linearise_noise(data: PoseData, f: Fit, family: str = "flicker") -> tuple[C.Problem, C.Basis, C.WanderFit]:
    """:func:`linearise` at the REML estimate of the wander's axis correlation under the
    fit's own model (:func:`~.wander.fit_common`): the problem, the :class:`~.wander.Basis`
    of its columns and the REML noise (test grid), the wander chosen from the members of
    ``family`` (:data:`~.rules.WANDER_FAMILIES`)."""
    fam = FAMILIES[family]
    starts, durations, _ = intervals(data)
    taus = C.tau_grid(durations, float(np.max(starts + durations) - np.min(starts)), members=fam.members)
    prob = linearise(data, f, taus=taus, common=None, rests=fam.rests)
    if fam.short:  # the short part pinned by the rests (:mod:`.wander.sums`)
        short = fit_short(data.rests.full if data.rests is not None else None)
        prob = pinned(prob, short) if short is not None else prob
    return C.fit_common(prob, prob.X0)


def noise_model_dict(w: C.WanderFit | None, prob: C.Problem | None, reason: str = "",
                     placement: dict | None = None) -> dict:
    """The ``noise_model`` key: the named stochastic term of the joint fit, with ``reading``
    (:func:`describe_noise_model`) and ``placement`` (:func:`repeated_placements`)."""
    base = {"method": "REML of the pose residuals' noise s (white + one of: a per-placement offset, a Gauss-Markov "
                      "bias wander, tau -> inf: a random walk, a flicker (1/f) bias; chosen by likelihood; the same "
                      "size on every axis, correlated between the "
                      "axes by axis_correlation, a common-mode share), jointly with the calibration; 95 % "
                      "profile-likelihood intervals",
            "white": "per-pose standard errors of the rests (static detection) times the white scale"}
    if w is None:
        out = {**base, "term": "not_estimated", "process": "none", "estimated": False, "reason": reason}
        return {**out, "reading": describe_noise_model(out)}
    shortest = float(np.min(prob.durations)) if prob is not None else float("nan")
    span = prob.span if prob is not None else float("nan")
    proc = process_of(w, span)
    white_like = proc.white_like(w, shortest)
    # the wander is time-correlated beyond doubt when its τ interval stays above the poses
    correlated = proc.time_correlated(w, shortest)
    out = {**base, "term": proc.term, "process": proc.id, "estimated": True,
           "white_like": white_like, "time_correlation_established": correlated,
           "white_excess_N": proc.white_excess(w, shortest),
           "size": w.size, "size_ci": list(w.size_ci),
           "tau_s": proc.tau_s(w),
           "tau_ci": list(w.tau_ci),
           "white_scale": w.white_scale, "white_scale_ci": list(w.white_scale_ci),
           "random_walk_K": w.K, "random_walk_K_ci": list(w.K_ci), "q_rel": w.q_rel,
           "change_over_session": proc.change_over_session(w, span),
           "session_s": span,
           "excess_ci": list(w.excess_ci), "at_bound": list(w.at_bound),
           "axis_correlation": w.common, "axis_correlation_ci": list(w.common_ci),
           "axis_correlation_profile": {f"{phi:g}": v for phi, v in zip(C.COMMON_GRID, w.common_profile)},
           "notes": list(prob.notes) if prob is not None else [],
           "placement": placement or {},
           "unit": "size: data unit (std of the wander or of the per-placement offset, per axis; null for a random "
                   "walk, which has no stationary size; for flicker its coefficient B, Allan floor 0.664 B); "
                   "tau_s: s (0: the per-placement offset, null: a random walk or flicker); random_walk_K: data unit / sqrt(s) (change_over_session = K sqrt(session_s)); "
                   "white_scale: variance of the white part over the rests' prediction; "
                   "axis_correlation: correlation of the wander between any two sensor axes (its common-mode share; "
                   "interval and -2 log REML likelihood on the grid of the tests); "
                   "white_excess_N: data unit * sqrt(s) (when tau is below the poses, white_like: the wander "
                   "acts as white noise the rests' standard errors miss)"}
    return {**out, "reading": describe_noise_model(out)}


def describe_noise_model(nm: dict, unit: str | None = None) -> str:
    """The named noise term in words, with what its numbers mean (``reading`` of the JSON and
    the command line's line; each process's own words: :meth:`.wander_process.WanderProcess.reading`):
    a random walk as its coefficient and its change over the session (it has no stationary
    size, no correlation time), a Gauss–Markov wander as its size and correlation time (an
    interval open at the top: a random walk is not ruled out; reaching 0: a per-placement
    offset is not), a per-placement offset as its size with what separates it from an
    effect of the orientation.  ``unit``: the data unit, if known (in m/s² the sizes are
    also given in mg)."""
    if not nm.get("estimated"):
        return f"bias wander not estimated (nor a per-placement offset): {nm.get('reason', '')}".rstrip(": ")
    return process_in(nm).reading(nm, words_of(nm, unit))


def repeated_placements(data: PoseData, f: Fit, w: C.WanderFit | None, max_angle_deg: float = 5.0,
                        alpha: float = 0.05) -> dict:
    """What separates a per-placement offset from a deterministic effect of the orientation:
    orientations placed more than once, not in consecutive poses (a rest split in two may be
    one placement).  Poses whose gravity directions (the fit's ``x``) lie within
    ``max_angle_deg`` of each other form a group; ``pure_error_dof`` = Σ (size − 1).  With
    independent offsets of the fitted size (``w``), the residuals of a group scatter about
    their mean with ``χ² = Σ_groups rᵀ(Σ⁻¹ − Σ⁻¹11ᵀΣ⁻¹/1ᵀΣ⁻¹1)r ~ χ²(pure_error_dof)``
    (``Σ`` the poses' white and offset variances); a small χ² (``p_lower`` ≤ α) says the
    offsets repeat with the orientation: part of the excess belongs to the orientation."""
    u = f.x / np.linalg.norm(f.x, axis=1, keepdims=True)
    idx = data.pose_index
    n = len(u)
    parent = list(range(n))

    def root(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    cos = math.cos(math.radians(max_angle_deg))
    for i in range(n):
        for j in range(i + 1, n):
            if abs(int(idx[j]) - int(idx[i])) > 1 and float(u[i] @ u[j]) >= cos:
                parent[root(j)] = root(i)
    groups = {}
    for i in range(n):
        groups.setdefault(root(i), []).append(i)
    groups = [g for g in groups.values() if len(g) > 1]
    dof = sum(len(g) - 1 for g in groups)
    out = {"max_angle_deg": max_angle_deg, "groups": [[int(idx[i]) for i in g] for g in groups],
           "pure_error_dof": int(dof)}
    if not dof:
        return {**out, "reading": "no orientation was placed twice (non-consecutively): a per-placement offset cannot "
                                  "be told apart from a deterministic effect of the orientation here (place at least "
                                  "three orientations twice, not in a row)"}
    grad = -(f.J[:, :3] * f.sigma[:, None])
    v = (w.white_scale if w is not None else 1.0) * f.sigma ** 2
    starts, durations, _ = intervals(data)
    own = process_of(w, float(np.max(starts + durations) - np.min(starts))).own_variance(w) if w is not None else 0.0
    if own:  # a per-placement offset: independent from pose to pose, part of each pose's own variance
        v = v + own * C.axis_weight(grad, w.common)
    chi2 = 0.0
    for g in groups:
        r, wi = f.residuals[g], 1.0 / v[g]
        chi2 += float(np.sum(wi * r * r) - np.sum(wi * r) ** 2 / np.sum(wi))
    p_lower = float(1.0 - dist.chi2_sf(chi2, dof))
    verdict = ("the repeated placements agree better than independent offsets would: part of the excess belongs to "
               "the orientation" if p_lower <= alpha else "the repeated placements scatter as independent offsets do")
    return {**out, "chi2": chi2, "p_lower": p_lower,
            "reading": f"{len(groups)} orientation(s) placed again ({dof} pure-error dof): chi2 {chi2:.3g} on {dof} "
                       f"(P(lower) {p_lower:.3g}): {verdict}"}


def wander_summary(data, base, prob, wander, cur_data, current) -> dict:
    """Gaps and excess under the named noise model (white + bias wander or per-placement offset
    of the final model).  Per pose: ``wander_residual_std``, the wander's (or offset's) share
    of the residual's std (unit of g); ``noise_residual_std``, the whole model's,
    ``sqrt(s σ_i² + share²)`` (what the excess is predicted from)."""
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
    # per pose (every pose, outliers too): std of the wander's (or offset's) share of the residual
    # about the session's common mean, through the final model's gradient, and of the whole
    # noise model (white part times the white scale, and that share)
    starts, durations, _ = intervals(data)
    _, J_all, _ = evaluate(current.p, data, current.effects)
    if wander.present and J_all is not None:
        v = centred_pose_variance(_difference_variance(wander, starts, durations))
        extra = np.sqrt(np.clip(v, 0, None) * C.axis_weight(J_all[:, :3], prob.common))
    else:
        extra = np.zeros(len(data))
    total = np.sqrt(s_w * data.sigma ** 2 + extra ** 2)
    return {
        "gap_wander_before": gap_before,
        "gap_wander_after": math.sqrt(quad_a / len(cur_data)),
        "excess_predicted": math.sqrt(mean / dof) if dof > 0 else float("nan"),
        "excess_predicted_interval": [math.sqrt(lo / dof), math.sqrt(hi / dof)] if dof > 0 else [float("nan")] * 2,
        "excess_observed": math.sqrt(chi2_obs / dof) if dof > 0 else float("nan"),
        "excess_explained": bool(dof > 0 and lo <= chi2_obs <= hi),
        "chi2_mean": mean, "chi2_var": var,
        "wander_residual_std": extra.tolist(),
        "noise_residual_std": total.tolist(),
        "dof": int(dof),
    }


def _difference_variance(w: C.WanderFit, starts, durations) -> np.ndarray:
    """``D_ij = Var(β̄_i − β̄_j)`` of the fitted wander or per-placement offset (data unit²)."""
    return process_of(w, float(np.max(starts + durations) - np.min(starts))).difference_variance(w, starts, durations)


def _quad(prob: C.Problem, q: float, X) -> float:
    """``yᵀ P y`` of a one-τ problem at relative variance ``q`` (unit white scale)."""
    return float(C.profile(prob, X, prob.y[None], np.array([q])).quad[0, 0, 0])


__all__ = ["describe_noise_model", "intervals", "linearise", "linearise_noise", "noise_model_dict",
           "repeated_placements"]
