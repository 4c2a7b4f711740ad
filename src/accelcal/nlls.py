"""Iterative nonlinear least squares (the baseline of Burkhard et al. 2024; Clausen & Skaloud 2020).

Minimise ``Σ_i (||M⁻¹(z_i - b)|| - g)²`` over ``(b, s, θ)`` (full) or over ``b`` with
``M = I`` (bias-only), starting from ``b = 0, M = I``, with CasADi + IPOPT (exact
Hessian), in scaled variables (:func:`_solver`).  The NLP is built once per (model, pose count) and reused with the poses
and g as parameters, so that repeated calls (Monte Carlo, timing) pay only the solve.

The data are divided by ``k = sqrt(mean ||z||²)`` as in the closed forms and the
residuals by g, so that IPOPT sees O(1) numbers whatever the unit.  A solve that IPOPT does not report as converged
raises :class:`NotConvergedError` (or, in the batched forms :func:`full_nlls_batch`,
:func:`bias_nlls_batch` and :func:`nlls_batch`, is recorded with its status and NaN
estimates).

Stopping rule (a fair baseline stops at the accuracy the problem needs).  IPOPT stops
when the gradient of the scaled cost is below ``tol``; what is left of the error is
then about ``H⁻¹ ∇f``, which on Burkhard's grid (24 poses, full model) measured
``0.15-0.18 tol / σr`` times the Cramér–Rao bound, with ``σr ≈ noise_std / g`` the
noise of the relative residuals.  So: IPOPT's own default ``tol = 1e-8`` (:data:`DEFAULT_TOL`), unless
the caller gives the noise std and a tenth of the residual noise is smaller; then the
power of ten at or below ``σr / 10`` (:func:`solver_tol`; at most ~2 % of the bound is
added to the error).  For noise above ~1e-7 g this is IPOPT's default; at Burkhard's
smallest noise (1e-7 m/s² ≈ 1e-8 g) it is 1e-9.  Earlier versions used 1e-14, which
made IPOPT fight rounding for 13-19 iterations on ~40 % of the bias-only problems.

casadi is imported on the first solve, not with this module.
"""

from __future__ import annotations

import math
import time
from functools import lru_cache

import numpy as np

from .errors import DegeneratePosesError, InputShapeError, NotConvergedError
from .model import m_from_params_single
from .results import BatchResult, NLLSResult
from .validation import check_g, check_poses, degenerate_trials

#: IPOPT statuses accepted as converged.
CONVERGED = ("Solve_Succeeded", "Solved_To_Acceptable_Level")

#: IPOPT's own default of ``tol`` (scaled NLP error, here the largest gradient entry).
DEFAULT_TOL = 1e-8
#: With a known noise std, ``tol`` is at most this fraction of the scaled noise std.
NOISE_TOL_FRACTION = 0.1
#: Never asked tighter than this (double precision on O(1) data).
MIN_TOL = 1e-13

#: Options of every solve; ``ipopt.tol`` is set per solver (:func:`solver_tol`).  The
#: other convergence options are IPOPT's defaults (exact Hessian, acceptable level 1e-6).
IPOPT_OPTIONS = {
    "ipopt.print_level": 0,
    "ipopt.sb": "yes",
    "print_time": False,
    "ipopt.max_iter": 200,
    "ipopt.hessian_approximation": "exact",
    # IPOPT would divide the cost by its largest gradient at the start when that exceeds
    # 100 (raw counts started from M = I), and then stop far from the optimum: the cost
    # here is already scaled (residuals relative to g, of order one).
    "ipopt.nlp_scaling_method": "none",
}


def solver_tol(noise_std: float | None, radius: float) -> float:
    """IPOPT's ``tol`` for pose means of noise std ``noise_std`` on an ellipsoid of about
    ``radius`` (same unit; the residuals are relative to it, see :func:`_solver`).

    :data:`DEFAULT_TOL` if the noise is unknown or large; else the power of ten at or
    below ``NOISE_TOL_FRACTION * noise_std / radius`` (powers of ten: one solver per
    decade), but not below :data:`MIN_TOL`.
    """
    if noise_std is None:
        return DEFAULT_TOL
    wanted = NOISE_TOL_FRACTION * float(noise_std) / radius
    if not wanted < DEFAULT_TOL:  # also NaN
        return DEFAULT_TOL
    if not wanted > MIN_TOL:
        return MIN_TOL
    return 10.0 ** math.floor(math.log10(wanted))


