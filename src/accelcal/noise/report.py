"""The noise of a static recording: Allan deviations and the IEEE noise terms, per sensor and axis.

For the accelerometer and (when recorded) the gyroscope of one static recording:

1. Overlapping Allan deviation at octave-spaced τ (:func:`accelcal.noise.allan.allan_variance`
   on the whole record; the grid stops where the white-FM equivalent degrees of freedom
   fall below ``min_edf``, 3 by default: τ_max ≈ a quarter of the record).
2. The five IEEE Std 952 terms fitted per axis by the Gamma maximum likelihood the
   discrepancy stochastic layer uses too (:mod:`accelcal.noise.allan_fit`, coefficients ≥ 0):
   quantization Q, white noise N (the noise density, ``u/√Hz``), bias instability B
   (flicker floor ``0.664 B``), random walk K (``u·s^-½ = u/s/√Hz``) and ramp R.  The fit
   is weighted by the edf of the fitted model itself (a Satterthwaite mix of each term's
   NIST SP 1065 edf, :func:`~accelcal.noise.allan_fit.model_edf`), refitted once.
   When the five terms cannot follow the data to within its sampling error (a real
   sensor's filter, a periodic disturbance), a model-error variance is estimated and
   added to every point's (:func:`~accelcal.noise.allan_fit.fit_avar_model_error`), so that no τ range dominates the fit by its
   degrees of freedom alone; the intervals then include the misfit.
3. Intervals.  Each Allan variance point is ``A_j χ²_ν/ν`` with ν the model's edf; the
   intervals come from the coefficients refitted to ``n_boot`` draws of the fitted
   model's points (a parametric bootstrap of the fit, fast because it redraws the Allan
   variances, not the time series; basic or percentile intervals, :func:`_term_table`).
   The overlapping estimates at neighbouring octaves are correlated (0.5 one octave apart
   for white noise, 0.9 for a random walk: each term's
   :attr:`~accelcal.noise.terms.NoiseTerm.octave_correlation`,
   measured by simulation); drawing them
   independently gave 84 % coverage for white noise at a stated 95 %, so the draws are
   correlated (a Gaussian copula, :func:`~accelcal.noise.allan_fit.bootstrap_fits`), and
   where terms overlap their variance is the coherent mix of the terms'
   (:func:`~accelcal.noise.allan_fit.model_edf`; the Satterthwaite mix understated it by up
   to 40 %).  Coverage at a stated 95 % (``tools/bench_noise_coverage.py``, 300 simulated
   axes of 2.9 h per configuration): white noise 0.95–0.97; quantization 0.96; a
   dominant flicker floor 0.96; a dominant random walk 0.94; terms absent from the data
   0.96–1.00; but a flicker floor under a dominant random walk 0.86, and where the
   flicker floor and the random walk hide each other (neither ever carries the Allan
   variance: the "masked" configuration) 0.88 for the flicker and 0.81 for the random
   walk (on 120 of these axes, 12 % of its intervals lay wholly below the truth).  On
   shorter records the random walk also trades with the ramp: on 22 min records
   (``snakemake noise``, 90 axes) a random walk dominating from τ = 30 s covered 0.78,
   the ramp taking part of it on most axes.  The
   bootstrap draws from the fitted model, and where the fit trades one term for the other
   the draws inherit the trade: read such terms as a pair (their sum at the τ they
   share is well determined).  A prototype inverting a bootstrap test per term (the
   model refitted with the term fixed on a grid, the estimate's rank among the refits of
   each) covered both at 0.98 on 120 of these axes, with intervals 1.4–1.6× wider, at six
   times the refits, and over-covered the others: not used.  The Allan-deviation error
   bars are the chi-square intervals of each point with the model's edf.
4. A term is *resolved* when it carries at least half of the model's Allan variance at
   some measured τ and its interval excludes zero; of an unresolved one only the upper
   bound is known, and a warning says whether the neighbouring terms mask it or how
   long a record would resolve it (the record reaches τ_max ≈ duration / 4).  Exports
   use an unresolved random walk's upper interval end and say so.

Static: a recording that moved is refused (:class:`~accelcal.errors.NotStaticError`):
the direction of the 1 s means of the accelerometer may not leave the median direction
by more than :data:`REFUSE_TILT_DEG`, nor the 1 s gyro means the median by more than
:data:`REFUSE_RATE`; smaller departures, noisy blocks (taps, vibration) and irregular
sampling are warnings.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import AccelcalError, NotStaticError
from ..formats.units_evidence import require_gyro_unit
from ..summary import Summary
from .allan import DEFAULT_MIN_EDF, AllanVariance, allan_variance
from .allan_fit import NoiseFit, bootstrap_fits, fit_avar_model_error, model_edf
from .avr import avr_lines
from .export import conversions, exported_values, report_dict
from .planner import DEFAULT_WIDTH, plan_lines
from .terms import TERMS, ieee_terms, model_avar

DEFAULT_LEVEL = 0.95
DEFAULT_N_BOOT = 400
#: Refuse / warn: largest angle [deg] of a 1 s mean accelerometer direction from the median one.
REFUSE_TILT_DEG, WARN_TILT_DEG = 3.0, 0.3
#: Refuse / warn: largest departure [rad/s] of a 1 s mean gyro rate from the median (0.05 rad/s ≈ 2.9 °/s).
REFUSE_RATE, WARN_RATE = 0.05, 0.005
#: A 1 s block whose variance exceeds this multiple of the median block variance is "noisy".
NOISY_BLOCK_FACTOR = 10.0
#: Largest relative departure of a time step from the median step that is not a gap.
MAX_STEP_JITTER = 0.5
#: Misfit of the five terms (relative, in Allan deviation) above which a warning says so.
MODEL_ERROR_WARN = 0.05
#: Share of the model's Allan variance a term must carry at some τ to be resolved.
RESOLVED_SHARE = 0.5


class NoiseAnalysisError(AccelcalError):
    """A recording or a setting the noise analysis cannot use."""


@dataclass(frozen=True)
class TermEstimate:
    """One fitted term of one axis: IEEE coefficient and its interval, in the sensor's unit."""

    value: float
    lo: float
    hi: float
    resolved: bool
    dominant_taus: tuple[float, float] | None   # measured τ range where the term carries ≥ half the AVAR

    def to_dict(self) -> dict:
        return {"value": self.value, "interval": [self.lo, self.hi], "resolved": self.resolved,
                "dominant_taus_s": list(self.dominant_taus) if self.dominant_taus else None}


