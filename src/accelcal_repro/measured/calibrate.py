"""Calibrating one measured recording: static detection → pose set → every estimator → tidy tables.

Units.  The full models are fitted to the pose means as stored (raw counts for the
Xsens and MPU-6050 files) with g in m/s², so that ``M`` carries the sensitivity in
counts per m/s² and ``b`` is in counts (as in IMU-TK).  The bias-only models fix
``M = I`` and therefore need z and g in one unit: they are fitted to the pose means
converted with the recording's *nominal* conversion (``(z - offset) / counts_per_unit``,
:func:`accelcal.nominal.nominal_conversion`), and their bias is converted back to the
file unit for the tables (``offset + counts_per_unit · b``).  Where the true sensitivity
differs from the nominal one, the bias-only model is wrong by that much, and its
residuals and χ² show it.  Residuals are in m/s² for every estimator.

Pose sets.  All detected rests are used for the hand-placed sessions (Xsens, MPU-6050).
For the imucal Ferraris session the six rests that overlap the section list's static
positions (x_p ... z_a) are used, labelled by it: the other detected rests lie before,
between or after the three 360° rotations, in the same three "parallel" orientations
as x_p, y_p, z_p (the rotation sections turn the sensor about the vertical axis), so
adding them only re-weights three of the six orientations (up to 4 rests for x_p
against 1 for x_a), and it is the six-position design that imucal's Ferraris
calibration, the peer, uses.  ``pose_selection='all'`` uses every rest instead.
"""

from __future__ import annotations

import time
import zlib
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from accelcal import evaluation as ev
from accelcal.calibration import calibrate_poses, pose_noise_std
from accelcal.errors import AccelcalError, RecordingError, TooFewPosesError
from accelcal.recording import Recording
from accelcal.registry import ESTIMATORS, estimator
from accelcal.static import StaticPoses, detect_static_recording
from .sources import FERRARIS_STATIC, source

AXES = ("x", "y", "z")
#: The per-recording tables, by file stem (``results/measured/<recording>/<stem>.csv``).
TABLES = ("poses", "params", "pose_errors", "summary", "agreement", "nominal")
FULL_PARAMETERS = (*(f"bias_{a}" for a in AXES), *(f"sensitivity_{a}" for a in AXES),
                   "nonorth_xy", "nonorth_zx", "nonorth_zy")
BIAS_PARAMETERS = FULL_PARAMETERS[:3]


@dataclass(frozen=True)
class PoseSet:
    """The static poses an estimator is fitted to (rows in time order).

    ``detected`` holds each pose's index among all detected rests.
    """

    recording: str
    means: np.ndarray
    mean_std: np.ndarray
    noise_std: np.ndarray
    t_start: np.ndarray
    t_end: np.ndarray
    n_samples: np.ndarray
    labels: tuple[str, ...]
    detected: np.ndarray
    temp: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.means)

    @property
    def t_mid(self) -> np.ndarray:
        return 0.5 * (self.t_start + self.t_end)


@dataclass(frozen=True)
class Frame:
    """What one estimator sees: pose means ``z`` and their standard errors in its unit, g,
    and the map of its bias back to the file unit (``offset + scale · b``)."""

    z: np.ndarray
    mean_std: np.ndarray
    g: float
    offset: np.ndarray
    scale: np.ndarray


@dataclass
class MeasuredCalibration:
    """Every table of one recording (tidy: one row per recording × estimator × parameter or pose)."""

    recording: str
    poses: pd.DataFrame
    params: pd.DataFrame
    pose_errors: pd.DataFrame
    summary: pd.DataFrame
    agreement: pd.DataFrame
    nominal: pd.DataFrame
    results: dict = field(default_factory=dict, repr=False)
    pose_set: PoseSet | None = field(default=None, repr=False)
    detected: StaticPoses | None = field(default=None, repr=False)


# --------------------------------------------------------------------------- poses


