"""The extended model of :mod:`accelcal.effects`, implemented once for every effect of the table.

::

    z = M P(x) + b + Σ_additive c φ,      P_j(x) = x_j + Σ_polynomial c φ_j x_j^p + K_j(x, x)

Each effect contributes ``c φ`` (additive: added to ``z``, outside ``M``), ``c φ_j x_j^p``
(polynomial: added to ``P_j``, inside ``M``), with ``c`` its centred covariate per row
or 1, or ``K(x, x) = Σ_m φ_m T_m(x, x)`` (harmonic, power 2: ``T_m`` the symmetric
tensor of the harmonic cubic ``H_m(x) = T_m(x, x, x)``, :func:`harmonic_basis`, so that
``K(x, x) = Σ_m φ_m ∇H_m(x)/3``).  :func:`effect_terms` turns effect ids and covariates into :class:`EffectTerms` (one
row per effect: kind, power, covariate column); :meth:`EffectTerms.at` adds the
parameters and gives the model's terms at them (:class:`ModelTerms`: the additive
offset and the polynomial coefficients).  :func:`model_terms` does both at once.
Everything that evaluates the model consumes them:

* the forward model :func:`forward` (simulations, :func:`accelcal.discrepancy.residuals.forward`);
* its inverse, ``P(x) = y`` per axis by Newton (with a harmonic effect, Newton on the
  three axes together) (:meth:`ModelTerms.solve`): the pose
  residuals of the fits (:func:`accelcal.discrepancy.residuals.evaluate_batch`) and
  :meth:`accelcal.calibration.Calibration.apply`;
* the Jacobian of the residual ``||x|| - g`` with respect to the effect parameters
  (:meth:`EffectTerms.jacobian_columns`);
* the compiled kernels of the fits (:mod:`accelcal.discrepancy._fit_kernels`), which take
  the same rows as arrays (:attr:`EffectTerms.kernel_arrays`: covariate columns, powers,
  additive or not, harmonic or not with its tensors) and evaluate the same sums in the
  same order.

The parameters of the effects are one flat vector, each effect's block of
:attr:`accelcal.effects.Effect.size` after the other, in the order of the effects.

Arithmetic.  The order of the sums and products below (``P'(x)`` as ``(p C) x … x``,
``C₂ x²`` as ``(C₂ x) x``, higher powers by ``x ** p``; the coefficients summed per power
in the order of the effects) is the one every result of the project was computed with:
changing it moves the last digits of every fit.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property, lru_cache
from math import factorial

import numpy as np

from .effects import ADDITIVE, HARMONIC, Effect, effect
from .errors import AccelcalError

#: Relative tolerance (to ``max(|y|, g)``) and iteration cap of the Newton solve of ``P(x) = y``.
NEWTON_RTOL = 1e-14
NEWTON_MAX_ITER = 60


def _power(x, p: int):
    return x if p == 1 else x ** p


#: The real harmonic cubics ``H_m`` (m = -3..3) as ``{(a, b, c): coefficient}`` of ``x^a y^b z^c``.
_CUBIC_HARMONICS = (
    {(2, 1, 0): 3.0, (0, 3, 0): -1.0},                      # 3x²y − y³
    {(1, 1, 1): 1.0},                                        # xyz
    {(0, 1, 2): 4.0, (2, 1, 0): -1.0, (0, 3, 0): -1.0},     # y(4z² − x² − y²)
    {(0, 0, 3): 2.0, (2, 0, 1): -3.0, (0, 2, 1): -3.0},     # z(2z² − 3x² − 3y²)
    {(1, 0, 2): 4.0, (3, 0, 0): -1.0, (1, 2, 0): -1.0},     # x(4z² − x² − y²)
    {(2, 0, 1): 1.0, (0, 2, 1): -1.0},                      # z(x² − y²)
    {(3, 0, 0): 1.0, (1, 2, 0): -3.0},                      # x³ − 3xy²
)


def _sphere_moment(e) -> float:
    """``E[x^a y^b z^c]`` over the uniform unit sphere: ``Π (a_k − 1)!! / (3 · 5 ⋯ (2n + 1))``
    for even exponents summing to ``2n`` (zero if one is odd)."""
    if any(v % 2 for v in e):
        return 0.0
    num = np.prod([np.prod(np.arange(v - 1, 0, -2), initial=1.0) for v in e])
    return float(num / np.prod(np.arange(3, sum(e) + 2, 2), initial=1.0))


@lru_cache(maxsize=None)
def harmonic_basis(power: int) -> np.ndarray:
    """The symmetric tensors ``T_m`` (2l + 1, 3, 3, 3) of a harmonic effect of ``power``
    (:mod:`accelcal.effects`): ``H_m(x) = Σ_jkl T_m,jkl x_j x_k x_l`` are the real harmonic
    homogeneous polynomials of degree ``l = power + 1`` (m = −l..l), normalised to a unit
    mean square over the unit sphere (``E_u[H_m(u)²] = 1``).  Read-only."""
    if power != 2:
        raise AccelcalError(f"no harmonic basis for power {power} (implemented: 2)")
    out = np.zeros((len(_CUBIC_HARMONICS), 3, 3, 3))
    for m, poly in enumerate(_CUBIC_HARMONICS):
        norm2 = sum(ca * cb * _sphere_moment(np.add(a, b)) for a, ca in poly.items() for b, cb in poly.items())
        for j, k, l in np.ndindex(3, 3, 3):
            e = tuple(int(v) for v in np.bincount([j, k, l], minlength=3))
            # the monomial's coefficient is shared by its 3!/(a! b! c!) index orders
            orders = 6 // (factorial(e[0]) * factorial(e[1]) * factorial(e[2]))
            out[m, j, k, l] = poly.get(e, 0.0) / orders / np.sqrt(norm2)
    out.setflags(write=False)
    return out


@dataclass(frozen=True)
class ModelTerms:
    """The extended model's terms at given parameters (a stack of them: leading axes ``...``).

    Attributes
    ----------
    offset : ndarray, shape (..., n, 3)
        ``Σ_additive c φ``: ``z = M P(x) + b + offset``.
    polynomial : tuple of (int, ndarray)
        ``(p, c φ)`` of every polynomial effect, in the order of the effects; ``c φ`` of
        shape (..., n, 3), or (..., 1, 3) without a covariate.
    harmonic : ndarray, shape (..., 3, 3, 3), or None
        ``K``, the second-order tensor of the harmonic effects: ``P(x) += K(x, x)``.
    """

    offset: np.ndarray
    polynomial: tuple[tuple[int, np.ndarray], ...]
    harmonic: np.ndarray | None = None

    @property
    def nonlinear(self) -> bool:
        """Whether ``P(x) = y`` needs solving (else ``x = y``)."""
        return bool(self.polynomial) or self.harmonic is not None

    def polynomial_of(self, x: np.ndarray) -> np.ndarray:
        """``P(x) = x + Σ c φ x^p + K(x, x)`` (the forward model's order: effect by effect)."""
        P = x
        for p, coef in self.polynomial:
            P = P + coef * _power(x, p)
        if self.harmonic is not None:
            P = P + quadratic_form(self.harmonic, x)
        return P

    def coefficients(self) -> dict[int, np.ndarray | float]:
        """``{p: C_p}``, powers ascending, with ``P_j(x) = Σ_p C_p x_j^p`` (``C_1`` includes the 1)."""
        C: dict[int, np.ndarray | float] = {1: 1.0}
        for p in sorted({p for p, _ in self.polynomial}):
            C.setdefault(p, 0.0)
        for p, coef in self.polynomial:
            C[p] = C[p] + coef
        return C

    def solve(self, y: np.ndarray, scale: float, rtol: float = NEWTON_RTOL, max_iter: int = NEWTON_MAX_ITER):
        """``x`` with ``P(x) = y``, axis by axis: Newton from ``x = y``.

        One stopping test for the whole stack: every step below ``rtol * scale``.  Where
        ``P'(x) <= 0`` (the polynomial not monotonic there) the step, and then ``x``, is NaN.

        With a harmonic effect ``P`` couples the axes: Newton on the three at once, and
        ``slope`` is the Jacobian ``∂P/∂x`` (..., n, 3, 3) (NaN where ``det ∂P/∂x <= 0``).

        Returns
        -------
        x : ndarray, shape of ``y``
        slope : ndarray, shape of ``y``, or (..., n, 3, 3) with a harmonic effect
            ``P'(x)`` at the solution (NaN where ``x`` is, or where ``P`` is not invertible).
        converged : ndarray of bool, shape ``y.shape[:-2]``
            Every step of that member of the stack fell below the tolerance.
        """
        if self.harmonic is not None:
            return self._solve_coupled(y, scale, rtol, max_iter)
        C = self.coefficients()
        tol = rtol * scale
        x = y
        for _ in range(max_iter):
            slope = _slope(C, x)
            step = (_value(C, x) - y) / np.where(slope > 0, slope, np.nan)
            x = x - step
            if not np.max(np.abs(step), where=~np.isnan(step), initial=-np.inf) > tol:
                converged = np.ones(y.shape[:-2], bool)
                break
        else:
            converged = np.all(np.abs(step) <= tol, axis=(-2, -1))
        return x, _slope(C, x), converged

    def _solve_coupled(self, y, scale, rtol, max_iter):
        """:meth:`solve` with a harmonic effect: Newton on the three axes at once."""
        C = self.coefficients()
        tol = rtol * scale
        x = y
        for _ in range(max_iter):
            Kx = _contract(self.harmonic, x)                       # K(·, ·, x): (..., n, 3, 3)
            inv, det = inverse3(_diag_slope(C, x) + 2.0 * Kx)
            res = _value(C, x) + np.einsum("...njk,...nk->...nj", Kx, x) - y
            step = np.where((det > 0)[..., None], np.einsum("...jk,...k->...j", inv, res), np.nan)
            x = x - step
            if not np.max(np.abs(step), where=~np.isnan(step), initial=-np.inf) > tol:
                converged = np.ones(y.shape[:-2], bool)
                break
        else:
            converged = np.all(np.abs(step) <= tol, axis=(-2, -1))
        jac = self.jacobian_of(x, C)
        return x, np.where((inverse3(jac)[1] > 0)[..., None, None], jac, np.nan), converged

    def jacobian_of(self, x: np.ndarray, C: dict | None = None) -> np.ndarray:
        """``∂P/∂x`` (..., n, 3, 3): the per-axis slopes on the diagonal plus ``2 K(x, ·)``."""
        jac = _diag_slope(self.coefficients() if C is None else C, x)
        return jac if self.harmonic is None else jac + 2.0 * _contract(self.harmonic, x)

    def invertible(self, slope: np.ndarray) -> bool:
        """Whether :meth:`solve`'s ``slope`` says ``P`` was invertible at every row: the
        per-axis slopes positive, or (harmonic effect) every Jacobian's determinant (NaN where
        it was not positive)."""
        return bool(np.all(np.isfinite(slope)) and (self.harmonic is not None or np.all(slope > 0)))


def inverse3(J: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Inverses and determinants of a stack of 3 × 3 matrices (..., 3, 3) by their cofactors
    (many small systems: numpy's batched LAPACK calls cost more than the arithmetic)."""
    a, b, c = J[..., 0, 0], J[..., 0, 1], J[..., 0, 2]
    d, e, f = J[..., 1, 0], J[..., 1, 1], J[..., 1, 2]
    g, h, i = J[..., 2, 0], J[..., 2, 1], J[..., 2, 2]
    A, B, C = e * i - f * h, f * g - d * i, d * h - e * g
    det = a * A + b * B + c * C
    adj = np.stack([np.stack([A, c * h - b * i, b * f - c * e], -1),
                    np.stack([B, a * i - c * g, c * d - a * f], -1),
                    np.stack([C, b * g - a * h, a * e - b * d], -1)], -2)
    with np.errstate(divide="ignore", invalid="ignore"):
        return adj / det[..., None, None], det


def _contract(K: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``Σ_l K_jkl x_l`` (..., n, 3, 3) for rows ``x`` (..., n, 3) and tensors ``K`` (..., 3, 3, 3)."""
    K9 = K.reshape(*K.shape[:-3], 9, 3)
    return (x @ np.swapaxes(K9, -1, -2)).reshape(*x.shape[:-1], 3, 3)


def _diag_slope(C: dict, x: np.ndarray) -> np.ndarray:
    """The per-axis slopes ``P_j'(x)`` as diagonal matrices (..., n, 3, 3)."""
    return np.broadcast_to(_slope(C, x), x.shape)[..., :, None] * np.eye(3)


def quadratic_form(K: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``K(x, x)_j = Σ_kl K_jkl x_k x_l`` for rows ``x`` (..., n, 3) and tensors ``K`` (..., 3, 3, 3)."""
    return np.einsum("...njk,...nk->...nj", _contract(K, x), x)


def _value(C: dict, x: np.ndarray) -> np.ndarray:
    """``P(x) = Σ_p C_p x^p``, powers ascending."""
    value = C[1] * x
    for p, c in C.items():
        if p > 1:
            value = value + (c * x * x if p == 2 else c * x ** p)
    return value


def _slope(C: dict, x: np.ndarray) -> np.ndarray:
    """``P'(x) = Σ_p p C_p x^(p-1)``, powers ascending."""
    slope = C[1]
    for p, c in C.items():
        if p > 1:
            term = p * c
            for _ in range(p - 1):
                term = term * x
            slope = slope + term
    return slope


@dataclass(frozen=True)
class EffectTerms:
    """The effects of a model on ``n`` rows, before the parameters.

    Attributes
    ----------
    effects : tuple of Effect
    columns : tuple of (ndarray, shape (n,), or None)
        Each effect's centred covariate ``c`` per row; None: ``c = 1``.
    n : int
    """

    effects: tuple[Effect, ...]
    columns: tuple[np.ndarray | None, ...]
    n: int

    @property
    def n_parameters(self) -> int:
        """Length of the flat parameter vector of the effects."""
        return sum(e.size for e in self.effects)

    def at(self, params) -> ModelTerms:
        """The model's terms at the effect parameters ``params`` (..., P): the effects' blocks
        one after the other (module docstring)."""
        params = np.asarray(params, float)
        if params.shape[-1] != self.n_parameters:
            raise AccelcalError(f"{params.shape[-1]} effect parameters for effects of {self.n_parameters}")
        offset = np.zeros((*params.shape[:-1], self.n, 3))
        polynomial, harmonic, start = [], None, 0
        for e, col in zip(self.effects, self.columns):
            phi = params[..., None, start:start + e.size]
            start += e.size
            if e.kind == HARMONIC:
                K = np.einsum("...m,mjkl->...jkl", phi[..., 0, :], harmonic_basis(e.power))
                harmonic = K if harmonic is None else harmonic + K
                continue
            coef = phi if col is None else col[:, None] * phi
            if e.kind == ADDITIVE:
                offset = offset + coef
            else:
                polynomial.append((e.power, coef))
        return ModelTerms(offset, tuple(polynomial), harmonic)

    def jacobian_columns(self, v: np.ndarray, w: np.ndarray, x: np.ndarray) -> list[np.ndarray]:
        """``∂r/∂φ`` (..., n, size) of every effect, ``r = ||x|| - g``, by implicit differentiation.

        With ``v = x̂ᵀ (∂P/∂x)⁻¹`` (per axis ``v_j = x̂_j / P_j'(x)``) and ``w = v M⁻¹``:
        ``-w c`` for an additive effect (it moves ``z``), ``-v c x^p`` for a polynomial one
        (it moves ``P(x)``), ``-v · T_m(x, x)`` for a harmonic one.
        """
        cols = []
        for e, col in zip(self.effects, self.columns):
            if e.kind == HARMONIC:  # -v · T_m(x, x): through the outer products x_k x_l
                T = harmonic_basis(e.power)
                xx = (x[..., :, None] * x[..., None, :]).reshape(*x.shape[:-1], 9)
                Txx = (xx @ T.reshape(-1, 9).T).reshape(*x.shape[:-1], T.shape[0], 3)   # (..., n, m, j)
                cols.append(-np.sum(Txx * v[..., None, :], axis=-1))
                continue
            d = -w if e.kind == ADDITIVE else -v * _power(x, e.power)
            cols.append(d if col is None else d * col[:, None])
        return cols

    @cached_property
    def kernel_arrays(self) -> tuple[np.ndarray, ...]:
        """The effects as the compiled kernels take them: covariate columns (k, n) (ones
        where ``c = 1``), powers (k,) int64 (0 for additive effects), additive (k,) bool,
        harmonic (k,) bool and the harmonic effects' tensors (k, m, 3, 3, 3) (zeros for the
        others; ``m`` their parameters, 1 without one)."""
        cols = np.ones((len(self.effects), self.n))
        for i, col in enumerate(self.columns):
            if col is not None:
                cols[i] = col
        power = np.array([e.power for e in self.effects], np.int64)
        additive = np.array([e.kind == ADDITIVE for e in self.effects], np.bool_)
        harmonic = np.array([e.kind == HARMONIC for e in self.effects], np.bool_)
        m = max([e.size for e in self.effects if e.kind == HARMONIC], default=1)
        basis = np.zeros((len(self.effects), m, 3, 3, 3))
        for i, e in enumerate(self.effects):
            if e.kind == HARMONIC:
                basis[i] = harmonic_basis(e.power)
        return cols, power, additive, harmonic, basis


def effect_terms(effects: Sequence, covariates: Mapping[str, np.ndarray | None], n: int,
                 references: Sequence[float | None] | None = None) -> EffectTerms:
    """:class:`EffectTerms` of ``effects`` (ids or :class:`~accelcal.effects.Effect`) on ``n`` rows.

    Parameters
    ----------
    effects : sequence of str or Effect
    covariates : mapping
        ``{'time': (n,), 'temperature': (n,)}``, None (or absent) where the data have none.
    n : int
    references : sequence of float or None, optional
        Per effect, the centre subtracted from its covariate (a calibration's session
        means); None: the covariates are centred already.

    Raises
    ------
    AccelcalError
        An effect needs a covariate the data lack, an unknown id, or a covariate of
        another length than ``n``.
    """
    es = tuple(e if isinstance(e, Effect) else effect(e) for e in effects)
    columns = []
    for i, e in enumerate(es):
        if e.covariate is None:
            columns.append(None)
            continue
        col = covariates.get(e.covariate)
        if col is None:
            raise AccelcalError(f"effect {e.id} needs the {e.covariate} of every row")
        col = np.asarray(col, float)
        if col.shape != (n,):
            raise AccelcalError(f"effect {e.id}: {e.covariate} of shape {col.shape}, expected ({n},)")
        if references is not None:
            if references[i] is None:
                raise AccelcalError(f"effect {e.id} has no reference {e.covariate} to centre it on")
            col = col - references[i]
        columns.append(col)
    return EffectTerms(es, tuple(columns), int(n))


def model_terms(effects: Sequence, params, covariates: Mapping[str, np.ndarray | None], n: int,
                references: Sequence[float | None] | None = None) -> ModelTerms:
    """The model's terms of ``effects`` at their flat parameters ``params`` (..., P) on ``n``
    rows (:func:`effect_terms`, then :meth:`EffectTerms.at`)."""
    return effect_terms(effects, covariates, n, references).at(params)


def forward(x, M, bias, params: Mapping, covariates: Mapping[str, np.ndarray | None]) -> np.ndarray:
    """``z = M P(x) + b + Σ_additive c φ`` (noise-free) of the rows ``x`` (n, 3).

    ``params``: ``{effect_id: (size,) parameters}``; ``covariates``: the centred
    ``{'time': (n,), 'temperature': (n,)}`` the effects need.
    """
    x = np.asarray(x, float)
    flat = np.concatenate([np.ravel(np.asarray(v, float)) for v in params.values()]) if params else np.zeros(0)
    terms = model_terms(list(params), flat, covariates, len(x))
    return terms.polynomial_of(x) @ np.asarray(M, float).T + np.asarray(bias, float) + terms.offset


__all__ = ["NEWTON_MAX_ITER", "NEWTON_RTOL", "EffectTerms", "ModelTerms", "effect_terms", "forward", "harmonic_basis", "inverse3",
           "model_terms", "quadratic_form"]
