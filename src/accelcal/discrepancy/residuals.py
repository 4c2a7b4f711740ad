"""The extended model's pose residuals and their Jacobian, numpy and compiled.

Model.  :mod:`accelcal.effects`, implemented by :mod:`accelcal.extended_model`:
``z = M P(x) + b + Σ_additive c φ`` (``z = M P(x) + b + β Δt + γ ΔT`` with the library's
effects) with the pose residual ``r_i = ||x_i|| - g`` (the magnitude a calibration
predicts; the pose direction is a nuisance, as in the base estimators).  ``x_i`` solves
``P(x_i) = y_i``, ``y_i = M⁻¹(z_i - b - Σ_additive c_i φ)``, axis by axis (Newton, from
``x = y``; not needed when no polynomial effect is present).  The Jacobian is analytic
(implicit differentiation): with ``v_ij = x̂_ij / P_j'(x_ij)`` and ``w_i = v_iᵀ M⁻¹``::

    ∂r/∂b = -w,  ∂r/∂(s,θ)_k = -w (∂M/∂p_k) y,
    ∂r/∂φ_j = -w_j c (additive effects: β, γ),  ∂r/∂φ_j = -v_j c x_j^p (polynomial: k, c, κ).

At zero effect parameters ``∂r/∂(b, s, θ)`` is :func:`accelcal.uncertainty.residual_jacobian`.

With numba (:mod:`accelcal.kernels`) the model runs compiled
(:mod:`accelcal.discrepancy._fit_kernels`, loaded at the first fit: a recording's loop
fits hundreds of models); the numpy code here is its reference.
"""

from __future__ import annotations

import numpy as np

from .. import extended_model, kernels
from ..effects import TEMPERATURE, TIME, effect
from ..extended_model import NEWTON_RTOL, EffectTerms, inverse3
from .poses import PoseData

N_BASE = 9
#: The compiled kernels of :func:`evaluate_batch`, :func:`accelcal.discrepancy.fit.fit` and
#: :func:`accelcal.discrepancy.lopo.lopo` (:mod:`accelcal.kernels`).
_KERNELS = "discrepancy._fit_kernels"


def n_parameters(effects) -> int:
    return N_BASE + sum(effect(e).size for e in effects)


def effect_slices(effects) -> dict[str, slice]:
    """Where each effect's block lies in the parameter vector of the model with ``effects``."""
    out, start = {}, N_BASE
    for e in effects:
        size = effect(e).size
        out[e] = slice(start, start + size)
        start += size
    return out


def parameter_names(effects) -> list[str]:
    names = ["b_x", "b_y", "b_z", "s_x", "s_y", "s_z", "theta_xy", "theta_zx", "theta_zy"]
    for e in effects:
        names += list(effect(e).parameters)
    return names


def _m_and_derivatives(s: np.ndarray, th: np.ndarray):
    """Batched ``M(s, θ)`` (B, 3, 3) and ``∂M/∂(s, θ)`` (B, 6, 3, 3); same parametrisation as
    :func:`accelcal.model.m_from_params` / :func:`accelcal.model.dM_dparams` (which are
    unbatched or validate their input: this is the solver's inner loop).  ``ok`` (B,)
    marks valid angles."""
    B = s.shape[0]
    sn, cs = np.sin(th), np.cos(th)
    uzz2 = 1.0 - sn[:, 1] ** 2 - sn[:, 2] ** 2
    ok = (uzz2 > 0) & np.all(1.0 + s > 0, axis=1)
    uzz = np.sqrt(np.where(ok, uzz2, 1.0))
    U = np.zeros((B, 3, 3))
    U[:, 0, 0] = 1.0
    U[:, 1, 0], U[:, 1, 1] = sn[:, 0], cs[:, 0]
    U[:, 2, 0], U[:, 2, 1], U[:, 2, 2] = sn[:, 1], sn[:, 2], uzz
    g1 = 1.0 + s
    M = U * g1[:, :, None]
    dM = np.zeros((B, 6, 3, 3))
    for i in range(3):
        dM[:, i, i, :] = U[:, i, :]
    dM[:, 3, 1, 0], dM[:, 3, 1, 1] = g1[:, 1] * cs[:, 0], -g1[:, 1] * sn[:, 0]
    dM[:, 4, 2, 0], dM[:, 4, 2, 2] = g1[:, 2] * cs[:, 1], -g1[:, 2] * sn[:, 1] * cs[:, 1] / uzz
    dM[:, 5, 2, 1], dM[:, 5, 2, 2] = g1[:, 2] * cs[:, 2], -g1[:, 2] * sn[:, 2] * cs[:, 2] / uzz
    return M, dM, ok


def evaluate_batch(P, data: PoseData, effects, jacobian: bool = True):
    """Pose residuals and Jacobians for a stack of parameter vectors ``P`` (B, q).

    Returns
    -------
    r : ndarray, shape (B, n)
        ``||x_i|| - g`` (unit of g); NaN rows where the model cannot be inverted (a
        solver trial that makes ``P`` non-monotonic or ``M`` singular).
    J : ndarray, shape (B, n, q), or None
        Jacobian of ``r`` (unweighted).
    x : ndarray, shape (B, n, 3)
        The true specific force each pose implies (unit of g).
    """
    P = np.atleast_2d(np.asarray(P, float))
    K, terms = _model(data, effects)
    if K is not None:
        return K.evaluate_batch(P, data.z, *terms.kernel_arrays, data.g, jacobian, NEWTON_RTOL)
    return _evaluate_batch_numpy(P, data, terms, jacobian)