@dataclass(frozen=True)
class SensorNoise:
    """Allan deviation and noise terms of one three-axis sensor."""

    sensor: str                         # 'accelerometer' or 'gyroscope'
    unit: str                           # data unit: 'm/s^2', 'rad/s' or 'counts'
    allan: AllanVariance
    edf: np.ndarray                     # (k, 3): edf of the fitted model at each τ
    adev_interval: np.ndarray           # (k, 3, 2)
    terms: tuple[dict, ...]             # per axis: {term id: TermEstimate}
    fits: tuple[NoiseFit, ...]
    boot_fits: tuple[np.ndarray, ...]   # per axis: (n_boot, 5) bootstrap coefficients
    model_error: tuple[float, ...]      # per axis: σ_m, the misfit of the five terms in ln AVAR (fit_ieee)

    def model_adev(self, taus) -> np.ndarray:
        """(len(taus), 3): Allan deviation of each axis's fitted model."""
        return np.column_stack([np.sqrt(f.avar(taus, self.allan.fs)) for f in self.fits])


@dataclass(frozen=True)
class NoiseReport:
    """The noise analysis of one static recording (see the module docstring)."""

    source: str
    fs: float
    n: int
    duration_s: float
    level: float
    n_boot: int
    seed: int
    sensors: dict
    static: dict
    warnings: tuple[str, ...] = ()
    notes: tuple[str, ...] = ()
    extra: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        return report_dict(self)