def select_poses(name: str, detected: StaticPoses, sections: dict | None = None,
                 selection: str = "section_list") -> tuple[np.ndarray, list[str]]:
    """Indices (into ``detected``) of the poses to fit, and a label for every detected rest.

    Parameters
    ----------
    name : str
        Recording name (for messages).
    detected : StaticPoses
    sections : dict, optional
        imucal section list ``{name: (start, end)}`` (sample positions, end exclusive).
    selection : {'section_list', 'all'}
        With a section list: the rests matching its six static positions, or every rest.

    Returns
    -------
    used : ndarray of int
    labels : list of str, one per detected rest (``'x_p'`` etc. where a section matches
        it, else ``'rest<k>'``).

    Raises
    ------
    RecordingError
        A static section that no detected rest covers by at least half, or two sections
        on one rest.
    """
    n = len(detected)
    labels = [f"rest{k:02d}" for k in range(n)]
    if sections is None:
        return np.arange(n), labels
    if selection not in ("section_list", "all"):
        raise AccelcalError(f"pose_selection must be 'section_list' or 'all', got {selection!r}")
    iv = detected.intervals
    matched = []
    for key in FERRARIS_STATIC:
        if key not in sections:
            raise RecordingError(f"{name}: section list lacks the static position {key!r}")
        a, b = sections[key]
        overlap = np.clip(np.minimum(iv[:, 1], b) - np.maximum(iv[:, 0], a), 0, None)
        j = int(np.argmax(overlap))
        if overlap[j] < 0.5 * (b - a):
            raise RecordingError(f"{name}: no detected rest covers half of section {key!r} (samples {a}-{b})")
        if j in matched:
            raise RecordingError(f"{name}: sections {labels[j]!r} and {key!r} fall on the same detected rest")
        matched.append(j)
        labels[j] = key
    used = np.arange(n) if selection == "all" else np.array(sorted(matched))
    return used, labels


def pose_set(name: str, detected: StaticPoses, used, labels) -> PoseSet:
    used = np.asarray(used, int)
    return PoseSet(recording=name, means=detected.means[used], mean_std=detected.mean_std[used],
                   noise_std=detected.noise_std[used], t_start=detected.t_start[used],
                   t_end=detected.t_end[used], n_samples=detected.n_samples[used],
                   labels=tuple(labels[k] for k in used), detected=used,
                   temp=None if detected.temp is None else detected.temp[used])


def poses_table(name: str, detected: StaticPoses, used, labels, t) -> pd.DataFrame:
    """One row per detected rest, with ``used`` marking the fitted ones.

    ``noise_reference`` and ``reference_t_start``/``_t_end`` (the same on every row of a
    recording) say where the detection's noise level came from
    (:attr:`accelcal.static.StaticPoses.reference`) and which stretch it was.
    """
    d = {"recording": name, "pose": np.arange(len(detected)), "label": labels,
         "t_start": detected.t_start, "t_end": detected.t_end, "n_samples": detected.n_samples,
         "start_index": detected.intervals[:, 0], "stop_index": detected.intervals[:, 1]}
    for k, a in enumerate(AXES):
        d[f"mean_{a}"] = detected.means[:, k]
    for k, a in enumerate(AXES):
        d[f"mean_std_{a}"] = detected.mean_std[:, k]
    for k, a in enumerate(AXES):
        d[f"noise_std_{a}"] = detected.noise_std[:, k]
    d["used"] = np.isin(np.arange(len(detected)), used)
    a, b = detected.init_rest
    d["noise_reference"] = detected.reference
    d["reference_t_start"] = float(t[a])
    d["reference_t_end"] = float(t[b - 1])
    return pd.DataFrame(d)


# --------------------------------------------------------------------------- estimators


def conversion_for(est: str, conversion):
    """The nominal conversion a bias-only estimator is fitted through (module docstring:
    units), None for the full models."""
    return conversion if estimator(est).model == "bias" else None


