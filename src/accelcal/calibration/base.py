"""The calibrated model ``z = M P(x) + b + ...``: :class:`Calibration` (units, quality,
provenance, ``apply``, JSON), the fitted effects it carries and the file format's constants."""

from __future__ import annotations

import json
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import ClassVar

import numpy as np

from ..atomic import write_json_atomic
from ..effects import EFFECT_IDS, EFFECTS, TEMPERATURE, TIME, effect
from ..errors import (AccelcalError)
from ..extended_model import model_terms
from ..jsonsafe import json_safe
from ..mag.result import MagCalibration
from ..model import m_from_params, params_from_m
from ..quality import FitQuality
from ..registry import ESTIMATORS, class_of_type, subclasses, types_of
from ..summary import Summary
from ..units import G0, acceleration_unit
from .summary import calibration_summary

FORMAT = "accelcal-calibration"
#: Version of the JSON layout written by :meth:`Calibration.to_dict` (0: the CLI's output
#: before versions, read as such; 1: the accelerometer alone; 2: its ``gyroscope`` object,
#: null when the recording had none).
FORMAT_VERSION = 2
#: Effects :meth:`Calibration.apply` can invert: every effect of :mod:`accelcal.effects`
#: (:mod:`accelcal.extended_model` implements the model for each).
APPLICABLE_EFFECTS = EFFECT_IDS


class CalibrationFileError(AccelcalError):
    """A calibration file that cannot be read or does not fit the data it is applied to."""


@dataclass(frozen=True)
class EffectTerm:
    """One fitted effect: the block of parameters of a discrepancy effect (three, x, y, z, or
    the size of a harmonic effect: :attr:`accelcal.effects.Effect.size`).

    Attributes
    ----------
    id : str
        An id of :data:`accelcal.effects.EFFECTS`.
    values : ndarray, shape (size,)
        The parameters (per axis: ``k``, ``c``, ``β``, ``γ``, ``κ``, ...; ``h_m``), units of
        :mod:`accelcal.effects` (data unit Z, unit of g G).
    reference : float or None
        Centre of the covariate (session mean time [s] or temperature [°C]).
    standard_errors : ndarray, shape (size,), or None
    """

    id: str
    values: np.ndarray
    reference: float | None = None
    standard_errors: np.ndarray | None = None

    def to_dict(self) -> dict:
        e = effect(self.id)
        return {"id": self.id, "kind": e.kind, "covariate": e.covariate, "reference": self.reference,
                "unit": e.unit, "parameters": dict(zip(e.parameters, map(float, self.values))),
                "standard_errors": None if self.standard_errors is None else
                dict(zip(e.parameters, map(_json_float, self.standard_errors)))}

    @classmethod
    def from_dict(cls, d: dict) -> EffectTerm:
        e = effect(d["id"])
        vals = np.array([float(d["parameters"][p]) for p in e.parameters])
        se = d.get("standard_errors")
        se = None if not se else np.array([np.nan if se[p] is None else float(se[p]) for p in e.parameters])
        ref = d.get("reference")
        return cls(d["id"], vals, None if ref is None else float(ref), se)