# --------------------------------------------------------------------------- analysis

    def summary(self, *, written_to=None, plan_width: float = DEFAULT_WIDTH,
                allan_variance_ros: dict | None = None) -> Summary:
        """The report in a few lines: what ``accelcal noise`` prints (its warnings apart).

        Per sensor the exported noise density and random walk, the data-sheet units, the
        record-length planner (``plan_width``: :mod:`accelcal.noise.planner`) and, where an
        allan_variance_ros reading of the same record (``allan_variance_ros``: ``{sensor:
        reading}``, :func:`accelcal.noise.avr.avr_reading`) would differ by more than 2x, why.
        """

        avr = allan_variance_ros or {}
        lines = [f"noise: {self.n} samples, {self.duration_s / 3600:.3g} h at {self.fs:.4g} Hz"]
        lines += [f"  read: {n}" for n in self.notes if n]
        differ = []
        for s in self.sensors.values():
            ex = [exported_values(s, j) for j in range(3)]
            lines.append(f"  {s.sensor}: noise density " + ", ".join(f"{e['noise_density']['value']:.3g}" for e in ex)
                         + f" {s.unit}/sqrt(Hz); random walk " + ", ".join(
                             f"{'<' if e['random_walk']['upper_bound'] else ''}{e['random_walk']['value']:.3g}"
                             for e in ex) + f" {ex[0]['random_walk']['unit']} (x, y, z)")
            quoted = _quoted(s)
            if quoted:
                lines.append(f"    {quoted}")
            lines += ["  " + line for line in plan_lines(s, self.duration_s, plan_width, self.level)]
            if s.sensor in avr:
                differ += avr_lines(s.sensor, s.unit, avr[s.sensor], [e["noise_density"]["value"] for e in ex],
                                    [e["random_walk"]["value"] for e in ex])
        lines += [f"  {line}" for line in differ]
        if written_to is not None:
            lines.append(f"  written to {written_to}")
        return Summary(lines)


def analyse_noise(rec, *, level: float = DEFAULT_LEVEL, n_boot: int = DEFAULT_N_BOOT, seed: int = 0,
                  min_edf: float = DEFAULT_MIN_EDF, allow_motion: bool = False, segments=None) -> NoiseReport:
    """Noise of a static :class:`~accelcal.recording.Recording` (accelerometer, and gyroscope if recorded).

    Parameters
    ----------
    rec : Recording
        ``acc`` in m/s² (or counts), ``gyro`` in rad/s or None, uniformly sampled.
    level : float
        Confidence level of the term intervals and the Allan-deviation error bars.
    n_boot : int
        Bootstrap draws of the fitted model (module docstring, step 3).
    seed : int
        Seeds the bootstrap (the report is deterministic).
    min_edf : float
        Smallest white-FM edf of the last τ of the grid.
    allow_motion : bool
        Analyse a recording that is not static (a warning instead of the refusal).
    segments : sequence of (start, stop), optional
        Sample ranges ``[start, stop)`` to analyse, e.g. the rests of a calibration session
        or a static stretch of a longer log: each is checked to be static on its own (the
        orientation may change between them) and their Allan variances are pooled
        (:mod:`accelcal.noise.allan`); default the whole recording.

    Raises
    ------
    NotStaticError
        The sensor moved (one line: how much, where, and what to record instead).
    NoiseAnalysisError
        Too short, a constant axis, bad settings.
    UndecidedUnitError
        A gyro whose unit neither the file nor the user states: a static record cannot
        decide it (:mod:`accelcal.formats.units_evidence`).
    """
    _check_request(rec, level, n_boot)
    t = np.asarray(rec.t, dtype=float)
    fs = 1.0 / float(np.median(np.diff(t)))
    parts = _parts(segments, len(t))
    warnings, notes = [], list(rec.notes)
    static = _static_parts(rec, parts, fs, warnings)
    if static["refuse"] and not allow_motion:
        raise NotStaticError(f"{rec.source}: not a static recording: {static['refuse']}; the noise analysis needs the "
                             "sensor at rest in one orientation for the whole recording (cut the static part out: "
                             "--start/--end, or its rests: --intervals)")
    warnings += static["warnings"] + ([f"not static ({static['refuse']}): analysed anyway"] if static["refuse"] else [])
    sensors = _sensors(rec, parts, fs, level, n_boot, seed, min_edf)
    duration = sum(float(t[b - 1] - t[a]) + 1.0 / fs for a, b in parts)
    if segments is not None:
        notes.append(_stretches_note(t, parts, fs, duration))
    for s in sensors.values():
        warnings += resolution_warnings(s, duration)
    return NoiseReport(source=str(rec.source), fs=fs, n=int(sum(b - a for a, b in parts)), duration_s=duration, level=float(level),
                       n_boot=int(n_boot), seed=int(seed), sensors=sensors, static=static, warnings=tuple(warnings),
                       notes=tuple(notes))