def frame(cal) -> Frame:
    """What the calibration ``cal`` was fitted to, and the map of its bias back to the
    file unit (:func:`accelcal.calibration.calibrate_poses`, ``conversion``)."""
    return Frame(np.asarray(cal.poses["mean"]), np.asarray(cal.poses["mean_std"]), cal.g, cal.input_offset,
                 cal.input_sensitivity)


def make_fit(est: str, fr: Frame):
    """``fit(z) -> result`` for estimator ``est`` with g and the noise level bound in, as
    :func:`accelcal.calibration.calibrate_poses` fits it (ALS: the rests' noise level,
    :func:`accelcal.calibration.pose_noise_std`)."""
    e = estimator(est)
    noise = pose_noise_std(fr.mean_std) if e.needs_noise else None
    return lambda z: e.fit(z, fr.g, noise_std=noise)


def parameter_names(est: str) -> tuple[str, ...]:
    return FULL_PARAMETERS if estimator(est).model == "full" else BIAS_PARAMETERS


def parameter_vector(result, fr: Frame) -> np.ndarray:
    """Reported parameters: bias (file unit), sensitivity ``1 + s`` (file unit per m/s²
    for counts, dimensionless for m/s²) and non-orthogonality [deg]."""
    b = fr.offset + fr.scale * result.bias
    if result.model == "bias":
        return b
    return np.concatenate([b, 1.0 + result.scale_factors, result.nonorthogonality_deg])


def _se_vector(se_b, se_s, se_th_deg, fr: Frame, model: str) -> np.ndarray:
    b = fr.scale * np.asarray(se_b, float)
    if model == "bias":
        return b
    return np.concatenate([b, np.asarray(se_s, float), np.asarray(se_th_deg, float)])


def parameter_units(est: str, unit: str) -> tuple[str, ...]:
    sens = "counts/(m/s^2)" if unit == "counts" else "1"
    u = (unit,) * 3
    return u if estimator(est).model == "bias" else (*u, *(sens,) * 3, *("deg",) * 3)


# --------------------------------------------------------------------------- one recording


def calibrate_recording(name: str, rec: Recording, *, g: float, estimators, sections=None,
                        pose_selection: str = "section_list", n_boot: int = 200, seed: int = 0,
                        level: float = 0.95, min_valid_fraction: float = 0.95,
                        static_kw: dict | None = None) -> MeasuredCalibration:
    """Detect the poses of ``rec``, fit every estimator, evaluate, and tabulate.

    Parameters
    ----------
    name : str
        Recording name (key of :data:`accelcal_repro.measured.sources.SOURCES`).
    rec : Recording
        The recording in its file unit.
    g : float
        Local gravity [m/s²].
    estimators : sequence of str
        Names from :data:`accelcal.registry.ESTIMATORS`.  An estimator the pose count
        does not allow raises :class:`~accelcal.errors.TooFewPosesError` (a configuration
        error, not a result).
    sections : dict, optional
        imucal section list (selects the Ferraris poses).
    pose_selection : {'section_list', 'all'}
    n_boot : int
        Bootstrap replicates (the same resampled poses for every estimator).
    seed : int
        Seed of the bootstrap; combined with the recording name.
    level : float
        Confidence level of the intervals.
    min_valid_fraction : float
        Fewest valid bootstrap replicates (fraction) for a bootstrap interval.
    static_kw : dict, optional
        Keyword arguments of :func:`accelcal.static.detect_static`.

    Returns
    -------
    MeasuredCalibration
    """
    src = source(name)
    conv = src.conversion
    _check_estimators(name, estimators)
    detected = detect_static_recording(rec, **(static_kw or {}))
    used, labels = select_poses(name, detected, sections, pose_selection)
    ps = pose_set(name, detected, used, labels)
    rng = np.random.default_rng([int(seed), zlib.crc32(name.encode())])
    idx = ev.bootstrap_indices(len(ps), int(n_boot), rng)

    param_rows, pose_rows, summary_rows = [], [], []
    boot, results = {}, {}
    for est in estimators:
        r, seconds = _calibrate_timed(name, est, ps, g, src.unit, conv)
        results[est] = r
        fit = _EstimatorFit(name, est, r, ps, g, src.unit)
        params_e, boot[est], interval = _parameter_rows(fit, idx, level, min_valid_fraction)
        param_rows += params_e
        pose_rows += _pose_rows(fit)
        summary_rows.append(_summary_row(fit, n_boot, interval, seconds))

    params = pd.DataFrame(param_rows)
    return MeasuredCalibration(
        recording=name, poses=poses_table(name, detected, used, labels, rec.t), params=params,
        pose_errors=pd.DataFrame(pose_rows), summary=pd.DataFrame(summary_rows),
        agreement=agreement_table(name, params, boot, level), nominal=nominal_table(name, params, conv, src.unit),
        results=results, pose_set=ps, detected=detected)


