"""Iterative nonlinear least squares (the baseline of Burkhard et al. 2024; Clausen & Skaloud 2020).

Minimise ``Σ_i (||M⁻¹(z_i - b)|| - g)²`` over ``(b, s, θ)`` (full) or over ``b`` with
``M = I`` (bias-only), starting from ``b = 0, M = I``, with CasADi + IPOPT (exact
Hessian).  The NLP is built once per (model, pose count) and reused with the poses
and g as parameters, so that repeated calls (Monte Carlo, timing) pay only the solve.

The data are divided by ``k = sqrt(mean ||z||²)`` as in the closed forms, so that IPOPT
sees O(1) numbers whatever the unit; its tolerance is tight (1e-14 on the scaled
problem) because the Burkhard grids go down to noise of 1e-8 g.  A solve that IPOPT
does not report as converged raises :class:`NotConvergedError` (or, in
:func:`nlls_batch`, is recorded with its status and NaN estimates).
"""

from __future__ import annotations

import math
import time
from functools import lru_cache

import casadi as ca
import numpy as np

from .errors import NotConvergedError
from .model import m_from_params_single
from .results import NLLSResult
from .validation import check_g, check_poses

#: IPOPT statuses accepted as converged.
CONVERGED = ("Solve_Succeeded", "Solved_To_Acceptable_Level")

IPOPT_OPTIONS = {
    "ipopt.print_level": 0,
    "ipopt.sb": "yes",
    "print_time": False,
    "ipopt.tol": 1e-14,
    "ipopt.acceptable_tol": 1e-12,
    "ipopt.max_iter": 200,
    "ipopt.hessian_approximation": "exact",
}


def _symbolic_m(p):
    """CasADi expression of M(s, θ) (same parametrisation as :func:`accelcal.model.m_from_params`)."""
    s, th = p[3:6], p[6:9]
    sxy, szx, szy = ca.sin(th[0]), ca.sin(th[1]), ca.sin(th[2])
    rows = [
        ca.horzcat(1 + s[0], 0, 0),
        (1 + s[1]) * ca.horzcat(sxy, ca.cos(th[0]), 0),
        (1 + s[2]) * ca.horzcat(szx, szy, ca.sqrt(1 - szx**2 - szy**2)),
    ]
    return ca.vertcat(*rows)


@lru_cache(maxsize=None)
def _solver(model: str, n: int):
    """IPOPT solver for ``n`` poses; parameters ``P = (z flattened row-major, g)``."""
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
        X = D
    r = ca.sqrt(ca.sum1(X**2)) - g
    nlp = {"x": p, "p": P, "f": 0.5 * ca.sumsqr(r)}
    return ca.nlpsol(f"nlls_{model}_{n}", "ipopt", nlp, IPOPT_OPTIONS)


def _solve(z: np.ndarray, g: float, model: str):
    # Python-side conversions kept lean (scalar arithmetic, DM.nonzeros()): the timing
    # against the closed forms should measure IPOPT, not numpy overhead around it.  The
    # scale k stays this expression bit for bit: IPOPT's iteration count at tol 1e-14
    # flips (3 <-> 13 iterations for some bias-only problems) with the last bit of k.
    k = float(np.sqrt(np.mean(np.sum(z**2, axis=1))))
    solver = _solver(model, len(z))
    sol = solver(x0=_X0[model], p=np.concatenate([(z / k).ravel(), [g / k]]))
    stats = solver.stats()
    p = sol["x"].nonzeros()
    cost = float(sol["f"]) * k**2
    b = np.array([p[0] * k, p[1] * k, p[2] * k])
    M = m_from_params_single(p[3:6], p[6:9]) if model == "full" else np.eye(3)
    return b, M, stats["return_status"], int(stats["iter_count"]), cost


#: Start of every solve: b = 0, M = I (s = 0, θ = 0).
_X0 = {"full": np.zeros(9), "bias": np.zeros(3)}
for _x0 in _X0.values():
    _x0.setflags(write=False)


def _nlls(z, g, model: str) -> NLLSResult:
    z = check_poses(z, model)
    g = check_g(g)
    b, M, status, iters, cost = _solve(z, g, model)
    if status not in CONVERGED or not math.isfinite(b.dot(b) + M.ravel().dot(M.ravel())):
        raise NotConvergedError(f"{model} NLLS did not converge (IPOPT status {status} after {iters} iterations)")
    return NLLSResult._trusted(method=f"{model}_nlls", bias=b, M=M, g=g, poses=z, status=status, iterations=iters,
                               cost=cost)


def full_nlls(z, g: float) -> NLLSResult:
    """Full NLLS: bias, scale factors and non-orthogonality by IPOPT from ``b = 0, M = I``.

    Parameters
    ----------
    z : array_like, shape (n, 3)
        Static pose means, ``n >= 10`` (the same minimum as the closed form, for a
        like-for-like comparison).
    g : float
        Gravity magnitude in the unit of ``z``.

    Returns
    -------
    NLLSResult

    Raises
    ------
    NotConvergedError
        If IPOPT does not report convergence.
    """
    return _nlls(z, g, "full")


def bias_nlls(z, g: float) -> NLLSResult:
    """Bias-only NLLS: ``M = I``, bias by IPOPT from ``b = 0`` (needs g)."""
    return _nlls(z, g, "bias")


def nlls_batch(z, g: float, model: str) -> dict[str, np.ndarray]:
    """NLLS over trials ``z`` (T, n, 3); one solver, reused.  Non-converged trials are NaN.

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
    _solver(model, z.shape[1])  # build outside the timed region
    for i in range(T):
        t0 = time.perf_counter()
        b, M, status, iters, _ = _solve(z[i], g, model)
        out["seconds"][i] = time.perf_counter() - t0
        out["status"][i], out["iterations"][i] = status, iters
        if status in CONVERGED:
            out["bias"][i], out["M"][i], out["valid"][i] = b, M, True
    return out
