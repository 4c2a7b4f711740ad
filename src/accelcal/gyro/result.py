"""A gyro calibration with its uncertainty, its trust lines and its motions, as the
calibration file (format 2, its ``gyroscope`` object) and the summary carry it:
``to_dict``/``from_dict`` and ``summary()``.

One class per estimator of the registry (:mod:`accelcal.registry`), found by its
``CAL_TYPE`` among the subclasses of :class:`GyroCalibration`
(:func:`accelcal.calibration.calibration_class`), as the accelerometer's are.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field
from typing import ClassVar

import numpy as np

from .. import distributions as dist
from ..errors import InputShapeError
from ..registry import class_of_type, types_of
from ..summary import Summary
from .effects import correct as correct_effects
from .model import RAW_UNITS, GyroModel


#: Thresholds of the warnings (:mod:`accelcal.gyro.assess`).
RULES = {"excess": 1.5, "p_value": 1e-3, "scale_rel_se": 0.01, "min_axis_turn_deg": 90.0, "short_deg": 10.0,
         "min_long_motions": 5, "integration_fraction": 0.3, "jitter": 0.05, "bias_excess": 3.0,
         "range_fraction": 0.9, "min_dof": 10}

#: The trust verdicts, least trusted first.  ``poorly_determined``: the motions do not pin the
#: parameters down, or too few residuals check them (the flags in :data:`UNDETERMINED_FLAGS`, or
#: fewer than ``RULES["min_dof"]`` degrees of freedom: with ν dof the excess that scales the ±
#: is itself uncertain by ``sqrt(2/ν)``, over 45 % below 10, and t(0.975, ν) exceeds 1.96 by over
#: 14 %); ``caution``: determined, but a warning holds (residuals beyond the noise, saturation,
#: the sample rate, ...); ``trusted``: no warning.
VERDICTS = ("poorly_determined", "caution", "trusted")
UNDETERMINED_FLAGS = ("few_dof", "few_axes", "short_motions", "exactly_determined")


@dataclass(frozen=True)
class GyroQuality:
    """Whether the gyro calibration can be trusted (residuals vs the noise, coverage, warnings)."""

    n_motions: int
    n_parameters: int
    dof: int
    chi2: float
    p_value: float
    excess: float
    residual_rms_deg: float  #: RMS per-motion misfit [deg]
    predicted_rms_deg: float  #: RMS misfit the noise predicts [deg]
    axis_turn_deg: tuple  #: total rotation about each gyro axis over the used motions [deg]
    warnings: tuple[str, ...]
    flags: tuple[str, ...] = ()
    scale_rel_se: tuple = ()  #: relative standard error of each gyro axis' scale (diag of C)

    @property
    def trustworthy(self) -> bool:
        return not self.warnings

    @property
    def verdict(self) -> str:
        """One of :data:`VERDICTS`, from the same evidence as the warnings (their flags and the dof)."""
        if set(self.flags) & set(UNDETERMINED_FLAGS) or self.dof < RULES["min_dof"]:
            return "poorly_determined"
        return "caution" if self.warnings else "trusted"

    @property
    def reasons(self) -> tuple[str, ...]:
        """Short reasons behind :attr:`verdict` (for a figure's mark or the summary's trust line)."""
        out = []
        if self.dof < RULES["min_dof"]:
            out.append(f"{self.dof} dof" + (" (exactly determined)" if "exactly_determined" in self.flags else ""))
        if "few_axes" in self.flags or "short_motions" in self.flags:
            rel = np.asarray(self.scale_rel_se, float)
            out.append(f"scale x/y/z ± {'/'.join(f'{100 * v:.2g}' for v in rel)} %" if rel.size == 3 else
                       "little rotation per axis")
        if "excess" in self.flags:
            out.append(f"excess {self.excess:.3g}")
        out += [f.replace("_", " ") for f in self.flags if f not in UNDETERMINED_FLAGS + ("excess",)]
        return tuple(out)

    def to_dict(self) -> dict:
        d = asdict(self)
        d.update(warnings=list(self.warnings), flags=list(self.flags), axis_turn_deg=list(self.axis_turn_deg),
                 scale_rel_se=list(self.scale_rel_se), trustworthy=self.trustworthy, verdict=self.verdict,
                 reasons=list(self.reasons), rules=dict(RULES))
        return d

    @classmethod
    def from_dict(cls, d: dict) -> GyroQuality:
        keys = set(cls.__dataclass_fields__)
        v = {k: d[k] for k in keys if k in d}
        v["warnings"], v["flags"] = tuple(v.get("warnings", ())), tuple(v.get("flags", ()))
        v["axis_turn_deg"] = tuple(v.get("axis_turn_deg", ()))
        v["scale_rel_se"] = tuple(float("nan") if x is None else float(x) for x in v.get("scale_rel_se", ()))
        for k in ("chi2", "p_value", "excess", "residual_rms_deg", "predicted_rms_deg"):
            v[k] = float("nan") if v.get(k) is None else float(v[k])
        return cls(**v)


def _f(x):
    if isinstance(x, np.ndarray):
        return [_f(v) for v in x.tolist()]
    if isinstance(x, (list, tuple)):
        return [_f(v) for v in x]
    if isinstance(x, (float, np.floating)):
        return None if not math.isfinite(float(x)) else float(x)
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, dict):
        return {k: _f(v) for k, v in x.items()}
    return x


@dataclass(frozen=True, eq=False)
class GyroCalibration:
    """A fitted gyro model, its standard errors, quality, motion table and settings.

    Attributes
    ----------
    model : GyroModel
    standard_errors : dict of ndarray
        From the rest noise, scaled by ``max(1, excess)``: ``C`` (3, 3), ``bias`` (3,),
        ``g_sensitivity`` (3, 3) or absent, ``scale_factors`` (3,) (relative to
        ``nominal``), ``T`` (3, 3) (IMU-TK's misalignment, zero on the diagonal).
    quality : GyroQuality
    motions : dict of lists
        Per motion: ``t_start``, ``t_end``, ``angle_deg`` (integrated rotation),
        ``peak_rate_dps``, ``residual_deg``, ``predicted_deg``, ``used`` and ``note``
        (why a motion was left out).
    settings : dict
        ``estimator``, ``integrator``, ``bias_mode``, ``time_base`` (``h``, ``rate``,
        ``jitter``), ``nominal`` (rad/s per raw unit), ``iterations``, ``seconds``,
        ``bias_chi2``...
    """

    CAL_TYPE: ClassVar[str] = ""

    model: GyroModel
    standard_errors: dict
    quality: GyroQuality
    motions: dict = field(default_factory=dict)
    settings: dict = field(default_factory=dict)

    @property
    def nominal(self) -> float:
        return float(self.settings.get("nominal", RAW_UNITS.get(self.model.raw_unit) or 1.0))

    @property
    def scale_factors(self) -> np.ndarray:
        return self.model.scale_factors(self.nominal)

    @property
    def method(self) -> str:
        return self.CAL_TYPE

    def interval95(self, name: str) -> np.ndarray:
        """Half-width of the 95 % interval of ``name`` (``C``, ``T``, ``scale_factors``):
        ``t(0.975, ν) s.e.`` with the Satterthwaite degrees of freedom ``ν`` the noise model
        gives each parameter (:mod:`accelcal.gyro.noise`); ``1.96 s.e.`` without it."""

        se = np.asarray(self.standard_errors[name], float)
        dof = ((self.settings.get("noise_model") or {}).get("parameter_dof") or {}).get(name)
        if dof is None:
            return 1.959963984540054 * se
        nu = np.array([np.inf if v is None else v for v in dof], float).reshape(se.shape)
        q = np.where(np.isfinite(nu) & (nu > 0), dist.t_ppf(0.975, np.where(np.isfinite(nu) & (nu > 0), nu, 1.0)),
                     1.959963984540054)
        return q * se

    @property
    def effects(self) -> list:
        """The effects beyond the model that ``accelcal discrepancy`` named (``settings["effects"]``)."""
        return list(self.settings.get("effects") or ())

    def correct(self, raw, specific_force=None, *, t=None) -> np.ndarray:
        """Angular rate [rad/s]: :meth:`GyroModel.correct` with the named :attr:`effects`
        applied to the bias-free samples first (:func:`accelcal.gyro.effects.correct`; ``t``
        the sample times [s], needed by the clock's and the time offset's effects)."""
        if not self.effects:
            return self.model.correct(raw, specific_force)
        m = self.model
        y = np.asarray(raw, dtype=float) - m.bias
        if m.g_sensitivity is not None:
            y = y - np.asarray(specific_force, float) @ m.g_sensitivity.T
        return correct_effects(y, self.effects, t=t) @ m.C.T

    def to_dict(self) -> dict:
        return _f({"sensor": "gyroscope", "cal_type": self.CAL_TYPE or None, "model": self.model.to_dict(),
                   "standard_errors": {k: np.asarray(v) for k, v in self.standard_errors.items()},
                   "quality": self.quality.to_dict(), "motions": self.motions, "settings": self.settings})

    @classmethod
    def from_dict(cls, d: dict) -> GyroCalibration:
        """Rebuild from :meth:`to_dict`'s object, as the class of its ``cal_type``
        (:func:`accelcal.registry.class_of_type`; without one, this class)."""

        kind = class_of_type(GyroCalibration, d["cal_type"]) if d.get("cal_type") else GyroCalibration
        if kind is None:
            raise InputShapeError(f"gyroscope: unknown calibration type {d['cal_type']!r}; known: "
                                  f"{', '.join(types_of(GyroCalibration))}")
        se = {k: np.array(v, dtype=float) for k, v in d.get("standard_errors", {}).items() if v is not None}
        return kind(GyroModel.from_dict(d["model"]), se, GyroQuality.from_dict(d["quality"]),
                    dict(d.get("motions", {})), dict(d.get("settings", {})))

    def __eq__(self, other) -> bool:
        if type(self) is not type(other):
            return NotImplemented
        return json.dumps(self.to_dict(), sort_keys=True) == json.dumps(other.to_dict(), sort_keys=True)

    __hash__ = None

    def summary(self, *, written_to=None) -> Summary:
        """Lines for the command line: the triad with ±, the fit, the trust lines (``written_to``: the file)."""
        m, se, q, s = self.model, self.standard_errors, self.quality, self.settings
        nom = self.nominal
        unit = m.raw_unit
        exact = "exactly_determined" in q.flags
        what = (f"{q.n_motions} rotations of known angle ({', '.join(f'{a:g}' for a in s.get('angles_deg', ()))} deg)"
                if exact else f"{q.n_motions} motions between rests")
        chosen = f" (chosen by {s['estimator_chosen_by']})" if s.get("estimator_chosen_by") else ""
        lines = [f"gyroscope: {s.get('estimator', '?')}{chosen} ({s.get('integrator', '?')} integration), "
                 f"{what}, bias from {s.get('bias_mode', '?')} rests"]
        sf, sse = self.scale_factors, se.get("scale_factors", np.full(3, np.nan))
        if unit != "counts" or not str(s.get("nominal_from", "")).startswith("scalar search"):
            lines.append("  scale factors [ppm]: " + ", ".join(
                f"{a} {1e6 * v:+.0f} ± {1e6 * e:.0f}" for a, v, e in zip("xyz", sf, sse)))
        if unit == "counts":
            k = 1.0 / np.diag(m.C)
            ke = np.diag(se.get("C", np.full((3, 3), np.nan))) / np.diag(m.C) ** 2
            lines.append("  sensitivity [counts per rad/s]: " + ", ".join(
                f"{a} {v:.2f} ± {e:.2f}" for a, v, e in zip("xyz", k, ke)))
        T, Te = m.T, se.get("T", np.full((3, 3), np.nan))
        off = [(i, j) for i in range(3) for j in range(3) if i != j]
        lines.append(f"  misalignment T (vs {s.get('frame', 'accelerometer frame')}) [mrad]: " + ", ".join(
            f"{'xyz'[i]}{'xyz'[j]} {1e3 * T[i, j]:+.2f} ± {1e3 * Te[i, j]:.2f}" for i, j in off))
        be = se.get("bias", np.full(3, np.nan))
        lines.append(f"  bias [{unit}]: " + ", ".join(f"{a} {v:.6g} ± {e:.2g}" for a, v, e in zip("xyz", m.bias, be)))
        runs = s.get("runs") or []
        for k, run in enumerate(runs if len(runs) > 1 else []):  # runs recorded apart: each its own bias
            lines.append(f"    run {k + 1}: " + ", ".join(f"{a} {v:.6g} ± {e:.2g}" for a, v, e in
                                                      zip("xyz", run["bias"], run["bias_se"])))
        if m.g_sensitivity is not None:
            Ge = se.get("g_sensitivity", np.full((3, 3), np.nan))
            lines.append(f"  g-sensitivity [{unit} per m/s^2]: " + ", ".join(
                f"{'xyz'[i]}{'xyz'[j]} {m.g_sensitivity[i, j]:+.3g} ± {Ge[i, j]:.2g}"
                for i in range(3) for j in range(3)))
        if not exact:
            lines.append(f"  motion residuals: {q.residual_rms_deg:.3g} deg RMS vs {q.predicted_rms_deg:.3g} deg "
                         f"from the rest noise (chi2/dof = {q.chi2 / max(q.dof, 1):.3g} on {q.dof} dof, "
                         f"excess {q.excess:.3g})")
        nm = s.get("noise_model")
        if nm:
            wander = ", ".join(f"{v:.2g}" for v in nm.get("wander_psd", ()))
            lines.append(f"  noise between the rests (the ±): per-motion error of C {100 * (nm.get('rotation_rel') or 0):.2g} %,"
                         f" motion rate noise {nm.get('motion_rate') or 0:.2g} rad/sqrt(s), rest directions "
                         f"{1e3 * (nm.get('rest_direction') or 0):.2g} mrad, bias wander PSD [{wander}] ({unit})^2/s "
                         f"(chi2/dof = {nm.get('chi2_per_dof', float('nan')):.3g})")
        lines.append(f"  nominal {nom:.6g} rad/s per {unit} ({s.get('nominal_from', 'unit')})")
        lines.append(f"  trust: {q.verdict.replace('_', ' ')}" + (f" ({'; '.join(q.reasons)})" if q.reasons else ""))
        lines += [f"warning: gyroscope: {w}" for w in q.warnings]
        if written_to is not None:
            lines.append(f"written to {written_to}")
        return Summary(lines)


@dataclass(frozen=True, eq=False)
class GyroIterativeCalibration(GyroCalibration):
    """Weighted Gauss-Newton on the motions between rests (``gyro_iterative``)."""

    CAL_TYPE: ClassVar[str] = "gyro_iterative"


@dataclass(frozen=True, eq=False)
class GyroOneStepCalibration(GyroCalibration):
    """One linearised solve about the nominal model (``gyro_one_step``)."""

    CAL_TYPE: ClassVar[str] = "gyro_one_step"


@dataclass(frozen=True, eq=False)
class GyroFerrarisCalibration(GyroCalibration):
    """Three rotations of known angle (``gyro_ferraris``): exactly determined, no residual."""

    CAL_TYPE: ClassVar[str] = "gyro_ferraris"


__all__ = ["GyroCalibration", "GyroFerrarisCalibration", "GyroIterativeCalibration", "GyroOneStepCalibration",
           "GyroQuality", "RULES", "UNDETERMINED_FLAGS", "VERDICTS"]