@dataclass(frozen=True, eq=False)
class Calibration:
    """A calibrated model ``z = M P(x) + b + ...`` with its units, quality and provenance.

    Attributes
    ----------
    bias : ndarray, shape (3,)
        ``b`` in :attr:`unit`.
    M : ndarray, shape (3, 3)
        Lower triangular; counts per m/s² for raw counts, dimensionless for m/s².
    g : float
        Gravity magnitude the calibration was fitted with [m/s²].
    unit : {'m/s^2', 'counts'} or None
        Unit of ``z`` and ``b`` (None: a format-0 file that did not say).
    input_offset, input_sensitivity : ndarray, shape (3,)
        Raw input → fit unit: ``z = (raw - input_offset) / input_sensitivity`` (zeros and
        ones unless a nominal conversion of raw counts, in counts per m/s², was applied
        for a bias-only model).
    input_unit : str or None
        Unit of the raw data ``apply`` expects by default.
    effects : tuple of EffectTerm
    standard_errors : dict of ndarray
        Residual-scaled linearised standard errors (the key the CLI always wrote).
    standard_errors_noise : dict of ndarray
        From the independent pose noise, scaled by ``max(1, excess)`` (:mod:`accelcal.quality`).
    quality : FitQuality or None
    residuals : ndarray, shape (n,)
    poses : dict
        ``mean``, ``mean_std``, ``t_start``, ``t_end``, ``n_samples``, ``temp``, ``labels``.
    provenance : dict
        ``recording``, ``recording_sha256``, ``accelcal_version``, ``notes``, ``static``,
        ``elapsed_s`` ... (copied to the JSON as they are).
    gyro : GyroCalibration or None
        The gyroscope calibrated from the same session (:mod:`accelcal.gyro`), in this
        accelerometer's frame; None when the recording had no gyro (or a format-0/1 file).
    mag : MagCalibration or None
        The magnetometer calibrated from the same session (:mod:`accelcal.mag`), aligned to
        this accelerometer's frame; None when the recording had no magnetometer.
    """

    CAL_TYPE: ClassVar[str] = ""

    bias: np.ndarray
    M: np.ndarray
    g: float
    unit: str | None
    input_offset: np.ndarray = field(default_factory=lambda: np.zeros(3))
    input_sensitivity: np.ndarray = field(default_factory=lambda: np.ones(3))
    input_unit: str | None = None
    effects: tuple[EffectTerm, ...] = ()
    standard_errors: dict = field(default_factory=dict)
    standard_errors_noise: dict = field(default_factory=dict)
    quality: object | None = None
    residuals: np.ndarray | None = None
    poses: dict = field(default_factory=dict)
    provenance: dict = field(default_factory=dict)
    gyro: object | None = None
    mag: object | None = None

    def __post_init__(self):
        for name in ("bias", "input_offset", "input_sensitivity"):
            object.__setattr__(self, name, np.asarray(getattr(self, name), dtype=float).reshape(3))
        M = np.asarray(self.M, dtype=float)
        if M.shape != (3, 3) or not np.all(np.isfinite(M)) or not np.all(np.isfinite(self.bias)):
            raise CalibrationFileError(f"a calibration needs a finite bias (3,) and M (3, 3); got M {M.shape}")
        object.__setattr__(self, "M", M)
        for e in self.effects:
            if e.id not in EFFECTS:
                raise CalibrationFileError(f"effect {e.id!r} cannot be applied; known: {', '.join(EFFECTS)}")

    # ----------------------------------------------------------------- derived quantities

    @property
    def method(self) -> str:
        return self.CAL_TYPE

    @property
    def model(self) -> str:
        return ESTIMATORS[self.CAL_TYPE].model if self.CAL_TYPE in ESTIMATORS else "full"

    @property
    def gain(self) -> np.ndarray:
        """Row norms of ``M`` (``1 + s``): counts per m/s² for counts, dimensionless for m/s²."""
        return np.linalg.norm(self.M, axis=1)

    @property
    def scale_factors(self) -> np.ndarray:
        return params_from_m(self.M)[0]

    @property
    def nonorthogonality_deg(self) -> np.ndarray:
        return np.rad2deg(params_from_m(self.M)[1])

    @property
    def n_poses(self) -> int:
        return 0 if "mean" not in self.poses else len(self.poses["mean"])

    @property
    def residual_rms(self) -> float:
        return float("nan") if self.residuals is None else float(np.sqrt(np.mean(np.square(self.residuals))))

    @property
    def units(self) -> dict:
        """The unit of every quantity of the JSON, spelled out."""
        z = self.unit or "data unit"
        gain = "counts/(m/s^2)" if self.unit == "counts" else ("1" if self.unit == "m/s^2" else f"{z}/(m/s^2)")
        return {"data": z, "g": "m/s^2", "bias": z, "M": gain, "gain": gain,
                "scale_factors": "1 (gain - 1; a scale-factor error only for data in m/s^2)",
                "nonorthogonality_deg": "deg", "residuals": "m/s^2", "residual_rms": "m/s^2",
                "poses.mean": z, "poses.mean_std": z, "poses.t_start": "s", "calibrated output": "m/s^2"}

    # ----------------------------------------------------------------- summary

    def summary(self, *, written_to=None, init_rest_s: float | None = None) -> Summary:
        """The calibration in a few lines: what ``accelcal calibrate`` prints.

        The method and its poses (with the static detection's noise reference and the
        reader's notes from :attr:`provenance`), the fit against the pose noise, the
        parameters with their standard errors, and the quality's warnings.

        Parameters
        ----------
        init_rest_s : float, optional
            Length of the initial rest that set the noise reference [s] (the detection's
            :attr:`StaticPoses.init_rest <accelcal.static.StaticPoses.init_rest>`), shown
            beside it.
        written_to : path, optional
            Where the calibration file was written (a line says so).

        Returns
        -------
        Summary
            Lines without a final newline (a ``str``; also as a dict and HTML).
        """
        return Summary(calibration_summary(self, init_rest_s=init_rest_s, written_to=written_to))

    # ----------------------------------------------------------------- apply

    def apply(self, raw, *, t=None, temp=None, unit: str | None = None, effects: bool = True) -> np.ndarray:
        """Calibrated specific force [m/s²] of raw samples.

        Parameters
        ----------
        raw : array_like, shape (n, 3)
            Raw accelerometer samples.
        t : array_like, shape (n,), optional
            Time [s] on the calibration session's clock (needed by ``bias_drift``).
        temp : array_like, shape (n,), optional
            Temperature [°C] (needed by ``temperature`` and ``temperature_scale``).
        unit : str, optional
            Unit of ``raw`` (``m/s2``, ``g``, ``mg``, ``counts``); default
            :attr:`input_unit` (the unit the calibration was made from).
        effects : bool
            Apply the fitted effects (default); False gives the base model only.

        Returns
        -------
        ndarray, shape (n, 3)
        """
        z = np.array(raw, dtype=float)
        if z.ndim != 2 or z.shape[1] != 3:
            raise CalibrationFileError(f"apply needs raw samples of shape (n, 3), got {z.shape}")
        if not np.all(np.isfinite(z)):
            raise CalibrationFileError("apply: raw samples hold NaN or infinite values")
        z = self._to_fit_unit(z, unit)
        terms = self.effects if effects else ()
        n = len(z)
        cov = {TIME: _covariate(t, n, "t", terms, TIME), TEMPERATURE: _covariate(temp, n, "temp", terms, TEMPERATURE)}
        params = np.concatenate([np.ravel(tm.values) for tm in terms]) if terms else np.zeros(0)
        model = model_terms([tm.id for tm in terms], params, cov, n, references=[tm.reference for tm in terms])
        y = np.linalg.solve(self.M, (z - self.bias - model.offset).T).T
        if not model.nonlinear:
            return y
        x, slope, converged = model.solve(y, max(float(np.max(np.abs(y))), self.g))
        if not model.invertible(slope):
            raise CalibrationFileError("the calibration's polynomial effects are not monotonic over these "
                                       "samples (they lie outside the calibrated range): cannot invert them")
        if not converged:
            raise CalibrationFileError("the polynomial effects did not invert (Newton did not converge)")
        return x

    def apply_gyro(self, raw_gyro, raw_acc=None, *, t=None, temp=None, unit: str | None = None) -> np.ndarray:
        """Calibrated angular rate [rad/s] in this accelerometer's frame (:attr:`gyro`).

        Parameters
        ----------
        raw_gyro : array_like, shape (n, 3)
            Raw gyro samples in the unit the gyro was calibrated from (``gyro.model.raw_unit``).
        raw_acc : array_like, shape (n, 3), optional
            The raw accelerometer samples of the same instants: needed when the gyro model
            has a g-sensitivity (its specific force is :meth:`apply`'s); ``t``, ``temp`` and
            ``unit`` as for :meth:`apply`.
        """
        if self.gyro is None:
            raise CalibrationFileError("this calibration has no gyroscope (calibrated from a recording without gyro "
                                       "columns, or a format-1 file)")
        model = self.gyro.model
        f = None
        if model.g_sensitivity is not None:
            if raw_acc is None:
                raise CalibrationFileError("the gyro model has a g-sensitivity: it needs the accelerometer samples")
            f = self.apply(raw_acc, t=t, temp=temp, unit=unit)
        y = np.asarray(raw_gyro, dtype=float)
        if y.ndim != 2 or y.shape[1] != 3 or not np.all(np.isfinite(y)):
            raise CalibrationFileError(f"apply_gyro needs finite raw samples of shape (n, 3), got {y.shape}")
        return self.gyro.correct(y, f, t=t)  # with the effects `accelcal discrepancy` named, if any

    def _to_fit_unit(self, z: np.ndarray, unit: str | None) -> np.ndarray:
        given = self.input_unit if unit is None else acceleration_unit(unit)
        if unit is not None and given is None:
            raise CalibrationFileError(f"unknown unit {unit!r}; use m/s2, g, mg or counts")
        if given is None or self.unit is None:
            return (z - self.input_offset) / self.input_sensitivity
        if given in ("g", "mg"):
            z = z * (G0 if given == "g" else G0 * 1e-3)
            given = "m/s^2"
        nominal = np.any(self.input_offset != 0) or np.any(self.input_sensitivity != 1)
        if nominal:
            if given != (self.input_unit or "counts"):
                raise CalibrationFileError(f"this calibration converts raw {self.input_unit} nominally; the data are "
                                           f"in {given}")
            return (z - self.input_offset) / self.input_sensitivity
        if given != self.unit:
            raise CalibrationFileError(f"the data are in {given} but the calibration was fitted to {self.unit}: "
                                       "apply it to data in the unit it was made from (--unit)")
        return z

    # ----------------------------------------------------------------- JSON

    def _method_fields(self) -> dict:
        """Method-specific JSON keys (solver status, conditioning...)."""
        return {k: _jsonable(getattr(self, k)) for k in self._method_field_names()}

    @classmethod
    def _method_field_names(cls) -> tuple[str, ...]:
        return tuple(f.name for f in fields(cls) if f.name not in _BASE_FIELDS)

    def to_dict(self) -> dict:
        """The JSON object (see the module docstring)."""
        est = ESTIMATORS.get(self.CAL_TYPE)
        q = self.quality
        d = {
            "format": FORMAT, "format_version": FORMAT_VERSION, "cal_type": self.CAL_TYPE,
            "method": est.cli_name if est else self.CAL_TYPE, "model": self.model,
            "g": float(self.g), "n_poses": self.n_poses,
            "bias": self.bias.tolist(), "M": self.M.tolist(),
            "scale_factors": self.scale_factors.tolist(), "nonorthogonality_deg": self.nonorthogonality_deg.tolist(),
            "gain": self.gain.tolist(),
            "residual_rms": self.residual_rms,
            "residuals": None if self.residuals is None else np.asarray(self.residuals).tolist(),
            "standard_errors": {k: np.asarray(v).tolist() for k, v in self.standard_errors.items()},
            "standard_errors_noise": {k: np.asarray(v).tolist() for k, v in self.standard_errors_noise.items()},
            "unit": self.unit, "units": self.units,
            "input": {"unit": self.input_unit, "offset": self.input_offset.tolist(),
                      "sensitivity": self.input_sensitivity.tolist(),
                      "meaning": "z = (raw - offset) / sensitivity is what the model was fitted to"},
            "effects": [e.to_dict() for e in self.effects],
            "quality": None if q is None else q.to_dict(),
            **self._method_fields(),
            "poses": {k: _jsonable(v) for k, v in self.poses.items()},
            "gyroscope": None if self.gyro is None else self.gyro.to_dict(),
            **({} if self.mag is None else {"magnetometer": self.mag.to_dict()}),
            **self.provenance,
        }
        return json_safe(d)

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), indent=2)

    def save(self, path) -> None:
        """Write the JSON atomically (whole or not at all)."""

        write_json_atomic(path, self.to_dict())

    @classmethod
    def from_dict(cls, d: dict) -> Calibration:
        """Rebuild a calibration from :meth:`to_dict`'s object (any subclass, by ``cal_type``)."""
        return _from_dict(d, source="calibration")

    @classmethod
    def from_json(cls, text: str) -> Calibration:
        try:
            d = json.loads(text)
        except json.JSONDecodeError as e:
            raise CalibrationFileError(f"not a calibration: invalid JSON ({' '.join(str(e).split())})") from None
        return _from_dict(d, source="calibration")

    def __eq__(self, other) -> bool:
        if type(self) is not type(other):
            return NotImplemented
        return json.dumps(self.to_dict(), sort_keys=True) == json.dumps(other.to_dict(), sort_keys=True)

    __hash__ = None