def check_section_list_estimators(name: str, estimators, sections, pose_selection: str) -> None:
    """A section list's six static positions (:data:`FERRARIS_STATIC`) allow bias-only
    estimators only: the configured estimators that need more poses raise
    :class:`~accelcal.errors.TooFewPosesError` naming the config key, before any work (the
    workflow's job checks this first, so that parsing the Snakefile imports no reproduction;
    :func:`calibrate_recording` refuses such a fit too, naming the recording)."""
    if sections is None or pose_selection != "section_list":
        return
    short = [e for e in estimators if e in ESTIMATORS and ESTIMATORS[e].min_poses > len(FERRARIS_STATIC)]
    if short:
        need = max(ESTIMATORS[e].min_poses for e in short)
        raise TooFewPosesError(f"measured.recordings.{name}.estimators: {', '.join(short)} need at least {need} "
                               f"poses, pose_selection 'section_list' gives the session's {len(FERRARIS_STATIC)} "
                               "static positions (bias-only estimators only)")


def _check_estimators(name: str, estimators) -> None:
    unknown = [e for e in estimators if e not in ESTIMATORS]
    if unknown:
        raise AccelcalError(f"{name}: unknown estimator(s) {', '.join(unknown)}; known: {', '.join(ESTIMATORS)}")


def _calibrate_timed(name: str, est: str, ps, g: float, unit: str, conv):
    """The CLI's calibration of the poses (accelcal.calibration) and its wall time [s]."""
    t0 = time.perf_counter()
    try:
        r = calibrate_poses(ps, g, est, unit=unit, conversion=conversion_for(est, conv))
    except AccelcalError as err:  # e.g. too few poses for the full model: name the recording
        raise type(err)(f"{name}, {est}: {err}") from None
    return r, time.perf_counter() - t0


class _EstimatorFit:
    """One estimator's calibration of a recording's poses, with what every table of it reads:
    the fit as a function of poses, the noise-predicted residual sigma, the χ² and the
    leave-one-pose-out errors."""

    def __init__(self, name: str, est: str, r, ps, g: float, unit: str):
        self.name, self.est, self.r, self.ps, self.g, self.unit = name, est, r, ps, g, unit
        self.e = estimator(est)
        self.fr = frame(r)
        self.fit = make_fit(est, self.fr)
        self.names = parameter_names(est)
        self.values = parameter_vector(r, self.fr)
        # residuals against the noise (the calibration's quality: accelcal.quality)
        self.sigma = ev.residual_sigma(self.fr.z, self.fr.mean_std, r.M, r.bias)
        self.chi = ev.Chi2(r.quality.chi2, r.quality.dof, r.quality.p_value)
        self.lo, self.lo_note = ev.lopo(self.fit, self.fr.z, g, self.e.min_poses)