def _check_request(rec, level: float, n_boot: int) -> None:
    """Refuse in one line what no analysis can answer: a bad level or bootstrap size, runs
    recorded apart, a gyro whose unit no one states."""
    if not 0 < level < 1 or n_boot < 50:
        raise NoiseAnalysisError(f"need 0 < level < 1 and n_boot >= 50, got level={level}, n_boot={n_boot}")
    if getattr(rec, "runs", None) is not None and len(rec.runs) > 1:
        raise NoiseAnalysisError(f"{rec.source}: {len(rec.runs)} runs recorded apart: one Allan deviation needs one "
                                 "uninterrupted record; analyse them one at a time (--variable NAME)")
    require_gyro_unit(rec, "a static record")  # no motion decides rad/s from deg/s: 57x


def _sensors(rec, parts, fs: float, level: float, n_boot: int, seed: int, min_edf) -> dict:
    """Each recorded sensor's analysis of the stretches ``parts``, each with its own random
    stream from ``seed``."""
    seeds = np.random.SeedSequence(int(seed)).spawn(2)
    cut = [slice(a, b) for a, b in parts]
    sensors = {}
    if rec.acc is not None:  # None: a gyro-only recording
        sensors["accelerometer"] = _sensor("accelerometer", [rec.acc[c] for c in cut], rec.unit or "counts", fs,
                                           level, n_boot, seeds[0], min_edf)
    if rec.gyro is not None:
        sensors["gyroscope"] = _sensor("gyroscope", [rec.gyro[c] for c in cut], rec.gyro_unit, fs, level, n_boot,
                                       seeds[1], min_edf)
    return sensors


def _stretches_note(t, parts, fs: float, duration: float) -> str:
    """The note saying which stretches were analysed, their Allan variances pooled."""
    longest = max(float(t[b - 1] - t[a]) + 1.0 / fs for a, b in parts)
    return (f"analysed {len(parts)} stretch(es) of the recording, {duration:.4g} s in all (the longest "
            f"{longest:.4g} s), their Allan variances pooled: t = " + ", ".join(
                f"{t[a] - t[0]:.4g}-{t[b - 1] - t[0]:.4g} s" for a, b in parts[:6])
            + (" ..." if len(parts) > 6 else ""))


def _parts(segments, n: int) -> list[tuple[int, int]]:
    """The sample ranges analysed: the whole recording, or the given ones (each at least 4 samples, inside it)."""
    if segments is None:
        return [(0, n)]
    parts = [(int(a), int(b)) for a, b in segments]
    if not parts:
        raise NoiseAnalysisError("no stretch of the recording to analyse (the intervals are empty)")
    for a, b in parts:
        if not 0 <= a < b <= n or b - a < 4:
            raise NoiseAnalysisError(f"the stretch of samples {a}-{b} is not a range of at least 4 samples inside "
                                     f"the recording's {n}")
    return parts


def _static_parts(rec, parts, fs: float, warnings: list) -> dict:
    """:func:`static_check` of each stretch (the orientation may change between them), merged."""
    checks = []
    for k, (a, b) in enumerate(parts):
        c = static_check(None if rec.acc is None else rec.acc[a:b], None if rec.gyro is None else rec.gyro[a:b], fs)
        tag = "" if len(parts) == 1 else f"stretch {k + 1} (t = {rec.t[a] - rec.t[0]:.4g} s): "
        c["refuse"] = c["refuse"] and tag + c["refuse"]
        c["warnings"] = [tag + w for w in c["warnings"]]
        warnings += [tag + w for w in sampling_warnings(np.asarray(rec.t[a:b], dtype=float))] if b - a > 2 else []
        checks.append(c)
    if len(checks) == 1:
        return checks[0]
    rates = [c["max_rate_departure"] for c in checks if c["max_rate_departure"] is not None]
    return {"block_s": checks[0]["block_s"], "max_tilt_deg": max(c["max_tilt_deg"] for c in checks),
            "noisy_blocks": sum(c["noisy_blocks"] for c in checks), "max_rate_departure": max(rates, default=None),
            "refuse": next((c["refuse"] for c in checks if c["refuse"]), None),
            "warnings": [w for c in checks for w in c["warnings"]], "stretches": len(checks)}