_BASE_FIELDS = frozenset(f.name for f in fields(Calibration))


def _covariate(values, n: int, name: str, terms, kind: str):
    needed = [t.id for t in terms if EFFECTS[t.id].covariate == kind]
    if not needed:
        return None
    if values is None:
        raise CalibrationFileError(f"the calibration's {', '.join(needed)} term needs the {name} of every sample; "
                                   f"the data have none" + (" (a temp column)" if name == "temp" else ""))
    v = np.asarray(values, dtype=float)
    if v.shape != (n,) or not np.all(np.isfinite(v)):
        raise CalibrationFileError(f"{name} must be {n} finite values, one per sample")
    return v


def _json_float(x):
    x = float(x)
    return x if np.isfinite(x) else None


def _jsonable(v):
    if isinstance(v, np.ndarray):
        return v.tolist()
    if isinstance(v, (np.floating, np.integer)):
        return v.item()
    if isinstance(v, tuple):
        return list(v)
    return v


# --------------------------------------------------------------------------- the classes by type tag


def calibration_class(cal_type: str, root: type | None = None) -> type:
    """The subclass of ``root`` (default :class:`Calibration`; the gyroscope's:
    :class:`accelcal.gyro.result.GyroCalibration`) whose own ``CAL_TYPE`` is ``cal_type``
    (:func:`accelcal.registry.class_of_type`: the registry's class first, else a subclass
    defined anywhere, a registered estimator's module or a user's script).

    Raises
    ------
    CalibrationFileError
        No such class (the message lists the known types).
    """
    root = Calibration if root is None else root
    cls = class_of_type(root, cal_type)
    if cls is None:
        raise CalibrationFileError(f"unknown calibration type {cal_type!r}; known: {', '.join(types_of(root))}")
    return cls


