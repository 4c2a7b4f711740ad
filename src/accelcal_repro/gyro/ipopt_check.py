"""Gauss-Newton with the analytic Jacobian against CasADi/IPOPT on the same cost: same minimum?

The gyro fit (:func:`accelcal.gyro.fit.fit_iterative`) is a Gauss-Newton iteration on
``χ²(C) = r(C)ᵀ Σ⁻¹ r(C)`` with the exact Jacobian of the product integrator.  Here the
same cost (the covariance ``Σ`` fixed at the nominal model, the same coning integrator) is
built symbolically in CasADi, every step ``exp(φ_k)`` of every motion unrolled, and solved
by IPOPT with the exact Hessian, as the accelerometer's NLLS is.  Reported: the largest
difference of the two estimates in units of the standard error, both costs, and the time
of each (IPOPT: building the NLP and solving it).
"""

from __future__ import annotations

import time

import numpy as np
import pandas as pd

from accelcal.gyro.fit import evaluate, fit_iterative, tangent_basis
from accelcal.gyro.simulate import random_gyro_matrix, simulate_session


def _expm_sx(phi):
    import casadi as ca

    th2 = ca.dot(phi, phi) + 1e-30
    th = ca.sqrt(th2)
    K = ca.skew(phi)
    return ca.SX.eye(3) + (ca.sin(th) / th) * K + ((1 - ca.cos(th)) / th2) * (K @ K)


def ipopt_fit(ms, chol, C0):
    """IPOPT on the whitened residuals of ``ms`` with the coning integrator (symbolic, unrolled)."""
    import casadi as ca

    t0 = time.perf_counter()
    c = ca.SX.sym("c", 9)
    C = ca.reshape(c, 3, 3).T  # row-major like vec(C)
    h = float(ms.h)
    res = []
    E = tangent_basis(ms.u[ms.rest_after])
    for i, (a, b) in enumerate(zip(ms.starts, ms.stops)):
        R = ca.SX.eye(3)
        w_prev = C @ ms.y[a]
        for k in range(a, b):
            w_next = C @ ms.y[k + 1]
            phi = 0.5 * h * (w_prev + w_next) + h * h / 12.0 * ca.cross(w_prev, w_next)
            R = R @ _expm_sx(phi)
            w_prev = w_next
        w = R.T @ ms.u[ms.rest_before[i]]
        res.append(E[i].T @ w)
    r = ca.vertcat(*res)
    Linv = np.linalg.inv(chol)
    z = ca.mtimes(ca.DM(Linv), r)
    solver = ca.nlpsol("gyro", "ipopt", {"x": c, "f": 0.5 * ca.dot(z, z)},
                       {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes", "ipopt.tol": 1e-12})
    t1 = time.perf_counter()
    sol = solver(x0=np.asarray(C0, float).reshape(9))
    t2 = time.perf_counter()
    return np.array(sol["x"]).reshape(3, 3), 2 * float(sol["f"]), solver.stats()["return_status"], t1 - t0, t2 - t1


def crosscheck(seed: int = 24, n_motions: int = 8, fs: float = 50.0) -> pd.DataFrame:
    """One simulated session solved both ways (module docstring)."""
    rng = np.random.default_rng(seed)
    C_true = random_gyro_matrix(rng)
    s = simulate_session(rng, n_motions=n_motions, angle_deg=90.0, peak_rate_dps=120.0, fs=fs, C=C_true,
                         gyro_noise=0.005, direction_noise=2e-4, rest_s=0.2)
    ev0 = evaluate(s.data, np.eye(3), "coning")
    t0 = time.perf_counter()
    gn = fit_iterative(s.data, np.eye(3), "coning")
    t_gn = time.perf_counter() - t0
    Ci, cost_i, status, t_build, t_solve = ipopt_fit(s.data, ev0.chol, np.eye(3))
    # the Gauss-Newton cost with the covariance frozen at the nominal model, as IPOPT's
    z = np.linalg.solve(ev0.chol, evaluate(s.data, gn.C, "coning").r.reshape(-1))
    se = np.sqrt(np.diag(gn.cov)).reshape(3, 3)
    return pd.DataFrame([{"motions": n_motions, "samples": int((s.data.stops - s.data.starts).sum()),
                          "max_diff_in_se": float(np.max(np.abs(Ci - gn.C) / se)), "chi2_gauss_newton": float(z @ z),
                          "chi2_ipopt": cost_i, "ipopt_status": status, "gauss_newton_s": t_gn,
                          "ipopt_build_s": t_build, "ipopt_solve_s": t_solve}])


__all__ = ["crosscheck", "ipopt_fit"]