def _parameter_rows(f: _EstimatorFit, idx, level: float, min_valid_fraction: float):
    """The parameter table's rows of one estimator, its bootstrap (samples, valid, interval
    method) and ``(valid fraction, interval method, seconds)`` of the bootstrap over poses."""
    r, fr, model = f.r, f.fr, f.e.model
    se = r.standard_errors
    se_v = _se_vector(se["bias"], se.get("scale_factors"), se.get("nonorthogonality_deg"), fr, model)
    nse = ev.noise_standard_errors(fr.z, fr.mean_std, r.M, r.bias, model)
    nse_v = _se_vector(nse[:3], nse[3:6], np.rad2deg(nse[6:9]), fr, model)
    t1 = time.perf_counter()
    samples, valid = ev.bootstrap(f.fit, lambda res, fr=fr: parameter_vector(res, fr), fr.z, idx,
                                  f.e.min_poses, len(f.names))
    boot_seconds = time.perf_counter() - t1
    frac = float(valid.mean()) if len(valid) else 0.0
    if len(valid) and frac >= min_valid_fraction:
        ci_lo, ci_hi = ev.percentile_ci(samples[valid], level)
        method = "bootstrap_percentile"
    else:
        ci_lo, ci_hi = ev.noise_interval(f.values, nse_v, f.chi, level)
        method = "linearised_noise"
    boot_se = np.nanstd(samples[valid], axis=0, ddof=1) if valid.sum() > 1 else np.full(len(f.names), np.nan)
    units = parameter_units(f.est, f.unit)
    rows = [{"recording": f.name, "estimator": f.est, "model": model, "parameter": p,
             "unit": units[k], "value": f.values[k], "se": se_v[k], "se_noise": nse_v[k],
             "boot_se": boot_se[k], "ci_low": ci_lo[k], "ci_high": ci_hi[k],
             "ci_method": method, "ci_level": level} for k, p in enumerate(f.names)]
    return rows, (samples, valid, method), (frac, method, boot_seconds)


def _pose_rows(f: _EstimatorFit) -> list[dict]:
    """The pose-error table's rows of one estimator: direction, residual, its prediction, LOPO."""
    r, ps = f.r, f.ps
    u = np.linalg.solve(r.M, (f.fr.z - r.bias).T).T
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    return [{"recording": f.name, "estimator": f.est, "pose": i, "label": ps.labels[i],
             "detected_pose": int(ps.detected[i]), "t_start": ps.t_start[i],
             "t_end": ps.t_end[i], "t_mid": ps.t_mid[i], "u_x": u[i, 0], "u_y": u[i, 1],
             "u_z": u[i, 2], "residual": r.residuals[i], "sigma_pred": f.sigma[i],
             "z_score": r.residuals[i] / f.sigma[i], "lopo_error": f.lo[i]} for i in range(len(ps))]


def _summary_row(f: _EstimatorFit, n_boot: int, interval: tuple, seconds: float) -> dict:
    """The summary table's row of one estimator (fit quality, LOPO, bootstrap, times)."""
    r, chi, qa, n = f.r, f.chi, f.r.quality, len(f.ps)
    frac, method, boot_seconds = interval
    dof_share = max(chi.dof, 0) / n
    pred_rms = float(np.sqrt(np.mean(f.sigma ** 2)))
    finite_lo = f.lo[np.isfinite(f.lo)]
    return {
        "recording": f.name, "estimator": f.est, "model": f.e.model, "g": f.g, "unit": f.unit,
        "n_poses": n, "n_params": f.e.n_parameters, "dof": chi.dof,
        "residual_rms": r.residual_rms, "predicted_rms": pred_rms,
        "rms_ratio": r.residual_rms / (pred_rms * np.sqrt(dof_share)) if dof_share > 0 else np.nan,
        "chi2": chi.chi2, "reduced_chi2": chi.reduced, "p_value": chi.p_value, "excess": chi.excess,
        "lopo_n": int(finite_lo.size),
        "lopo_rms": float(np.sqrt(np.mean(finite_lo ** 2))) if finite_lo.size else np.nan,
        "lopo_max_abs": float(np.max(np.abs(finite_lo))) if finite_lo.size else np.nan,
        "lopo_note": f.lo_note, "n_boot": int(n_boot), "boot_valid_fraction": frac, "ci_method": method,
        "distinct_orientations": qa.distinct_orientations, "coverage": qa.coverage,
        "warnings": " ".join(qa.flags), "fit_seconds": seconds, "boot_seconds": boot_seconds,
    }