def _sensor(name, segments, unit, fs, level, n_boot, seed_seq, min_edf) -> SensorNoise:
    x = [np.asarray(s, dtype=float) for s in segments]
    if not all(np.all(np.isfinite(s)) for s in x):
        raise NoiseAnalysisError(f"the {name} holds non-finite values")
    allan = allan_variance(x, fs, min_edf=min_edf)
    if allan.taus.size < 5:
        raise NoiseAnalysisError(f"the recording reaches only {allan.taus.size} octaves of tau "
                                 f"({allan.taus[-1]:.3g} s); the five noise terms need at least 5: record longer "
                                 "(or give a longer static stretch)")
    if np.any(allan.avar <= 0):
        axis = "xyz"[int(np.argmax(np.any(allan.avar <= 0, axis=0)))]
        raise NoiseAnalysisError(f"the {name}'s {axis} axis is constant (zero Allan variance): a stuck sensor?")
    rng = np.random.default_rng(seed_seq)
    fits, boots, edfs, terms, errors = [], [], [], [], []
    for j in range(x[0].shape[1]):
        fit, edf, sigma_m = fit_ieee(allan, j)
        boot = bootstrap_fits(fit, allan, edf, sigma_m, n_boot, rng)
        fits.append(fit)
        boots.append(boot)
        edfs.append(model_edf(allan, fit))
        errors.append(sigma_m)
        terms.append(_term_table(fit, boot, allan.taus, fs, level))
    edf = np.column_stack(edfs)
    lo, hi = allan.adev_interval(level, edf)
    return SensorNoise(sensor=name, unit=unit, allan=allan, edf=edf, adev_interval=np.stack([lo, hi], axis=-1),
                       terms=tuple(terms), fits=tuple(fits), boot_fits=tuple(boots), model_error=tuple(errors))


def fit_ieee(allan: AllanVariance, j: int, max_iter: int = 10) -> tuple[NoiseFit, np.ndarray, float]:
    """The five IEEE terms (:func:`~accelcal.noise.terms.ieee_terms`) fitted to axis ``j`` with the
    model error the fit leaves (:func:`accelcal.noise.allan_fit.fit_avar_model_error`): (fit, edf of
    each τ used by the fit, model error σ_m)."""
    return fit_avar_model_error(allan, allan.avar[:, j], ieee_terms(), max_iter=max_iter)


def _term_table(fit: NoiseFit, boot: np.ndarray, taus, fs: float, level: float) -> dict:
    """Each term's estimate and interval: the basic bootstrap interval ``[2θ̂ − q_hi, 2θ̂ − q_lo]`` (which
    corrects the shift of the refitted values, e.g. a random walk refitted 8 % low) where the bootstrap
    puts less than ``(1 − level)/2`` of its mass at zero, else the percentile interval ``[q_lo, q_hi]``
    (a term at or near its bound of zero).  Measured: the basic interval covered a dominant random
    walk 93 % of the time at 95 % where the percentile interval covered it 72 %; at the bound the
    basic interval collapses onto zero."""
    coef = fit.coefficients
    lo_q, hi_q = 100 * (0.5 - level / 2), 100 * (0.5 + level / 2)
    parts = np.array([c * TERMS[k].basis(taus, fs) for k, c in zip(fit.term_ids, fit.c)])
    share = parts / np.maximum(parts.sum(axis=0), 1e-300)
    out = {}
    for i, k in enumerate(fit.term_ids):
        dom = share[i] >= RESOLVED_SHARE
        lo, hi = (float(np.percentile(boot[:, i], q)) for q in (lo_q, hi_q))
        if np.mean(boot[:, i] <= 0) < (1 - level) / 2:
            lo, hi = max(2 * coef[k] - hi, 0.0), 2 * coef[k] - lo
        # resolved: the term carries the model somewhere, and its interval excludes zero
        out[k] = TermEstimate(value=coef[k], lo=lo, hi=hi, resolved=bool(dom.any() and lo > 0),
                              dominant_taus=(float(taus[dom][0]), float(taus[dom][-1])) if dom.any() else None)
    return out