def _model(data: PoseData, effects) -> tuple[object, EffectTerms]:
    """``(K, terms)``: the compiled kernel module (None: numpy runs) and the effects on the
    poses (:meth:`PoseData.effect_terms`; an effect whose covariate the recording lacks
    fails here, on both paths alike)."""
    return kernels.compiled(_KERNELS), data.effect_terms(effects)


def _evaluate_batch_numpy(P, data: PoseData, terms: EffectTerms, jacobian: bool):
    """:func:`evaluate_batch` in numpy (the reference of the compiled kernel)."""
    Bn = P.shape[0]
    n = len(data)
    M, dM, ok = _m_and_derivatives(P[:, 3:6], P[:, 6:9])
    A = np.linalg.inv(np.where(ok[:, None, None], M, np.eye(3)))
    model = terms.at(P[:, N_BASE:])
    y = (data.z[None] - P[:, None, :3] - model.offset) @ A.transpose(0, 2, 1)
    x, dP = y, 1.0
    coupled = model.harmonic is not None
    if model.nonlinear:
        x, dP, converged = model.solve(y, max(float(np.max(np.abs(y))), data.g), NEWTON_RTOL)
        valid = np.all(np.isfinite(dP), axis=(1, 2, 3)) if coupled else np.all(dP > 0, axis=(1, 2))
        ok = ok & converged & valid
    norm = np.linalg.norm(x, axis=2)
    r = norm - data.g
    ok = ok & np.all(np.isfinite(r), axis=1)
    r[~ok] = np.nan
    if not jacobian:
        return r, None, x
    xhat = x / norm[..., None]
    if coupled:  # v = x̂ᵀ (∂P/∂x)⁻¹ (NaN rows stay NaN)
        good = np.isfinite(dP).all(axis=(-2, -1))
        inv, _ = inverse3(np.where(good[..., None, None], dP, np.eye(3)))
        v = np.einsum("...k,...kj->...j", xhat, inv)
        v = np.where(good[..., None], v, np.nan)
    else:
        v = xhat / dP
    w = v @ A
    # ∂r/∂p_k = -w (∂M/∂p_k) y for the six (s, θ): all at once as one batched matmul
    dMy = (y @ dM.reshape(Bn, 18, 3).transpose(0, 2, 1)).reshape(Bn, n, 6, 3)
    cols = [-w, -np.sum(dMy * w[:, :, None, :], axis=3), *terms.jacobian_columns(v, w, x)]
    return r, np.concatenate(cols, axis=2), x


def evaluate(p, data: PoseData, effects, jacobian: bool = True):
    """Pose residuals ``||x_i|| - g`` (unit of g) and their Jacobian w.r.t. ``p``.

    Parameters
    ----------
    p : array_like, shape (:func:`n_parameters`,)
        ``(b, s, θ, φ_1, φ_2, ...)``, one block per effect in the order of ``effects``
        (:func:`effect_slices`).
    data : PoseData
    effects : sequence of str
        Effect ids.
    jacobian : bool

    Returns
    -------
    r : ndarray, shape (n,)
    J : ndarray, shape (n, q), or None
    x : ndarray, shape (n, 3)
        The true specific force each pose implies (unit of g).

    Returns ``(None, None, None)`` where the model cannot be inverted.
    """
    r, J, x = evaluate_batch(np.asarray(p, float)[None], data, effects, jacobian)
    if not np.all(np.isfinite(r)):
        return None, None, None
    return r[0], None if J is None else J[0], x[0]


def forward(x, M, bias, params: dict, dt=None, dtemp=None) -> np.ndarray:
    """The extended model forward: ``z = M P(x) + b + β Δt + γ ΔT`` (noise-free).

    Parameters
    ----------
    x : array_like, shape (n, 3)
        True specific force (unit of g), e.g. a whole time series.
    M, bias : array_like
        Base model (``M`` in data unit per unit of g).
    params : dict
        ``{effect_id: (size,) parameters}`` (:mod:`accelcal.effects`).
    dt, dtemp : array_like, shape (n,), optional
        Centred time and temperature of each row (needed by the effects that use them).
    """
    return extended_model.forward(x, M, bias, params, {TIME: dt, TEMPERATURE: dtemp})


def effect_columns(p, data: PoseData, base_effects, new_effect: str) -> np.ndarray:
    """Jacobian columns (n, size), unweighted, of ``new_effect`` at ``p`` with its parameters zero."""
    k = effect(new_effect).size
    _, J, _ = evaluate(np.concatenate([p, np.zeros(k)]), data, [*base_effects, new_effect])
    return J[:, -k:]


def orthonormal_basis(J: np.ndarray) -> tuple[np.ndarray, int]:
    """Orthonormal basis of the column space of ``J`` and its numerical rank."""
    U, s, _ = np.linalg.svd(J, full_matrices=False)
    if s.size == 0 or s[0] == 0:
        return U[:, :0], 0
    rank = int(np.sum(s > max(J.shape) * np.finfo(float).eps * s[0]))
    return U[:, :rank], rank


__all__ = ["N_BASE", "effect_columns", "effect_slices", "evaluate", "evaluate_batch", "forward", "n_parameters",
           "orthonormal_basis", "parameter_names"]
