"""Weighted least-squares fits of the base model and its extensions, on static pose means.

The data (:class:`PoseData`, :mod:`.poses`) and the model's residuals with their Jacobian
(:mod:`.residuals`) are fitted here, and each pose predicted from the others (:func:`lopo`).
This module also gives their public names (``from accelcal.discrepancy.fit import ...``).


Solver.  Levenberg–Marquardt on the weighted residuals ``r_i / σ_i`` with analytic
Jacobian and Marquardt's column scaling, in numpy, from the full LLS closed form (base
model) or from the previous model's optimum with zero effect parameters.  Chosen over
CasADi/IPOPT for the benchmark volume: a 30-pose problem converges in 2–5 iterations of
about 50 µs each, whereas one IPOPT call costs milliseconds of overhead, and the
leave-one-pose-out refits (one per pose, per model, per round) are warm-started from the
full-data optimum and take 1–3 iterations.  Convergence is tested in χ² units (the
residuals are in units of their noise), hence independent of the data unit: stop when
the Gauss–Newton step predicts a χ² decrease below ``CHI2_TOL``.

With numba (:mod:`accelcal.kernels`) the model, the Levenberg–Marquardt loop and the
leave-one-pose-out systems run compiled (:mod:`accelcal.discrepancy._fit_kernels`, loaded
at the first fit: a recording's loop fits hundreds of models); the numpy code here is
their reference.  Both give the same fits to rounding, which the stopping rule can turn
into an iteration more or less: residuals then differ by up to ~1e-5 noise units.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from ..effects import effect
from ..errors import AccelcalError, NotConvergedError
from ..extended_model import NEWTON_RTOL
from ..lls import full_lls
from ..model import m_from_params, params_from_m
from .poses import PoseData, pose_data, pose_data_from_static
from .residuals import (
    N_BASE,
    _evaluate_batch_numpy,
    _model,
    effect_columns,
    effect_slices,
    evaluate,
    evaluate_batch,
    forward,
    n_parameters,
    orthonormal_basis,
    parameter_names,
)

#: Stop when the Gauss–Newton step predicts a χ² decrease below this (χ² is dimensionless).
CHI2_TOL = 1e-10
#: Iteration caps of the full fits and of the warm-started leave-one-pose-out refits.
MAX_ITER = 200
MAX_ITER_LOPO = 50


def fit_at(data: PoseData, effects, p) -> Fit:
    """A :class:`Fit` evaluated at given parameters (no optimisation): the design of a
    simulation at its true parameters, for identifiability and MDE."""
    r, J, x = evaluate(p, data, effects)
    if r is None:
        raise AccelcalError("the model cannot be evaluated at these parameters")
    return Fit(tuple(effects), np.asarray(p, float), r, data.sigma, J / data.sigma[:, None], 0, x)



# --------------------------------------------------------------------------- fits


@dataclass(frozen=True)
class Fit:
    """A weighted least-squares fit of the base model plus ``effects``.

    ``chi2 = Σ (r_i/σ_i)²``; ``J`` is the Jacobian of the *weighted* residuals.
    """

    effects: tuple[str, ...]
    p: np.ndarray
    residuals: np.ndarray
    sigma: np.ndarray
    J: np.ndarray
    iterations: int
    x: np.ndarray = field(repr=False)

    @property
    def weighted(self) -> np.ndarray:
        return self.residuals / self.sigma

    @property
    def chi2(self) -> float:
        return float(self.weighted @ self.weighted)

    @property
    def n(self) -> int:
        return len(self.residuals)

    @property
    def q(self) -> int:
        return len(self.p)

    @property
    def dof(self) -> int:
        return self.n - self.q

    @property
    def M(self) -> np.ndarray:
        return m_from_params(self.p[3:6], self.p[6:9])

    @property
    def bias(self) -> np.ndarray:
        return self.p[:3]

    def block(self, effect_id: str) -> np.ndarray:
        return self.p[effect_slices(self.effects)[effect_id]]

    @cached_property
    def _information_inverse(self) -> np.ndarray:
        # computed once: the reports ask for the scaled and the unscaled standard errors
        return np.linalg.pinv(self.J.T @ self.J)

    @cached_property
    def column_basis(self) -> tuple[np.ndarray, int]:
        """Orthonormal basis of the column space of ``J`` and its numerical rank
        (:func:`orthonormal_basis`; computed once, every candidate of a round projects on it)."""
        return orthonormal_basis(self.J)

    def covariance(self, scaled: bool = True) -> np.ndarray:
        """``(JᵀJ)⁻¹``, times ``χ²/dof`` if ``scaled`` (the residual scatter, as the F-test uses)."""
        cov = self._information_inverse
        if scaled:
            cov = cov * (self.chi2 / self.dof if self.dof > 0 else np.nan)
        return cov

    def standard_errors(self, scaled: bool = True) -> np.ndarray:
        return np.sqrt(np.clip(np.diag(self.covariance(scaled)), 0, None))


def _start(data: PoseData, effects, p0) -> np.ndarray:
    q = n_parameters(effects)
    if p0 is None:
        base = full_lls(data.z, data.g)
        s, th = params_from_m(base.M)
        p0 = np.concatenate([base.bias, s, th])
    p0 = np.asarray(p0, float)
    if len(p0) > q:
        raise AccelcalError(f"start vector has {len(p0)} parameters, the model {q}")
    return np.concatenate([p0, np.zeros(q - len(p0))])


def fit(data: PoseData, effects=(), p0=None, max_iter: int = MAX_ITER) -> Fit:
    """Weighted least squares of the base model plus ``effects`` (Levenberg–Marquardt).

    Parameters
    ----------
    data : PoseData
    effects : sequence of str
        Effect ids (:data:`accelcal.effects.EFFECT_IDS`).
    p0 : array_like, optional
        Start; shorter than the model's parameter vector = padded with zeros (the
        previous model's optimum).  Default: the full LLS closed form.
    max_iter : int

    Raises
    ------
    NotConvergedError
        If the iteration cap is reached, or no start gives an invertible model.
    """
    effects = tuple(effects)
    for e in effects:
        effect(e)
    p = _start(data, effects, p0)
    K, terms = _model(data, effects)
    if K is None:
        p, r, J, x, it, status = _fit_numpy(data, effects, p, max_iter)
    else:
        p, r, J, x, it, status = K.lm_fit(p, data.z, *terms.kernel_arrays, data.g, NEWTON_RTOL, data.sigma,
                                          max_iter, CHI2_TOL)
    if status == 0:
        return Fit(effects, p, r, data.sigma, J, it, x)
    if status == 1:
        raise NotConvergedError(f"model {'+'.join(('base',) + effects)}: start point not invertible")
    raise NotConvergedError(f"model {'+'.join(('base',) + effects)} did not converge in {max_iter} iterations")


def _fit_numpy(data: PoseData, effects, p, max_iter: int):
    """Levenberg–Marquardt of :func:`fit` in numpy (the reference of the compiled kernel):
    ``(p, r, J / σ, x, iterations, status)``, status 0 converged, 1 start not invertible,
    2 not converged."""
    sig = data.sigma

    def fun(pp):
        r, J, x = evaluate(pp, data, effects)
        if r is None:
            return None
        return r, J / sig[:, None], x

    out = fun(p)
    if out is None:
        return p, None, None, None, 0, 1
    r, J, x = out
    cost = float(np.sum((r / sig) ** 2))
    lam = 1e-6
    for it in range(1, max_iter + 1):
        rw = r / sig
        d = np.sqrt(np.sum(J * J, axis=0))
        d[d == 0] = 1.0
        Js = J / d
        q = Js.shape[1]
        A = np.vstack([Js, np.sqrt(lam) * np.eye(q)])
        step = np.linalg.lstsq(A, np.concatenate([-rw, np.zeros(q)]), rcond=None)[0] / d
        pred = cost - float(np.sum((rw + J @ step) ** 2))
        trial = fun(p + step)
        if trial is not None:
            r_new, J_new, x_new = trial
            cost_new = float(np.sum((r_new / sig) ** 2))
        if trial is not None and cost_new <= cost:
            p, r, J, x = p + step, r_new, J_new, x_new
            decrease = cost - cost_new
            cost = cost_new
            lam = max(lam / 10, 1e-12)
            if pred <= CHI2_TOL and decrease <= CHI2_TOL:
                return p, r, J, x, it, 0
        else:
            if pred <= CHI2_TOL:  # at the optimum: no step can lower χ² measurably
                return p, r, J, x, it, 0
            lam *= 10
            if lam > 1e12:
                break


    return p, r, J, x, max_iter, 2


def _lopo_system(data: PoseData, effects):
    """``(P, normal) ↦ (r, cost, step, pred)``: the residuals of the stack ``P`` (row ``i``
    leaves out pose ``i``), the reduced χ², and if ``normal`` each row's Gauss–Newton step
    (in parameter units) and the χ² decrease it predicts (compiled, or in numpy)."""
    sig = data.sigma
    K, terms = _model(data, effects)
    if K is not None:
        def system(P, normal):
            r, cost, step, pred, d, H, grad, solved = K.lopo_step(P, data.z, *terms.kernel_arrays, data.g,
                                                                  NEWTON_RTOL, sig, normal)
            if normal and not solved:
                step, pred = _pinv_step(H, grad, d)
            return r, cost, step, pred

        return system
    keep = 1.0 - np.eye(len(data))

    def system(P, normal):
        r, J, _ = _evaluate_batch_numpy(P, data, terms, normal)
        rw = r / sig * keep
        if not normal:
            return r, np.sum(rw * rw, axis=1), None, None
        Jw = J / sig[None, :, None] * keep[:, :, None]
        d = np.sqrt(np.sum(Jw * Jw, axis=1))
        d[d == 0] = 1.0
        Js = Jw / d[:, None, :]
        JsT = Js.transpose(0, 2, 1)
        H, grad = JsT @ Js, (JsT @ rw[:, :, None])[:, :, 0]
        try:
            step = -np.linalg.solve(H, grad[..., None])[..., 0]
        except np.linalg.LinAlgError:
            return (r, np.sum(rw * rw, axis=1), *_pinv_step(H, grad, d))
        return r, np.sum(rw * rw, axis=1), step / d, -np.sum(grad * step, axis=1)

    return system


def _pinv_step(H, grad, d):
    """Gauss–Newton steps by the pseudo-inverse of every row (some ``H`` is singular)."""
    step = -(np.linalg.pinv(H) @ grad[:, :, None])[:, :, 0]
    return step / d, -np.sum(grad * step, axis=1)


def lopo(f: Fit, data: PoseData, max_iter: int = MAX_ITER_LOPO) -> np.ndarray:
    """Leave-one-pose-out prediction errors in noise units, ``r_i(p̂₋ᵢ) / σ_i``.

    All ``n`` reduced fits run at once: Gauss–Newton on the stack of parameter vectors,
    each with its own pose's weight set to zero, warm-started at the full-data optimum
    (the first step is the exact leverage correction ``r_i / (1 - h_ii)`` of the
    linearised model; the following ones remove the nonlinearity), until every reduced
    fit predicts a χ² decrease below ``CHI2_TOL``.  A reduced fit whose χ² rises, or that
    does not converge, is redone by :func:`fit` (Levenberg–Marquardt).  NaN where the
    reduced fit has no degree of freedom left (``n - 1 <= q``) or fails.
    """
    n, q = f.n, f.q
    out = np.full(n, np.nan)
    if n - 1 <= q:
        return out
    sig = data.sigma
    system = _lopo_system(data, f.effects)
    P = np.tile(f.p, (n, 1))
    start = None
    redo = np.zeros(n, bool)
    pred = np.full(n, np.inf)  # no step yet
    for it in range(max_iter + 1):
        done = it > 0 and not np.nanmax(pred) > CHI2_TOL
        r, cost, step, pred_new = system(P, not (done or it == max_iter))  # the last only needs r, cost
        if start is None:
            start = cost
        if done:
            break
        if it == max_iter:
            redo |= ~(pred <= CHI2_TOL)
            break
        pred = np.where(np.isfinite(pred_new), pred_new, np.inf)
        P = P + step
    redo |= ~np.isfinite(cost) | (cost > start * (1 + 1e-12) + CHI2_TOL)
    out[:] = r[np.arange(n), np.arange(n)] / sig
    for i in np.flatnonzero(redo):
        sub = np.arange(n) != i
        try:
            fi = fit(data.subset(sub), f.effects, p0=f.p, max_iter=MAX_ITER_LOPO)
        except AccelcalError:
            out[i] = np.nan
            continue
        ri, _, _ = evaluate(fi.p, data.subset(np.array([i])), f.effects, jacobian=False)
        out[i] = np.nan if ri is None else ri[0] / sig[i]
    return out


__all__ = ["CHI2_TOL", "N_BASE", "Fit", "PoseData", "effect_columns", "effect_slices", "evaluate", "evaluate_batch",
           "fit", "fit_at", "forward", "lopo", "n_parameters", "orthonormal_basis", "parameter_names", "pose_data",
           "pose_data_from_static"]