# --------------------------------------------------------------------------- checks


def sampling_warnings(t: np.ndarray) -> list[str]:
    """Gaps and jitter of the time stamps: the Allan deviation assumes uniform sampling."""
    dt = np.diff(t)
    step = float(np.median(dt))
    gaps = np.flatnonzero(dt > (1 + MAX_STEP_JITTER) * step)
    out = []
    if gaps.size:
        lost = int(np.sum(np.round(dt[gaps] / step) - 1))
        out.append(f"{gaps.size} gaps in the time stamps (about {lost} samples missing, the longest "
                   f"{float(dt[gaps].max()):.3g} s at t = {float(t[gaps[np.argmax(dt[gaps])]] - t[0]):.1f} s): the "
                   "samples are analysed as if uniformly spaced")
    jitter = float(np.percentile(np.abs(dt / step - 1), 99))
    if jitter > 0.1:
        out.append(f"time stamps jitter by {100 * jitter:.0f} % of the sample period (99th percentile): analysed as "
                   "uniformly sampled at the median rate")
    return out


def _blocks(x: np.ndarray, fs: float) -> np.ndarray:
    w = max(int(round(fs)), 10)
    k = len(x) // w
    return x[: k * w].reshape(k, w, -1) if k >= 3 else x[None]


def static_check(acc, gyro, fs: float) -> dict:
    """Did the sensor move?  Tilt of the 1 s accelerometer means, departure of the 1 s gyro means, noisy blocks
    (of the accelerometer; of the gyro when there is no accelerometer)."""
    b = _blocks(np.asarray(acc if acc is not None else gyro, dtype=float), fs)
    means = b.mean(axis=1)
    ref = np.median(means, axis=0)
    cos = means @ ref / (np.linalg.norm(means, axis=1) * np.linalg.norm(ref) + 1e-300)
    tilt = np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))) if acc is not None else np.zeros(len(means))
    var = b.var(axis=1).sum(axis=1)
    noisy = int(np.sum(var > NOISY_BLOCK_FACTOR * np.median(var)))
    out = {"block_s": b.shape[1] / fs, "max_tilt_deg": float(tilt.max()), "noisy_blocks": noisy,
           "max_rate_departure": None, "refuse": None, "warnings": []}
    where = float(np.argmax(tilt) * b.shape[1] / fs)
    if tilt.max() > REFUSE_TILT_DEG:
        out["refuse"] = f"the accelerometer's direction changed by {tilt.max():.3g} deg (at t = {where:.0f} s)"
    elif tilt.max() > WARN_TILT_DEG:
        out["warnings"].append(f"the accelerometer's 1 s mean direction wanders by up to {tilt.max():.2g} deg (at t = "
                               f"{where:.0f} s): a slow tilt or a large bias drift is in the long-tau terms")
    if gyro is not None:
        g = _blocks(np.asarray(gyro, dtype=float), fs).mean(axis=1)
        dep = np.linalg.norm(g - np.median(g, axis=0), axis=1)
        out["max_rate_departure"] = float(dep.max())
        at = float(np.argmax(dep) * b.shape[1] / fs)
        if dep.max() > REFUSE_RATE and out["refuse"] is None:
            out["refuse"] = (f"the gyro's 1 s mean rate departs from its median by {dep.max():.3g} rad/s "
                             f"(at t = {at:.0f} s)")
        elif dep.max() > WARN_RATE:
            out["warnings"].append(f"the gyro's 1 s mean rate departs from its median by up to {dep.max():.2g} rad/s "
                                   f"(at t = {at:.0f} s)")
    if noisy:
        out["warnings"].append(f"{noisy} of {len(var)} 1 s blocks are more than {NOISY_BLOCK_FACTOR:g}x noisier "
                               "than the median block (taps or vibration): they raise the short-tau Allan deviation")
    return out