def _all_calibration_classes() -> list[type]:
    """Every :class:`Calibration` subclass that declares a ``CAL_TYPE`` (the registered estimators' imported first)."""
    types_of(Calibration)
    return [c for c in subclasses(Calibration) if "CAL_TYPE" in c.__dict__]


# --------------------------------------------------------------------------- loading


def load_calibration(path) -> Calibration:
    """Read a calibration file: ``accelcal calibrate``'s JSON (any version this code knows)
    or ``accelcal discrepancy``'s report (its base model plus the named effects).

    Raises
    ------
    CalibrationFileError
        Missing file, invalid JSON, unknown ``cal_type``, a newer format version, or
        missing or malformed keys (one line naming the key).
    """
    path = Path(path)
    if not path.is_file():
        raise CalibrationFileError(f"{path}: no such calibration file")
    try:
        d = json.loads(path.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as e:
        raise CalibrationFileError(f"{path}: not a calibration (invalid JSON: {' '.join(str(e).split())[:80]})") \
            from None
    return _from_dict(d, source=str(path))


def _from_dict(d, source: str) -> Calibration:
    if not isinstance(d, dict):
        raise CalibrationFileError(f"{source}: not a calibration (expected a JSON object)")
    if d.get("sensor") == "gyroscope" and d.get("accelerometer", 1) is None:
        raise CalibrationFileError(f"{source}: a gyroscope calibrated alone (no accelerometer): apply and export take "
                                   "a calibration with an accelerometer; its model is the file's 'gyroscope' object "
                                   "(accelcal.gyro.result.GyroCalibration.from_dict)")
    try:
        if "model_after" in d and "cal_type" not in d:
            return _from_discrepancy(d)
        version = int(d.get("format_version", 0))
        if version > FORMAT_VERSION:
            raise CalibrationFileError(f"{source}: calibration format {version} is newer than this accelcal reads "
                                       f"({FORMAT_VERSION}); upgrade accelcal")
        cal_type = d.get("cal_type") or str(d.get("method", "")).replace("-", "_")
        cls = calibration_class(cal_type)
        return cls(**_common(d, version), **_method_values(cls, d))
    except CalibrationFileError as e:
        if str(e).startswith(source):
            raise
        raise CalibrationFileError(f"{source}: {e}") from None
    except (KeyError, TypeError, ValueError, IndexError) as e:
        what = f"key {e.args[0]!r} missing" if isinstance(e, KeyError) else f"malformed value ({e})"
        raise CalibrationFileError(f"{source}: not a valid calibration ({what})") from None


def _arr(v):
    return None if v is None else np.array([np.nan if x is None else x for x in np.ravel(v)], dtype=float).reshape(
        np.shape(v))


def _common(d: dict, version: int) -> dict:
    inp = d.get("input") or {}
    unit = d.get("unit")
    poses = {k: (v if k == "labels" else _arr(v)) for k, v in (d.get("poses") or {}).items()}
    if poses.get("n_samples") is not None:
        poses["n_samples"] = poses["n_samples"].astype(int)
    known = {"format", "format_version", "cal_type", "method", "model", "g", "n_poses", "bias", "M", "scale_factors",
             "nonorthogonality_deg", "gain", "residual_rms", "residuals", "standard_errors", "standard_errors_noise",
             "unit", "units", "input", "effects", "quality", "poses", "gyroscope", "magnetometer"}
    known |= {k for c in _all_calibration_classes() for k in c._method_field_names()}
    return {
        "bias": _arr(d["bias"]), "M": _arr(d["M"]), "g": float(d["g"]), "unit": unit,
        "input_offset": _arr(inp.get("offset", [0.0] * 3)),
        "input_sensitivity": _arr(inp.get("sensitivity", [1.0] * 3)),
        "input_unit": inp.get("unit", unit),
        "effects": tuple(EffectTerm.from_dict(e) for e in d.get("effects") or ()),
        "standard_errors": {k: _arr(v) for k, v in (d.get("standard_errors") or {}).items()},
        "standard_errors_noise": {k: _arr(v) for k, v in (d.get("standard_errors_noise") or {}).items()},
        "quality": None if not d.get("quality") else FitQuality.from_dict(d["quality"]),
        "residuals": _arr(d.get("residuals")),
        "poses": poses,
        "provenance": {k: v for k, v in d.items() if k not in known},
        "gyro": _gyro(d.get("gyroscope")),
        "mag": _mag(d.get("magnetometer")),
    }


def _gyro(d):
    """The ``gyroscope`` object of a format-2 file (None: absent, or a format-0/1 file), as
    the class the registry names for its ``cal_type`` (by name: the gyro package is not
    imported here, it imports this one's lookup)."""
    if not d:
        return None
    gyro = [e for e in ESTIMATORS.values() if e.sensor == "gyroscope"]
    if d.get("cal_type") not in {e.name for e in gyro}:
        raise CalibrationFileError(f"gyroscope: unknown calibration type {d.get('cal_type')!r}; known: "
                                   f"{', '.join(e.name for e in gyro)}")
    return ESTIMATORS[d["cal_type"]].load_calibration().from_dict(d)


def _mag(d):
    """The ``magnetometer`` object (None: absent)."""
    return MagCalibration.from_dict(d) if d else None


def _method_values(cls, d: dict) -> dict:
    out = {}
    for name in cls._method_field_names():
        if name not in d or d[name] is None:
            continue
        v = d[name]
        out[name] = _arr(v) if isinstance(v, list) and name != "base_effects_named" else v
        if name == "base_effects_named":
            out[name] = tuple(v)
    return out


def _from_discrepancy(d: dict) -> Calibration:
    """The base model + named effects of an ``accelcal discrepancy`` report."""

    after = d["model_after"]
    p = after["parameters"]
    val = {k: float(v["value"]) for k, v in p.items()}
    se = {k: (np.nan if v.get("se") is None else float(v["se"])) for k, v in p.items()}
    bias = np.array([val[f"b_{a}"] for a in "xyz"])
    s = np.array([val[f"s_{a}"] for a in "xyz"])
    th = np.array([val[k] for k in ("theta_xy", "theta_zx", "theta_zy")])
    poses = d.get("poses") or {}
    refs = {TIME: after.get("t_ref"), TEMPERATURE: after.get("temp_ref")}
    if refs[TIME] is None and poses.get("t"):
        refs[TIME] = float(np.mean(poses["t"]))
    if refs[TEMPERATURE] is None and poses.get("temp"):
        refs[TEMPERATURE] = float(np.mean(poses["temp"]))
    terms = []
    for eid in after.get("effects", []):
        e = effect(eid)
        ref = refs[e.covariate] if e.covariate else None
        if e.covariate and ref is None:
            raise CalibrationFileError(f"effect {eid} needs the session's mean {e.covariate}, which the report lacks")
        terms.append(EffectTerm(eid, np.array([val[q] for q in e.parameters]), ref,
                                np.array([se[q] for q in e.parameters])))
    units = d.get("units") or {}
    unit = d.get("unit") or units.get("data")
    unit = unit if unit in ("m/s^2", "counts") else None
    inp = d.get("input") or {}
    keep = {k: d[k] for k in ("recording", "recording_sha256", "accelcal_version") if k in d}
    keep["source"] = "accelcal discrepancy report (model_after)"
    return calibration_class("extended")(
        bias=bias, M=m_from_params(s, th), g=float(d["g"]), unit=unit, input_unit=inp.get("unit", unit),
        effects=tuple(terms),
        standard_errors={"bias": np.array([se[f"b_{a}"] for a in "xyz"]),
                         "scale_factors": np.array([se[f"s_{a}"] for a in "xyz"]),
                         "nonorthogonality_deg": np.rad2deg([se[k] for k in ("theta_xy", "theta_zx", "theta_zy")])},
        residuals=_arr((poses.get("residual_after"))),
        poses={"t_mid": _arr(poses.get("t")), "temp": _arr(poses.get("temp"))} if poses.get("t") else {},
        provenance=keep, base_effects_named=tuple(after.get("effects", [])),
        gyro=_gyro((d.get("gyroscope") or {}).get("calibration")))
