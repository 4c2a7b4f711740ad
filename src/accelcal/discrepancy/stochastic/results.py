"""The stochastic layer's results (per axis and per recording) and its error."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ...errors import AccelcalError
from ...jsonsafe import json_safe
from ...noise.terms import TERMS


class StochasticError(AccelcalError):
    """Rest data or settings the stochastic layer cannot use."""


@dataclass(frozen=True)
class AxisStochastic:
    """Stochastic layer result of one axis (arrays over the τ grid)."""

    axis: str
    taus: np.ndarray
    n_terms: np.ndarray
    edf: np.ndarray
    adev_measured: np.ndarray
    adev_ci: np.ndarray                 # (k, 2): 68.3 % chi-square interval, edf of the final model
    adev_longest_rest: np.ndarray       # the longest rest alone (NaN beyond its reach)
    adev_model_before: np.ndarray       # white-only fit, theory
    adev_model_after: np.ndarray        # final fit, theory
    adev_resim_before: np.ndarray       # re-simulated rests, white-only fit
    adev_resim_after: np.ndarray        # re-simulated rests, final fit
    fit_before: dict                    # {id: {"value", "se"[, "correlation_time_s", ...]}}
    fit_after: dict
    tests: tuple                        # one dict per step
    named: tuple[str, ...]
    gap_before: float                   # RMS standardised log-ratio (module docstring)
    gap_after: float
    log_gap_before: float               # RMS log10 ratio [decades]
    log_gap_after: float
    homogeneity: dict
    pose_residual_implication: dict

    @property
    def model_after(self) -> dict:
        """The final noise model in the form :func:`simulate_segments` takes."""
        return {k: ((v["value"], v[TERMS[k].shape_key]) if TERMS[k].shape_key else v["value"])
                for k, v in self.fit_after.items()}

    def to_dict(self) -> dict:
        d = {k: getattr(self, k) for k in self.__dataclass_fields__}
        d["named"] = list(self.named) if self.named else ["none"]
        d["tests"] = list(self.tests)
        return json_safe(d)


@dataclass(frozen=True)
class StochasticResult:
    """Stochastic layer on rest data: per-axis Allan deviations, named terms, gaps and implications."""

    fs: float
    seed: int
    alpha: float
    candidates: tuple[str, ...]
    n_boot: int
    n_resim: int
    segment_lengths: tuple[int, ...]
    axes: tuple[AxisStochastic, ...]
    unit: str = "u"
    notes: tuple[str, ...] = field(default_factory=tuple)

    def axis(self, name: str) -> AxisStochastic:
        for a in self.axes:
            if a.axis == name:
                return a
        raise KeyError(name)

    def to_dict(self) -> dict:
        out = {k: getattr(self, k) for k in ("fs", "seed", "alpha", "n_boot", "n_resim", "unit")}
        out["candidates"] = list(self.candidates)
        out["segment_lengths"] = list(self.segment_lengths)
        out["notes"] = list(self.notes)
        out["terms"] = {k: {"parameter": t.symbol, "unit": t.unit_of(self.unit), "meaning": t.meaning}
                        for k, t in TERMS.items()}
        out["axes"] = {a.axis: a.to_dict() for a in self.axes}
        return json_safe(out)


__all__ = ["AxisStochastic", "StochasticError", "StochasticResult"]