def _symbolic_m(p):
    """CasADi expression of M(s, θ) (same parametrisation as :func:`accelcal.model.m_from_params`)."""
    import casadi as ca

    s, th = p[3:6], p[6:9]
    sxy, szx, szy = ca.sin(th[0]), ca.sin(th[1]), ca.sin(th[2])
    rows = [
        ca.horzcat(1 + s[0], 0, 0),
        (1 + s[1]) * ca.horzcat(sxy, ca.cos(th[0]), 0),
        (1 + s[2]) * ca.horzcat(szx, szy, ca.sqrt(1 - szx**2 - szy**2)),
    ]
    return ca.vertcat(*rows)


@lru_cache(maxsize=64)
def _solver(model: str, n: int, tol: float = DEFAULT_TOL):
    """IPOPT solver for ``n`` poses, built once and reused.

    Variables ``(b', s', θ)`` (full) or ``b'`` (bias-only), parameters ``P = (z'
    flattened row-major, g')`` with ``z' = z / k``, ``b' = b / k``, ``g' = g / k``; cost
    ``½ Σ (|M'⁻¹(z'_i - b')| - 1)²`` with ``M' = g' M`` (``M' = g' I`` bias-only): the
    residual relative to g.  The same minimiser as ``½ Σ (|M⁻¹(z_i - b)| - g)²`` (the cost
    is divided by the constant g²), but with every parameter of order one also for raw
    counts against g in m/s², where ``M`` (counts per m/s²) is in the hundreds and the
    gradient in b tiny: a gradient tolerance then stops tens of counts from the optimum.
    """
    import casadi as ca

    q = 9 if model == "full" else 3
    p = ca.SX.sym("p", q)
    P = ca.SX.sym("P", 3 * n + 1)
    Z = ca.reshape(P[: 3 * n], 3, n)  # column i = pose i
    g = P[3 * n]
    b = p[:3]
    D = Z - ca.repmat(b, 1, n)
    if model == "full":
        M = _symbolic_m(p)
        # M is lower triangular: x = M⁻¹(z - b) by forward substitution.
        x0 = D[0, :] / M[0, 0]
        x1 = (D[1, :] - M[1, 0] * x0) / M[1, 1]
        x2 = (D[2, :] - M[2, 0] * x0 - M[2, 1] * x1) / M[2, 2]
        X = ca.vertcat(x0, x1, x2)
    else:
        X = D / g
    r = ca.sqrt(ca.sum1(X**2)) - 1
    nlp = {"x": p, "p": P, "f": 0.5 * ca.sumsqr(r)}
    return ca.nlpsol(f"nlls_{model}_{n}", "ipopt", nlp, {**IPOPT_OPTIONS, "ipopt.tol": tol})


def _solve(z: np.ndarray, g: float, model: str, noise_std: float | None = None):
    # Python-side conversions kept lean (scalar arithmetic, DM.nonzeros()): the timing
    # against the closed forms should measure IPOPT, not numpy overhead around it.
    k = float(np.sqrt(np.mean(np.sum(z**2, axis=1))))
    gs = g / k
    solver = _solver(model, len(z), solver_tol(noise_std, _spread(z) if noise_std is not None else k))
    # start b = 0, M = I, i.e. M' = g' I: s' = g' - 1
    x0 = [0.0, 0.0, 0.0, gs - 1.0, gs - 1.0, gs - 1.0, 0.0, 0.0, 0.0] if model == "full" else [0.0, 0.0, 0.0]
    sol = solver(x0=x0, p=np.concatenate([(z / k).ravel(), [gs]]))
    stats = solver.stats()
    p = sol["x"].nonzeros()
    cost = float(sol["f"]) * g * g
    b = np.array([p[0] * k, p[1] * k, p[2] * k])
    if model == "full":
        M = m_from_params_single([(1.0 + p[3]) / gs - 1.0, (1.0 + p[4]) / gs - 1.0, (1.0 + p[5]) / gs - 1.0], p[6:9])
    else:
        M = np.eye(3)
    return b, M, stats["return_status"], int(stats["iter_count"]), cost


def _spread(z: np.ndarray) -> float:
    """RMS distance of the poses from their mean: about the radius of the ellipsoid (in
    the unit of z), which turns the noise std of z into that of the relative residual."""
    return float(np.sqrt(np.mean(np.sum((z - z.mean(axis=0)) ** 2, axis=1))))