def agreement_table(name: str, params: pd.DataFrame, boot: dict, level: float) -> pd.DataFrame:
    """Pairwise differences of the shared parameters of every pair of estimators.

    ``diff_ci_*`` is the paired-bootstrap percentile interval of the difference, over
    replicates valid for both (NaN if either estimator's intervals are not bootstrap ones).
    """
    rows = []
    ests = list(dict.fromkeys(params["estimator"]))
    for i, a in enumerate(ests):
        for b in ests[i + 1:]:
            pa = params[params.estimator == a].set_index("parameter")
            pb = params[params.estimator == b].set_index("parameter")
            shared = [p for p in pa.index if p in pb.index]
            sa, va, ma = boot[a]
            sb, vb, mb = boot[b]
            both = va & vb
            use_boot = ma.startswith("bootstrap") and mb.startswith("bootstrap") and both.any()
            for p in shared:
                ka, kb = list(pa.index).index(p), list(pb.index).index(p)
                d = pa.loc[p, "value"] - pb.loc[p, "value"]
                if use_boot:
                    dd = sa[both, ka] - sb[both, kb]
                    lo, hi = np.quantile(dd, [(1 - level) / 2, (1 + level) / 2])
                    se = float(np.std(dd, ddof=1)) if dd.size > 1 else np.nan
                else:
                    lo = hi = se = np.nan
                rows.append({"recording": name, "parameter": p, "unit": pa.loc[p, "unit"], "estimator_a": a,
                             "estimator_b": b, "diff": d, "diff_boot_se": se, "diff_ci_low": lo, "diff_ci_high": hi,
                             "diff_over_se_a": d / pa.loc[p, "se"] if pa.loc[p, "se"] > 0 else np.nan})
    return pd.DataFrame(rows, columns=["recording", "parameter", "unit", "estimator_a", "estimator_b", "diff",
                                       "diff_boot_se", "diff_ci_low", "diff_ci_high", "diff_over_se_a"])


def nominal_table(name: str, params: pd.DataFrame, conv, unit: str) -> pd.DataFrame:
    """Estimated sensitivities against the nominal ones (recordings in counts, full models)."""
    cols = ["recording", "estimator", "axis", "value", "ci_low", "ci_high", "nominal", "rel_diff_pct",
            "rel_ci_low_pct", "rel_ci_high_pct"]
    if unit != "counts":
        return pd.DataFrame(columns=cols)
    rows = []
    for k, a in enumerate(AXES):
        sel = params[params.parameter == f"sensitivity_{a}"]
        nom = float(conv.counts_per_unit[k])
        for _, r in sel.iterrows():
            rows.append({"recording": name, "estimator": r.estimator, "axis": a, "value": r.value,
                         "ci_low": r.ci_low, "ci_high": r.ci_high, "nominal": nom,
                         "rel_diff_pct": 100 * (r.value / nom - 1), "rel_ci_low_pct": 100 * (r.ci_low / nom - 1),
                         "rel_ci_high_pct": 100 * (r.ci_high / nom - 1)})
    return pd.DataFrame(rows, columns=cols)


__all__ = ["BIAS_PARAMETERS", "FULL_PARAMETERS", "Frame", "MeasuredCalibration", "PoseSet", "TABLES",
           "agreement_table", "calibrate_recording", "conversion_for", "frame", "make_fit", "nominal_table",
           "parameter_names", "parameter_vector", "pose_set", "poses_table", "select_poses"]

