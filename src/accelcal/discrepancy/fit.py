"""Weighted least-squares fits of the base model and its extensions, on static pose means.

Data.  A :class:`PoseData` holds the pose means ``z_i`` (data unit), the pose times and
temperatures (centred: ``Δt_i``, ``ΔT_i``) and the noise-predicted standard deviation
``σ_i`` of each pose residual, ``σ_i² = Σ_k (∂r_i/∂z_ik)² se_ik²`` from the per-pose
standard errors ``se_ik`` of the static detection (which account for correlated
samples; :func:`accelcal.evaluation.residual_sigma`).  ``σ_i`` is computed once,
at the closed-form (full LLS) fit, and then held fixed, so that every model of a
recording is fitted to, and compared on, the same weighted data.

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

from .. import extended_model, kernels
from ..effects import COVARIATES, TEMPERATURE, TIME, effect
from ..errors import AccelcalError, NotConvergedError
from ..extended_model import NEWTON_RTOL, EffectTerms, effect_terms
from ..model import m_from_params, params_from_m

#: Stop when the Gauss–Newton step predicts a χ² decrease below this (χ² is dimensionless).
CHI2_TOL = 1e-10
#: Iteration caps of the full fits and of the warm-started leave-one-pose-out refits.
MAX_ITER = 200
MAX_ITER_LOPO = 50
N_BASE = 9
#: The compiled kernels of :func:`evaluate_batch`, :func:`fit` and :func:`lopo` (:mod:`accelcal.kernels`).
_KERNELS = "discrepancy._fit_kernels"


@dataclass(frozen=True)
class PoseData:
    """What every model of one recording is fitted to (rows in time order).

    Attributes
    ----------
    z : ndarray, shape (n, 3)
        Pose means, data unit.
    g : float
        Gravity magnitude (the unit the residuals are in).
    sigma : ndarray, shape (n,)
        Noise-predicted standard deviation of each pose residual (unit of g), fixed.
    t : ndarray, shape (n,)
        Mid time of each pose [s].
    temp : ndarray, shape (n,), or None
        Mean temperature of each pose [°C], if the recording has one.
    mean_std : ndarray, shape (n, 3)
        Per-pose standard errors of the means (data unit), from the static detection.
    t_ref, temp_ref : float
        Centres of the covariates (the means over the full pose set; a subset keeps them).
    t_start, t_end : ndarray, shape (n,), or None
        First and last sample time of each pose [s] (the interval its mean averages over:
        the colored null needs them for the covariance of interval means).  None: unknown.
    index : ndarray of int, shape (n,), or None
        Index of each pose in the recording's full pose set (a subset keeps it); None = ``0..n-1``.
    """

    z: np.ndarray
    g: float
    sigma: np.ndarray
    t: np.ndarray
    temp: np.ndarray | None
    mean_std: np.ndarray
    t_ref: float
    temp_ref: float
    t_start: np.ndarray | None = None
    t_end: np.ndarray | None = None
    index: np.ndarray | None = None
    _terms: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    def __len__(self) -> int:
        return len(self.z)

    def effect_terms(self, effects) -> EffectTerms:
        """The effects on these poses (:func:`accelcal.extended_model.effect_terms`), kept:
        a recording's loop evaluates the same models hundreds of times.

        Raises
        ------
        AccelcalError
            An effect needs a covariate the recording lacks.
        """
        key = tuple(effects)
        terms = self._terms.get(key)
        if terms is None:
            terms = self._terms[key] = effect_terms(key, {name: self.covariate(name) for name in COVARIATES}, len(self))
        return terms

    def covariate(self, name: str | None) -> np.ndarray | None:
        """The centred covariate ``Δt`` or ``ΔT`` (None if the recording has no such column)."""
        if name == TIME:
            return self.t - self.t_ref
        if name == TEMPERATURE:
            return None if self.temp is None else self.temp - self.temp_ref
        return None

    @property
    def pose_index(self) -> np.ndarray:
        """Index of each pose in the full pose set."""
        return np.arange(len(self.z)) if self.index is None else self.index

    @property
    def has_intervals(self) -> bool:
        return self.t_start is not None and self.t_end is not None

    def subset(self, keep) -> PoseData:
        """The poses ``keep`` (boolean mask or indices), covariates centred as in the full set."""
        def sel(a):
            return None if a is None else a[keep]

        return PoseData(self.z[keep], self.g, self.sigma[keep], self.t[keep], sel(self.temp), self.mean_std[keep],
                        self.t_ref, self.temp_ref, sel(self.t_start), sel(self.t_end), self.pose_index[keep])


def pose_data(z, g: float, mean_std, t, temp=None, sigma=None, t_start=None, t_end=None) -> PoseData:
    """Build :class:`PoseData`; ``sigma`` defaults to the noise prediction at the full LLS fit.

    ``t_start``, ``t_end`` (optional, both or neither): the interval each pose mean
    averages over [s], ``t_start <= t <= t_end``, intervals in time order and disjoint.

    Raises
    ------
    AccelcalError
        Shapes that do not match, or the full LLS failing on the poses (too few or
        degenerate poses: the same one-line errors as ``accelcal calibrate``).
    """
    from .. import full_lls
    from ..evaluation import residual_sigma

    z = np.asarray(z, float)
    mean_std = np.asarray(mean_std, float)
    t = np.asarray(t, float)
    if z.ndim != 2 or z.shape[1] != 3 or mean_std.shape != z.shape or t.shape != (len(z),):
        raise AccelcalError(f"pose data of inconsistent shapes: z {z.shape}, mean_std {mean_std.shape}, t {t.shape}")
    if temp is not None:
        temp = np.asarray(temp, float)
        if temp.shape != t.shape:
            raise AccelcalError(f"pose temperatures of shape {temp.shape}, expected {t.shape}")
    if sigma is None:
        base = full_lls(z, g)
        sigma = residual_sigma(z, mean_std, base.M, base.bias)
    sigma = np.asarray(sigma, float)
    if not np.all(np.isfinite(sigma)) or np.any(sigma <= 0):
        raise AccelcalError("a pose has zero or non-finite noise: its standard error cannot weight it")
    if (t_start is None) != (t_end is None):
        raise AccelcalError("give both t_start and t_end of the poses, or neither")
    if t_start is not None:
        t_start, t_end = np.asarray(t_start, float), np.asarray(t_end, float)
        if t_start.shape != t.shape or t_end.shape != t.shape:
            raise AccelcalError(f"pose intervals of shapes {t_start.shape}, {t_end.shape}, expected {t.shape}")
        if not (np.all(np.isfinite(t_start)) and np.all(np.isfinite(t_end))) or np.any(t_end < t_start) \
                or np.any(t_start[1:] < t_end[:-1]):
            raise AccelcalError("pose intervals must be finite, in time order and disjoint (t_start <= t_end)")
    return PoseData(z, float(g), sigma, t, temp, mean_std, float(t.mean()),
                    float(temp.mean()) if temp is not None else float("nan"), t_start, t_end, None)


def pose_data_from_static(poses, g: float) -> PoseData:
    """:class:`PoseData` of the poses found by :func:`accelcal.static.detect_static`."""
    return pose_data(poses.means, g, poses.mean_std, poses.t_mid, poses.temp, t_start=poses.t_start,
                     t_end=poses.t_end)


# --------------------------------------------------------------------------- the model


def n_parameters(effects) -> int:
    return N_BASE + 3 * len(effects)


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
    model = terms.at(P[:, N_BASE:].reshape(Bn, -1, 3))
    y = (data.z[None] - P[:, None, :3] - model.offset) @ A.transpose(0, 2, 1)
    x, dP = y, 1.0
    if model.polynomial:
        x, dP, converged = model.solve(y, max(float(np.max(np.abs(y))), data.g), NEWTON_RTOL)
        ok = ok & converged & np.all(dP > 0, axis=(1, 2))
    norm = np.linalg.norm(x, axis=2)
    r = norm - data.g
    ok = ok & np.all(np.isfinite(r), axis=1)
    r[~ok] = np.nan
    if not jacobian:
        return r, None, x
    v = (x / norm[..., None]) / dP
    w = v @ A
    # ∂r/∂p_k = -w (∂M/∂p_k) y for the six (s, θ): all at once as one batched matmul
    dMy = (y @ dM.reshape(Bn, 18, 3).transpose(0, 2, 1)).reshape(Bn, n, 6, 3)
    cols = [-w, -np.sum(dMy * w[:, :, None, :], axis=3), *terms.jacobian_columns(v, w, x)]
    return r, np.concatenate(cols, axis=2), x


def evaluate(p, data: PoseData, effects, jacobian: bool = True):
    """Pose residuals ``||x_i|| - g`` (unit of g) and their Jacobian w.r.t. ``p``.

    Parameters
    ----------
    p : array_like, shape (9 + 3 len(effects),)
        ``(b, s, θ, φ_1, φ_2, ...)``, one block per effect in the order of ``effects``.
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
        ``{effect_id: (3,) parameters}`` (:mod:`accelcal.effects`).
    dt, dtemp : array_like, shape (n,), optional
        Centred time and temperature of each row (needed by the effects that use them).
    """
    return extended_model.forward(x, M, bias, params, {TIME: dt, TEMPERATURE: dtemp})


def fit_at(data: PoseData, effects, p) -> Fit:
    """A :class:`Fit` evaluated at given parameters (no optimisation): the design of a
    simulation at its true parameters, for identifiability and MDE."""
    r, J, x = evaluate(p, data, effects)
    if r is None:
        raise AccelcalError("the model cannot be evaluated at these parameters")
    return Fit(tuple(effects), np.asarray(p, float), r, data.sigma, J / data.sigma[:, None], 0, x)


def effect_columns(p, data: PoseData, base_effects, new_effect: str) -> np.ndarray:
    """Jacobian columns (n, 3), unweighted, of ``new_effect`` at ``p`` with its parameters zero."""
    _, J, _ = evaluate(np.concatenate([p, np.zeros(3)]), data, [*base_effects, new_effect])
    return J[:, -3:]


def orthonormal_basis(J: np.ndarray) -> tuple[np.ndarray, int]:
    """Orthonormal basis of the column space of ``J`` and its numerical rank."""
    U, s, _ = np.linalg.svd(J, full_matrices=False)
    if s.size == 0 or s[0] == 0:
        return U[:, :0], 0
    rank = int(np.sum(s > max(J.shape) * np.finfo(float).eps * s[0]))
    return U[:, :rank], rank


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
        i = self.effects.index(effect_id)
        return self.p[N_BASE + 3 * i: N_BASE + 3 * i + 3]

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
        from .. import full_lls

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


__all__ = ["CHI2_TOL", "Fit", "PoseData", "effect_columns", "evaluate", "evaluate_batch", "fit", "fit_at", "forward", "lopo", "n_parameters", "orthonormal_basis",
           "parameter_names", "pose_data", "pose_data_from_static"]