def _nlls(z, g, model: str, noise_std: float | None) -> NLLSResult:
    z = check_poses(z, model)
    g = check_g(g)
    b, M, status, iters, cost = _solve(z, g, model, _check_noise(noise_std))
    if status not in CONVERGED or not math.isfinite(b.dot(b) + M.ravel().dot(M.ravel())):
        raise NotConvergedError(f"{model} NLLS did not converge (IPOPT status {status} after {iters} iterations)")
    return NLLSResult._trusted(method=f"{model}_nlls", bias=b, M=M, g=g, poses=z, status=status, iterations=iters,
                               cost=cost)


def _check_noise(noise_std):
    if noise_std is None:
        return None
    v = float(noise_std)
    if not (math.isfinite(v) and v >= 0):
        raise InputShapeError(f"noise_std must be a finite number >= 0 (or None), got {noise_std}")
    return v


def full_nlls(z, g: float, noise_std: float | None = None) -> NLLSResult:
    """Full NLLS: bias, scale factors and non-orthogonality by IPOPT from ``b = 0, M = I``.

    Parameters
    ----------
    z : array_like, shape (n, 3)
        Static pose means, ``n >= 10`` (the same minimum as the closed form, for a
        like-for-like comparison).
    g : float
        Gravity magnitude in the unit of ``z``.
    noise_std : float, optional
        Per-axis noise std of the pose means (unit of ``z``): sets IPOPT's stopping
        tolerance (:func:`solver_tol`; 0 for noise-free poses: the tightest,
        :data:`MIN_TOL`); IPOPT's default tolerance if omitted.

    Returns
    -------
    NLLSResult

    Raises
    ------
    NotConvergedError
        If IPOPT does not report convergence.
    """
    return _nlls(z, g, "full", noise_std)


def bias_nlls(z, g: float, noise_std: float | None = None) -> NLLSResult:
    """Bias-only NLLS: ``M = I``, bias by IPOPT from ``b = 0`` (needs g); ``noise_std``
    as in :func:`full_nlls`."""
    return _nlls(z, g, "bias", noise_std)


def nlls_batch(z, g: float, model: str, noise_std: float | None = None) -> dict[str, np.ndarray]:
    """NLLS over trials ``z`` (T, n, 3); one solver per pose count and tolerance, built
    once and reused.  Non-converged trials are NaN.  ``noise_std`` as in :func:`full_nlls`.

    Returns
    -------
    dict with ``bias`` (T, 3), ``M`` (T, 3, 3), ``status`` (T,) str, ``valid`` (T,) bool,
    ``iterations`` (T,), ``seconds`` (T,) wall time of each solve.
    """
    z = check_poses(z, model, batched=True)
    g = check_g(g)
    T = len(z)
    out = {"bias": np.full((T, 3), np.nan), "M": np.full((T, 3, 3), np.nan),
           "status": np.empty(T, dtype=object), "valid": np.zeros(T, bool),
           "iterations": np.zeros(T, int), "seconds": np.zeros(T)}
    noise_std = _check_noise(noise_std)
    for zi in z[:1]:  # build outside the timed region
        _solver(model, z.shape[1], solver_tol(noise_std, _spread(zi)))
    degenerate = degenerate_trials(z)
    for i in range(T):
        if degenerate[i]:  # refused as the single form refuses it, without a solve
            out["status"][i] = DegeneratePosesError.__name__
            continue
        t0 = time.perf_counter()
        b, M, status, iters, _ = _solve(z[i], g, model, noise_std)
        out["seconds"][i] = time.perf_counter() - t0
        out["status"][i], out["iterations"][i] = status, iters
        if status in CONVERGED:
            out["bias"][i], out["M"][i], out["valid"][i] = b, M, True
    return out


def full_nlls_batch(z, g: float, noise_std: float | None = None) -> BatchResult:
    """:func:`full_nlls` over trials ``z`` (T, n, 3) (:func:`nlls_batch`): ``status`` is
    IPOPT's return status of each trial, ``iterations`` its iteration count."""
    return _batch_result(nlls_batch(z, g, "full", noise_std=noise_std), "full_nlls")


def bias_nlls_batch(z, g: float, noise_std: float | None = None) -> BatchResult:
    """:func:`bias_nlls` over trials ``z`` (T, n, 3), as :func:`full_nlls_batch`."""
    return _batch_result(nlls_batch(z, g, "bias", noise_std=noise_std), "bias_nlls")


def _batch_result(out: dict, method: str) -> BatchResult:
    return BatchResult(method=method, bias=out["bias"], M=out["M"], valid=out["valid"],
                       status=out["status"].astype(str), iterations=out["iterations"])
