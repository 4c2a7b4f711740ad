"""The extended model of :mod:`accelcal.effects`, implemented once for every effect of the table.

::

    z = M P(x) + b + Σ_additive c φ,      P_j(x) = x_j + Σ_polynomial c φ_j x_j^p

Each effect contributes ``c φ`` (additive: added to ``z``, outside ``M``) or ``c φ_j x_j^p``
(polynomial: added to ``P_j``, inside ``M``), with ``c`` its centred covariate per row
or 1.  :func:`effect_terms` turns effect ids and covariates into :class:`EffectTerms` (one
row per effect: kind, power, covariate column); :meth:`EffectTerms.at` adds the
parameters and gives the model's terms at them (:class:`ModelTerms`: the additive
offset and the polynomial coefficients).  :func:`model_terms` does both at once.
Everything that evaluates the model consumes them:

* the forward model :func:`forward` (simulations, :func:`accelcal.discrepancy.residuals.forward`);
* its inverse, ``P(x) = y`` per axis by Newton (:meth:`ModelTerms.solve`): the pose
  residuals of the fits (:func:`accelcal.discrepancy.residuals.evaluate_batch`) and
  :meth:`accelcal.calibration.Calibration.apply`;
* the Jacobian of the residual ``||x|| - g`` with respect to the effect parameters
  (:meth:`EffectTerms.jacobian_columns`);
* the compiled kernels of the fits (:mod:`accelcal.discrepancy._fit_kernels`), which take
  the same rows as arrays (:attr:`EffectTerms.kernel_arrays`: covariate columns, powers,
  additive or not) and evaluate the same sums in the same order.

Arithmetic.  The order of the sums and products below (``P'(x)`` as ``(p C) x … x``,
``C₂ x²`` as ``(C₂ x) x``, higher powers by ``x ** p``; the coefficients summed per power
in the order of the effects) is the one every result of the project was computed with:
changing it moves the last digits of every fit.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from .effects import ADDITIVE, POLYNOMIAL, Effect, effect
from .errors import AccelcalError

#: Relative tolerance (to ``max(|y|, g)``) and iteration cap of the Newton solve of ``P(x) = y``.
NEWTON_RTOL = 1e-14
NEWTON_MAX_ITER = 60


def _power(x, p: int):
    return x if p == 1 else x ** p


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
    """

    offset: np.ndarray
    polynomial: tuple[tuple[int, np.ndarray], ...]

    def polynomial_of(self, x: np.ndarray) -> np.ndarray:
        """``P(x) = x + Σ c φ x^p`` (the forward model's order: effect by effect)."""
        P = x
        for p, coef in self.polynomial:
            P = P + coef * _power(x, p)
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

        Returns
        -------
        x : ndarray, shape of ``y``
        slope : ndarray, shape of ``y``
            ``P'(x)`` at the solution (NaN where ``x`` is).
        converged : ndarray of bool, shape ``y.shape[:-2]``
            Every step of that member of the stack fell below the tolerance.
        """
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
    def has_polynomial(self) -> bool:
        """Whether ``P(x) = y`` needs solving (else ``x = y``)."""
        return any(e.kind == POLYNOMIAL for e in self.effects)

    def at(self, blocks) -> ModelTerms:
        """The model's terms at the effect parameters ``blocks`` (..., k, 3), one block per effect."""
        blocks = np.asarray(blocks, float)
        offset = np.zeros((*blocks.shape[:-2], self.n, 3))
        polynomial = []
        for i, (e, col) in enumerate(zip(self.effects, self.columns)):
            phi = blocks[..., i:i + 1, :]
            coef = phi if col is None else col[:, None] * phi
            if e.kind == ADDITIVE:
                offset = offset + coef
            else:
                polynomial.append((e.power, coef))
        return ModelTerms(offset, tuple(polynomial))

    def jacobian_columns(self, v: np.ndarray, w: np.ndarray, x: np.ndarray) -> list[np.ndarray]:
        """``∂r/∂φ`` (..., n, 3) of every effect, ``r = ||x|| - g``, by implicit differentiation.

        With ``v_j = x̂_j / P_j'(x)`` and ``w = v M⁻¹``: ``-w c`` for an additive effect
        (it moves ``z``), ``-v c x^p`` for a polynomial one (it moves ``P(x)``).
        """
        cols = []
        for e, col in zip(self.effects, self.columns):
            d = -w if e.kind == ADDITIVE else -v * _power(x, e.power)
            cols.append(d if col is None else d * col[:, None])
        return cols

    @cached_property
    def kernel_arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The effects as the compiled kernels take them: covariate columns (k, n) (ones
        where ``c = 1``), powers (k,) int64 (0 for additive effects), additive (k,) bool."""
        cols = np.ones((len(self.effects), self.n))
        for i, col in enumerate(self.columns):
            if col is not None:
                cols[i] = col
        power = np.array([e.power for e in self.effects], np.int64)
        additive = np.array([e.kind == ADDITIVE for e in self.effects], np.bool_)
        return cols, power, additive


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


def model_terms(effects: Sequence, blocks, covariates: Mapping[str, np.ndarray | None], n: int,
                references: Sequence[float | None] | None = None) -> ModelTerms:
    """The model's terms of ``effects`` at the parameters ``blocks`` (..., k, 3) on ``n`` rows
    (:func:`effect_terms`, then :meth:`EffectTerms.at`)."""
    return effect_terms(effects, covariates, n, references).at(blocks)


def forward(x, M, bias, params: Mapping, covariates: Mapping[str, np.ndarray | None]) -> np.ndarray:
    """``z = M P(x) + b + Σ_additive c φ`` (noise-free) of the rows ``x`` (n, 3).

    ``params``: ``{effect_id: (3,) parameters}``; ``covariates``: the centred
    ``{'time': (n,), 'temperature': (n,)}`` the effects need.
    """
    x = np.asarray(x, float)
    terms = model_terms(list(params), [np.asarray(v, float) for v in params.values()] or np.zeros((0, 3)),
                        covariates, len(x))
    return terms.polynomial_of(x) @ np.asarray(M, float).T + np.asarray(bias, float) + terms.offset


__all__ = ["NEWTON_MAX_ITER", "NEWTON_RTOL", "EffectTerms", "ModelTerms", "effect_terms", "forward", "model_terms"]