def resolution_warnings(s: SensorNoise, duration: float) -> list[str]:
    """A warning per unresolved term that asks for one (:attr:`~accelcal.noise.terms.NoiseTerm.warn_unresolved`:
    the random walk and the bias instability, which a short record cannot see), and per axis the five
    terms describe only roughly."""
    out = []
    if max(s.model_error) / 2 > MODEL_ERROR_WARN:
        out.append(f"{s.sensor}: the five IEEE terms follow the Allan deviation only to about "
                   f"{', '.join(f'{50 * e:.0f}' for e in s.model_error)} % (x, y, z), more than its sampling error "
                   "(a feature they lack: the sensor's filter, a periodic disturbance...); the intervals include this "
                   "misfit")
    tau_max = float(s.allan.taus[-1])
    for k in (k for k in s.terms[0] if TERMS[k].warn_unresolved):
        axes = [a for a, terms in zip("xyz", s.terms) if not terms[k].resolved]
        if not axes:
            continue
        need = [needed_tau(s.fits[i], k, s.allan.fs, s.terms[i][k].hi) for i, a in enumerate("xyz") if a in axes]
        need = min((x for x in need if np.isfinite(x)), default=math.inf)
        if need <= tau_max:  # it would show within the record: the neighbouring terms mask it
            how = ("; within the measured tau the data do not tell it from zero (the neighbouring terms, or the few "
                   "degrees of freedom of the longest tau)")
        elif np.isfinite(need):  # two octaves of tau beyond where the term (at its upper bound) would take over
            how = (f"; at the upper end of its interval it would carry half the Allan variance from tau = {need:.3g} s,"
                   f" so a record of about {4 * need * duration / tau_max / 3600:.2g} h would resolve it")
        else:
            how = ""
        out.append(f"{s.sensor} {', '.join(axes)}: {k} is not resolved by this record ({duration / 3600:.3g} h, tau "
                   f"up to {tau_max:.3g} s){how}; only its upper bound is known"
                   + (" (the exports use it)" if TERMS[k].exported_as else ""))
    return out


def needed_tau(fit: NoiseFit, term: str, fs: float, value: float | None = None) -> float:
    """Smallest τ at which ``term`` (at ``value``, default its fitted one) would carry half the model's
    Allan variance (inf if never, within 10⁸ s)."""
    c = dict(zip(fit.term_ids, fit.c))
    if value is not None:
        c[term] = float(value) ** 2
    if c.get(term, 0.0) <= 0:
        return math.inf
    taus = np.logspace(-3, 8, 400)
    part = c[term] * TERMS[term].basis(taus, fs)
    total = model_avar({k: math.sqrt(v) for k, v in c.items()}, taus, fs)
    ok = part >= RESOLVED_SHARE * total
    return float(taus[np.argmax(ok)]) if ok.any() else math.inf


def _quoted(s) -> str:
    """The data-sheet units of the white noise and the flicker floor (the JSON's ``conversions``), x, y, z."""

    c = [conversions(s.sensor, s.unit, terms) for terms in s.terms]
    if not c[0]:
        return ""
    names = {"angle_random_walk_deg_sqrt_h": ("angle random walk", "deg/sqrt(h)"),
             "velocity_random_walk_m_s_sqrt_h": ("velocity random walk", "m/s/sqrt(h)"),
             "bias_instability_floor_deg_h": ("bias instability (0.664 B)", "deg/h"),
             "bias_instability_floor_mg": ("bias instability (0.664 B)", "mg")}
    return "; ".join(f"{names[k][0]} " + ", ".join(f"{x[k]:.3g}" for x in c) + f" {names[k][1]}"
                     for k in c[0] if k in names) + " (x, y, z)"


__all__ = ["DEFAULT_LEVEL", "DEFAULT_N_BOOT", "NoiseAnalysisError", "NoiseReport", "SensorNoise",
           "TermEstimate", "analyse_noise", "fit_ieee", "needed_tau",
           "resolution_warnings", "sampling_warnings", "static_check"]
