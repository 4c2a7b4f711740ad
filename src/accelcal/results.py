"""Result objects: one dataclass per family of estimator, all with the same core fields.

Every result has ``bias`` (3,), ``M`` (3, 3) with ``z = M x + b`` (identity for the
bias-only models), ``scale_factors`` (3,), ``nonorthogonality`` (3,) [rad, order
θxy, θzx, θzy], per-pose ``residuals`` ``||M⁻¹(z_i - b)|| - g`` [input units] and
``standard_errors`` (dict of arrays, same units; NaN where not estimable).

Everything an estimate does not need (residuals, standard errors, the parameters
derived from ``M``, the singular values of the design) is computed on first access and
cached: a closed-form solve takes microseconds, and the timing of Burkhard et al.
(2024) compares estimators, not their error analysis.  The estimators build results
with :meth:`CalibrationResult._trusted`, which skips the frozen-dataclass ``__init__``
(a frozen ``__init__`` sets each field through ``object.__setattr__`` and costs more
than the closed form itself).
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from functools import cached_property

import numpy as np

from .jsonsafe import json_safe
from .model import params_from_m
from .registry import N_PARAMETERS, estimator, model_of
from .uncertainty import pose_residuals, standard_errors


@dataclass(frozen=True)
class CalibrationResult:
    """Fields shared by every estimator.

    ``poses`` are the static pose means the estimate was computed from; residuals and
    standard errors are derived from them on first access (so that timing an estimator
    times the estimator, not its error analysis).
    """

    method: str
    bias: np.ndarray
    M: np.ndarray
    g: float
    poses: np.ndarray

    @classmethod
    def _trusted(cls, **values):
        """Build a result from already validated values without running ``__init__``.

        Same object as ``cls(**values)``: every dataclass field must be given (the
        tests check each estimator's results field by field); extra keys may pre-fill a
        cached property such as ``singular_values``.
        """
        obj = object.__new__(cls)
        object.__setattr__(obj, "__dict__", values)  # the fresh dict of the keyword arguments
        return obj

    @property
    def model(self) -> str:
        """'bias' for the bias-only estimators (M = I), else 'full' (:mod:`accelcal.registry`)."""
        return model_of(self.method)

    @property
    def n_poses(self) -> int:
        return len(self.poses)

    @cached_property
    def _params(self) -> tuple[np.ndarray, np.ndarray]:
        return params_from_m(self.M)

    @property
    def scale_factors(self) -> np.ndarray:
        return self._params[0]

    @property
    def nonorthogonality(self) -> np.ndarray:
        """Non-orthogonality angles (θxy, θzx, θzy) in radians."""
        return self._params[1]

    @property
    def nonorthogonality_deg(self) -> np.ndarray:
        return np.rad2deg(self.nonorthogonality)

    @cached_property
    def residuals(self) -> np.ndarray:
        """Per-pose misfit ``||M⁻¹(z_i - b)|| - g`` in input units."""
        return pose_residuals(self.poses, self.g, self.M, self.bias)

    @property
    def residual_rms(self) -> float:
        return float(np.sqrt(np.mean(self.residuals**2)))

    @cached_property
    def standard_errors(self) -> dict[str, np.ndarray]:
        """Linearised standard errors (see :func:`accelcal.uncertainty.standard_errors`)."""
        return standard_errors(self.poses, self.g, self.M, self.bias, self.model)

    @property
    def n_parameters(self) -> int:
        return N_PARAMETERS[self.model]

    def apply(self, z) -> np.ndarray:
        """Calibrated specific force ``M⁻¹(z - b)`` of raw samples ``z`` (..., 3), unit of g.

        The plain model only; :class:`accelcal.calibration.Calibration` adds units,
        fitted effects and a file format.
        """
        z = np.asarray(z, dtype=float)
        return np.linalg.solve(self.M, (z - self.bias).reshape(-1, 3).T).T.reshape(z.shape)

    def to_dict(self) -> dict:
        """JSON-ready dictionary (the CLI's output format)."""
        out = {
            "method": self.method,
            "g": float(self.g),
            "n_poses": int(self.n_poses),
            "bias": self.bias.tolist(),
            "M": self.M.tolist(),
            "scale_factors": self.scale_factors.tolist(),
            "nonorthogonality_deg": self.nonorthogonality_deg.tolist(),
            "residual_rms": self.residual_rms,
            "residuals": self.residuals.tolist(),
            "standard_errors": {k: np.asarray(v).tolist() for k, v in self.standard_errors.items()},
        }
        for k in self._extra_fields():
            v = getattr(self, k)
            out[k] = v.tolist() if isinstance(v, np.ndarray) else v
        return json_safe(out)

    def _extra_fields(self) -> tuple[str, ...]:
        """Method-specific attributes written by :meth:`to_dict` after the common ones."""
        return tuple(f.name for f in fields(self) if f.name not in _CORE_FIELDS)


_CORE_FIELDS = frozenset(f.name for f in fields(CalibrationResult))


@dataclass(frozen=True)
class LLSResult(CalibrationResult):
    """Closed-form estimators (full LLS, bias-only LLS, ALS).

    ``lam`` the scale λ of eq. (5) (NaN for bias-only); ``c`` the fitted ``g² - bᵀb``
    of eq. (7) (NaN for full); ``noise_var`` the noise variance ALS corrected for
    (NaN for LLS); ``singular_values`` (computed on first access for the LLS) those of
    the scaled design matrix X of eq. (3) (full LLS), of the scaled bias-only system
    ``[2z, 1]`` of eq. (7) (bias-only LLS), or the square roots of the eigenvalues of
    the corrected moment matrix (ALS).
    """

    lam: float = float("nan")
    c: float = float("nan")
    noise_var: float = float("nan")

    @cached_property
    def singular_values(self) -> np.ndarray:
        # The registry names the function (imported on first use), so that this module
        # imports no estimator: lls and als build these results.
        est = estimator(self.method)
        f = est.load_conditioning()
        return f(self.poses, self.noise_var) if est.conditioning_uses_noise else f(self.model, self.poses)

    def _extra_fields(self) -> tuple[str, ...]:
        return ("singular_values",) + super()._extra_fields()


@dataclass(frozen=True)
class NLLSResult(CalibrationResult):
    """Iterative NLLS (CasADi + IPOPT): solver status, iterations, final cost."""

    status: str = ""
    iterations: int = 0
    cost: float = float("nan")


@dataclass(frozen=True)
class BatchResult:
    """Batched estimates over many trials (Monte Carlo).

    ``valid`` marks trials where the estimator produced a model (for the full LLS:
    Ŝ positive definite and λ > 0); invalid trials hold NaN, never a number.
    ``status`` per trial: ``'ok'`` or the name of the error the single-problem
    estimator raises on that trial (the iterative ones: IPOPT's return status).
    ``iterations``: the solver's iterations per trial (iterative estimators; else None).
    """

    method: str
    bias: np.ndarray  # (T, 3)
    M: np.ndarray  # (T, 3, 3)
    valid: np.ndarray  # (T,) bool
    status: np.ndarray | None = None  # (T,) str
    iterations: np.ndarray | None = None  # (T,) int
