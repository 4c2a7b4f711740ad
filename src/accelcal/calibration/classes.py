"""One calibration class per estimator (``CAL_TYPE``), found by its type tag among the
subclasses of :class:`~.base.Calibration`, as imucal's ``CalibrationInfo``."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from .base import Calibration


@dataclass(frozen=True, eq=False)
class FullLLSCalibration(Calibration):
    """Burkhard et al.'s closed-form full model (``full_lls``): λ of eq. 5, the singular values of the design."""

    CAL_TYPE: ClassVar[str] = "full_lls"
    lam: float = float("nan")
    singular_values: np.ndarray | None = None


@dataclass(frozen=True, eq=False)
class FullALSCalibration(Calibration):
    """Adjusted least squares (``full_als``): the noise variance it corrected for, and where it came from."""

    CAL_TYPE: ClassVar[str] = "full_als"
    lam: float = float("nan")
    noise_var: float = float("nan")
    noise_source: str = ""
    singular_values: np.ndarray | None = None


@dataclass(frozen=True, eq=False)
class FullNLLSCalibration(Calibration):
    """Iterative full model (``full_nlls``, CasADi/IPOPT): solver status, iterations, cost."""

    CAL_TYPE: ClassVar[str] = "full_nlls"
    status: str = ""
    iterations: int = 0
    cost: float = float("nan")


@dataclass(frozen=True, eq=False)
class BiasLLSCalibration(Calibration):
    """Bias-only closed form (``bias_lls``, ``M = I``): the fitted ``g² - bᵀb`` (``c``) and the singular values."""

    CAL_TYPE: ClassVar[str] = "bias_lls"
    c: float = float("nan")
    singular_values: np.ndarray | None = None


@dataclass(frozen=True, eq=False)
class BiasNLLSCalibration(Calibration):
    """Bias-only iterative (``bias_nlls``): solver status, iterations, cost."""

    CAL_TYPE: ClassVar[str] = "bias_nlls"
    status: str = ""
    iterations: int = 0
    cost: float = float("nan")


@dataclass(frozen=True, eq=False)
class ExtendedCalibration(Calibration):
    """The base model plus the effects the discrepancy loop named (``accelcal discrepancy``)."""

    CAL_TYPE: ClassVar[str] = "extended"
    base_effects_named: tuple[str, ...] = ()
