"""Noise profiles of the discrepancy benchmark: the sensor noise a simulated session carries.

A profile is a noise model per axis in the session's data unit (raw counts), added to the
whole time series (rests and motions: a bias wander does not pause while the sensor is
moved) before the samples are rounded to integer counts.  Three kinds:

* **parametric** (config ``discrepancy.benchmark.profiles``): white noise of
  ``noise_counts`` per sample (the session's, unless the profile sets its own) plus
  terms of the stochastic layer's library (:data:`accelcal.noise.TERMS`)
  whose sizes are given in units of ``σ_pm``, the white noise of one pose mean
  (``noise_counts / sqrt(samples of a trimmed rest)``; 0.141 counts for the Xsens-like
  session):

  - ``gauss_markov: [[k, T_c], ...]``: one first-order Gauss–Markov bias per pair, of
    standard deviation ``k σ_pm`` and correlation time ``T_c`` seconds (``session``: the
    session's length);
  - ``bias_instability: k``: flicker bias whose Allan floor ``0.664 B`` is ``k σ_pm``;
  - ``random_walk: k``: rate random walk whose Allan deviation at the session length,
    ``K sqrt(T_s/3)``, is ``k σ_pm``;
  - ``placement: k``: a per-placement offset, ``k σ_pm`` per axis, drawn anew for every
    pose and constant over it (from the start of its rest to the start of the next: a
    sensor set down by hand, a mount that settles differently each time), independent
    between the axes: what the FXOS8700 sessions carry (20-35 ``σ_pm`` there);
  - ``noise_counts: s``: white noise of ``s`` counts per sample instead of the session's.
    Below about half a count the rounding to integer counts no longer averages out: a
    pose mean keeps a bias that depends on where the true value falls between two
    counts, ``Σ_k (−1)^k e^{−2π²k²s²} sin(2πk f)/(πk)`` (the Fourier series of the
    rounding error smoothed by the Gaussian noise), of variance
    ``Σ_k e^{−4π²k²s²}/(2π²k²)`` over a uniform fraction ``f``, which no sample scatter
    reveals: the "raw counts with rounding" profile.

* **fitted** (``fitted: xsens_mti``, ``xsens_mti_joint`` or ``adis16405``): the noise
  model fitted to a real sensor, in counts: the Xsens session's stochastic-layer fit of its
  rests (results/discrepancy/measured/xsens_mti.json, already in counts), the joint
  model's bias wander estimated from the Xsens pose residuals with the white noise of its
  rests (:func:`joint_source`), or the ADIS16405
  model fitted to its 2.78 h Allan deviation (:mod:`accelcal_repro.discrepancy.adis`),
  rescaled so that its white term equals the session's (the ratio of wander to white
  noise is the ADIS's own).
* **real** (``real: adis16405``): windows of the ADIS16405 recording itself (demeaned,
  same rescaling), no model at all.  The record is cut into disjoint windows of session
  length; those holding a transient are left out (below), and replicate ``r`` takes the
  ``r mod W``-th clean window (``W`` clean windows) with the axis permutation
  ``⌊r / W⌋ mod 6``, each recording with its own sensor and temperature.  Recordings that
  share a window are correlated, which the scoring's confidence interval accounts for
  (Kish's effective sample size, :mod:`.scoring`); the benchmark gives such a profile its
  own number of effect-free recordings (``seeds_none_real``: at 576, each window and
  permutation three times, the outcomes of one window correlate by about 0.005, so the
  576 count as about 530).

  **Screen of the record (pre-registered).**  A real record can hold transients, and a
  window that holds one is not effect-free: it is a disturbed pose.  The windows a real
  profile draws from are those that :mod:`.record_screen` finds clean.

Every profile also gives the covariance of the pose means it implies
(:func:`pose_mean_covariance`), from which the benchmark sizes its hidden effects in
units of the minimum detectable effect of a test that knows the true noise
(:mod:`accelcal_repro.discrepancy.benchmark`).  Time-correlated terms enter through
their pose-difference variances ``D`` (:func:`accelcal.discrepancy.stochastic.pose_difference_variance`)
as ``−½ P D P`` (``P`` centres over the poses): the covariance of each pose-mean error
about the session's mean, which differs from the full covariance only by a common
offset per axis that the bias absorbs.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace
from itertools import permutations

import numpy as np

from accelcal.discrepancy.stochastic import pose_difference_variance
from accelcal.discrepancy.wander_process import process_in, wander_named
from accelcal.errors import AccelcalError
from accelcal.noise import TERMS, simulate_noise

from .record_screen import RecordScreen, clean_windows, record_windows, transient_scan

#: Allan floor of flicker noise per unit B: sqrt(2 ln 2 / π).
FLICKER_FLOOR = math.sqrt(2 * math.log(2) / math.pi)
#: Names of the real noise records a profile can draw from.
REAL_RECORDS = ("adis16405",)
#: Sources of fitted profiles.
FITTED_SOURCES = ("xsens_mti", "xsens_mti_joint", "adis16405")
AXIS_PERMUTATIONS = tuple(permutations(range(3)))


class ProfileError(AccelcalError):
    """A noise profile that cannot be built (bad config, missing fit)."""


@dataclass(frozen=True)
class NoiseProfile:
    """The noise of a simulated session, per axis, in counts.

    Attributes
    ----------
    name : str
    white : tuple of 3 float
        Standard deviation of the white term per sample, per axis [counts].
    components : tuple of (term id, tuple of 3 values)
        Further noise terms, each simulated on its own stream; a value is the IEEE 952
        coefficient in counts (``(coefficient, shape)`` for ``gauss_markov`` and
        ``sinusoid``), per axis.
    real : str
        Name of a real noise record (:data:`REAL_RECORDS`) the simulation draws
        windows from ('' for none); ``white`` and ``components`` are then the record's
        fitted model, used only for the covariance.
    real_scale : tuple of 3 float
        Record unit → counts, per axis.
    real_windows : tuple of int
        Indices of the record's windows of session length that the simulation may use
        (the clean ones, :func:`clean_windows`); empty: every window.
    kind : {'parametric', 'fitted', 'real'}
    description : str
    axis_correlation : float
        Correlation ``φ`` between the axes of every component (a common-mode share, as the
        wander null's joint model estimates it: :func:`accelcal.discrepancy.wander.axis_gram`);
        it needs the same component on every axis.  0: independent axes.
    placement : tuple of 3 float
        Standard deviation of the per-placement offset per axis [counts] (0: none); the
        simulation needs the poses' windows (:func:`placement_offsets`).
    """

    name: str
    white: tuple
    components: tuple = ()
    real: str = ""
    real_scale: tuple = (1.0, 1.0, 1.0)
    kind: str = "parametric"
    description: str = ""
    real_windows: tuple = ()
    axis_correlation: float = 0.0
    placement: tuple = (0.0, 0.0, 0.0)

    def model(self, axis: int, fs: float) -> dict:
        """The axis's noise model as :func:`accelcal.noise.model_avar` takes it
        (one entry per term; repeated terms, e.g. several Gauss–Markov biases, keep only the
        first: use :attr:`components` for the full model)."""
        out = {"white": self.white[axis] / math.sqrt(fs)}
        for term, values in self.components:
            out.setdefault(term, values[axis])
        return out

    def to_dict(self) -> dict:
        d = asdict(self)
        d["components"] = [[t, [list(v) if isinstance(v, (tuple, list)) else v for v in vals]]
                           for t, vals in self.components]
        return d

    @classmethod
    def from_dict(cls, d: dict) -> NoiseProfile:
        comps = tuple((t, tuple(tuple(v) if isinstance(v, list) else float(v) for v in vals))
                      for t, vals in d.get("components", ()))
        return cls(d["name"], tuple(float(v) for v in d["white"]), comps, d.get("real", ""),
                   tuple(float(v) for v in d.get("real_scale", (1.0, 1.0, 1.0))), d.get("kind", "parametric"),
                   d.get("description", ""), tuple(int(k) for k in d.get("real_windows", ())),
                   float(d.get("axis_correlation", 0.0)),
                   tuple(float(v) for v in d.get("placement", (0.0, 0.0, 0.0))))


# --------------------------------------------------------------------------- building profiles


def pose_mean_white(session) -> float:
    """``σ_pm``: white noise of one pose mean of the session [counts] (trimmed rest, rounding included)."""
    n = int(round((session.rest_s - 2 * session.trim_s) * session.rate))
    return math.sqrt(session.noise_counts ** 2 + 1.0 / 12.0) / math.sqrt(n)


def session_length(session) -> float:
    """Length of the simulated session [s]."""
    return session.init_rest_s + (session.n_poses - 1) * (session.move_s + session.rest_s)


def _parametric(name: str, spec: dict, session) -> NoiseProfile:
    known = {"noise_counts", "gauss_markov", "bias_instability", "random_walk", "placement", "description"}
    bad = sorted(set(spec) - known)
    if bad:
        raise ProfileError(f"profile {name}: unknown keys {bad} (known: {', '.join(sorted(known))})")
    white = float(spec.get("noise_counts", session.noise_counts))
    spm = pose_mean_white(session)
    ts = session_length(session)
    comps = []
    for k, tc in spec.get("gauss_markov", ()):
        tc = ts if tc == "session" else float(tc)
        comps.append(("gauss_markov", ((k * spm, tc),) * 3))
    if "bias_instability" in spec:
        comps.append(("bias_instability", (spec["bias_instability"] * spm / FLICKER_FLOOR,) * 3))
    if "random_walk" in spec:
        comps.append(("random_walk", (spec["random_walk"] * spm * math.sqrt(3.0 / ts),) * 3))
    return NoiseProfile(name, (white,) * 3, tuple(comps), kind="parametric", description=spec.get("description", ""),
                        placement=(float(spec.get("placement", 0.0)) * spm,) * 3)


def _from_model(name: str, models: list[dict], fs: float, scale, kind: str, real: str, description: str):
    """Profile from per-axis library models ``{term: value}`` in the record's unit, times ``scale`` per axis."""
    white, comps = [], {}
    for a, m in enumerate(models):
        white.append(scale[a] * m["white"] * math.sqrt(fs))
        for term, v in m.items():
            if term == "white":
                continue
            vv = (scale[a] * v[0], v[1]) if TERMS[term].shape_key else scale[a] * v
            comps.setdefault(term, [0.0 if not TERMS[term].shape_key else (0.0, v[1])] * 3)[a] = vv
    return NoiseProfile(name, tuple(white), tuple((t, tuple(v)) for t, v in comps.items()),
                        real=real, real_scale=tuple(float(s) for s in scale), kind=kind, description=description)


def build_profiles(specs, session, *, fitted: dict | None = None, records: dict | None = None,
                   screen: RecordScreen | None = None) -> dict[str, NoiseProfile]:
    """Every configured profile, resolved to counts, in config order.

    Parameters
    ----------
    specs : sequence of dict
        Config ``discrepancy.benchmark.profiles``: ``[{name: ..., **spec}]`` (module docstring).
    session : Session
    fitted : dict, optional
        ``{source: {"models": [3 per-axis models {term: value}], "fs": Hz, "unit_to_counts":
        float or 3 floats, "white_match": bool}}`` for the fitted and real profiles.
    records : dict, optional
        ``{name: record (n, 3)}``: the real records, screened with ``screen``.
    screen : RecordScreen, optional
        The transient screen of the real records (module docstring); with it, a real
        profile needs its record and keeps only the clean windows
        (:attr:`NoiseProfile.real_windows`); without it, every window.
    """
    fitted = fitted or {}
    out = {}
    for spec in specs:
        spec = dict(spec)
        name = spec.pop("name", None)
        if not name or name in out:
            raise ProfileError(f"every profile needs a distinct name; got {name!r}")
        src = spec.get("fitted") or spec.get("real")
        if src is None:
            out[name] = _parametric(name, spec, session)
            continue
        if set(spec) - {"fitted", "real", "description"} or ("fitted" in spec and "real" in spec):
            raise ProfileError(f"profile {name}: 'fitted' or 'real' stands alone (got {sorted(spec)})")
        if src not in FITTED_SOURCES or (spec.get("real") and src not in REAL_RECORDS):
            raise ProfileError(f"profile {name}: unknown source {src!r} (fitted: {', '.join(FITTED_SOURCES)}; "
                               f"real: {', '.join(REAL_RECORDS)})")
        if src not in fitted:
            raise ProfileError(f"profile {name}: no noise model of {src} was given to the benchmark")
        f = fitted[src]
        fs = float(f["fs"])
        scale = np.broadcast_to(np.asarray(f.get("unit_to_counts", 1.0), float), (3,)).copy()
        if f.get("white_match", False):  # rescale so that the white term is the session's
            scale = np.array([session.noise_counts / (m["white"] * math.sqrt(fs)) for m in f["models"]])
        kind = "real" if spec.get("real") else "fitted"
        prof = _from_model(name, f["models"], fs, scale, kind, src if kind == "real" else "",
                           spec.get("description", f.get("description", "")))
        prof = replace(prof, axis_correlation=float(f.get("axis_correlation", 0.0)),
                       placement=tuple(float(f.get("placement", 0.0)) * scale))
        if kind == "real" and screen is not None:
            prof = replace(prof, real_windows=screened_windows(src, records, fs, session.n_samples, screen))
        out[name] = prof
    return out


def screened_windows(name: str, records: dict | None, fs: float, n: int, screen: RecordScreen) -> tuple[int, ...]:
    """The clean windows of ``n`` samples of record ``name`` (:func:`transient_scan`, :func:`clean_windows`)."""
    if not records or name not in records:
        raise ProfileError(f"the record screen needs the {name} noise record")
    rec = records[name]
    kept = clean_windows(len(rec), n, transient_scan(rec, fs, screen))
    if not kept:
        raise ProfileError(f"the record screen leaves no clean window of {n} samples in the {name} record")
    return kept


# --------------------------------------------------------------------------- simulation


def usable_windows(profile: NoiseProfile, n_record: int, n: int) -> tuple[int, ...]:
    """The windows of ``n`` samples of the record a real profile draws from: its clean ones, else every one."""
    w = record_windows(n_record, n)
    if w < 1:
        raise ProfileError(f"the {profile.real} record ({n_record} samples) is shorter than a session ({n})")
    if not profile.real_windows:
        return tuple(range(w))
    if max(profile.real_windows) >= w:  # screened for another session length or record
        raise ProfileError(f"profile {profile.name}: window {max(profile.real_windows)} is beyond the {w} windows "
                           f"of {n} samples in the {profile.real} record")
    return tuple(profile.real_windows)


def window_of(profile: NoiseProfile, replicate: int, n_record: int, n: int) -> tuple[int, tuple]:
    """Record window and axis permutation of replicate ``replicate`` of a real profile (module docstring)."""
    wins = usable_windows(profile, n_record, n)
    r = int(replicate)
    return wins[r % len(wins)], AXIS_PERMUTATIONS[(r // len(wins)) % len(AXIS_PERMUTATIONS)]


def independent_recordings(profile: NoiseProfile, n_recordings: int, n_record: int | None, n: int) -> int:
    """How many of ``n_recordings`` replicates carry independent noise (real profiles reuse windows)."""
    if not profile.real or n_record is None:
        return n_recordings
    return min(n_recordings, len(usable_windows(profile, n_record, n)))


def placement_offsets(profile: NoiseProfile, rng: np.random.Generator, starts, n: int) -> np.ndarray:
    """The per-placement offsets of ``profile`` on a session of ``n`` samples whose poses start
    at samples ``starts`` (n_poses,): each pose's offset from its start to the next pose's
    (the motion between them included), shape (n, 3) [counts]; zeros without one.  Axes
    correlated by :attr:`NoiseProfile.axis_correlation`, like the other components."""
    sd = np.asarray(profile.placement, float)
    out = np.zeros((n, 3))
    if not np.any(sd > 0):
        return out
    k = len(starts)
    draws = rng.standard_normal((k, 4))
    phi = float(profile.axis_correlation)
    offsets = (math.sqrt(1.0 - phi) * draws[:, :3] + math.sqrt(phi) * draws[:, 3:]) * sd[None, :]
    edges = np.append(np.asarray(starts, int), n)
    for i in range(k):
        out[edges[i]:edges[i + 1]] = offsets[i]
    return out


def simulate_profile(profile: NoiseProfile, rng: np.random.Generator, n: int, fs: float, *, replicate: int = 0,
                     records: dict | None = None) -> np.ndarray:
    """Noise of ``profile`` for a session of ``n`` samples, shape (n, 3) [counts], not rounded.

    Parametric and fitted profiles: white noise plus every component, each component and
    axis on its own stream spawned from ``rng`` (the per-placement offset apart: it needs
    the poses, :func:`placement_offsets`).  Real profiles: the ``replicate mod W``-th
    usable window of the record, axes permuted by ``⌊replicate / W⌋`` (:func:`window_of`),
    demeaned over the record, times :attr:`NoiseProfile.real_scale`.
    """
    if profile.real:
        if not records or profile.real not in records:
            raise ProfileError(f"profile {profile.name} needs the {profile.real} noise record")
        rec = records[profile.real]
        k, perm = window_of(profile, replicate, len(rec), n)
        return rec[k * n:(k + 1) * n][:, list(perm)] * np.asarray(profile.real_scale)[None, :]
    seeds = np.random.SeedSequence(int(rng.integers(2 ** 63))).spawn(1 + len(profile.components))
    out = np.random.default_rng(seeds[0]).standard_normal((n, 3)) * np.asarray(profile.white)[None, :]
    phi = float(profile.axis_correlation)
    for j, (term, values) in enumerate(profile.components):
        crng = np.random.default_rng(seeds[1 + j])
        same = all(v == values[0] for v in values)
        if phi:
            if not same:
                raise ProfileError(f"profile {profile.name}: an axis correlation needs the same {term} on every axis")
            # three independent columns and a common one: correlation φ between any two axes
            c = simulate_noise(crng, n, fs, {term: values[0]}, size=4)
            out += math.sqrt(1.0 - phi) * c[:, :3] + math.sqrt(phi) * c[:, 3:]
        elif same:  # the same model on every axis: one call, three columns
            out += simulate_noise(crng, n, fs, {term: values[0]}, size=3)
        else:
            for a in range(3):
                out[:, a] += simulate_noise(crng, n, fs, {term: values[a]})
    return out


# --------------------------------------------------------------------------- covariance


def rounding_bias_variance(std: float, harmonics: int = 20) -> float:
    """Variance (over a uniform fraction) of the bias that rounding to integer counts leaves
    in the mean of many samples with white noise of ``std`` counts (module docstring)."""
    k = np.arange(1, harmonics + 1)
    return float(np.sum(np.exp(-4 * math.pi ** 2 * k ** 2 * std ** 2) / (2 * math.pi ** 2 * k ** 2)))


def centred(D: np.ndarray) -> np.ndarray:
    """``−½ P D P``: covariance of the pose-mean errors about their mean from their difference variances."""
    n = D.shape[0]
    P = np.eye(n) - 1.0 / n
    return -0.5 * P @ D @ P


def pose_mean_covariance(profile: NoiseProfile, starts, durations, n_samples, fs: float) -> np.ndarray:
    """Covariance of the pose-mean errors per axis, shape (3, n, n) [counts²].

    White (and rounding, 1/12 count² per sample) on the diagonal, the rounding bias of
    low-noise profiles (:func:`rounding_bias_variance`) and the per-placement offset too,
    and every time-correlated component as ``−½ P D P`` over the pose intervals
    ``[starts, starts + durations)`` [s].  The axes are independent here: with an
    :attr:`NoiseProfile.axis_correlation`, :func:`pose_residual_covariance` adds the
    cross-axis terms.
    """
    n_samples = np.asarray(n_samples, float)
    C = np.zeros((3, len(n_samples), len(n_samples)))
    for a in range(3):
        s = profile.white[a]
        C[a] += np.diag((s ** 2 + 1.0 / 12.0) / n_samples + rounding_bias_variance(s) + profile.placement[a] ** 2)
        for term, values in profile.components:
            C[a] += centred(pose_difference_variance(term, values[a], starts, durations))
    return C


def residual_covariance(C: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Covariance of the scalar pose residuals, ``Σ_ij = Σ_a w_ia w_ja C_a,ij``, with ``w = ∂r/∂z`` (n, 3)."""
    return np.einsum("ia,ja,aij->ij", w, w, C)


def pose_residual_covariance(profile: NoiseProfile, starts, durations, n_samples, fs: float,
                             w: np.ndarray) -> np.ndarray:
    """The true covariance of the scalar pose residuals under ``profile`` (unit of ``w``²):
    :func:`residual_covariance` of :func:`pose_mean_covariance`, plus, for a profile whose
    components and offset are correlated between the axes by ``φ``, the cross-axis terms
    ``φ Σ_{a≠b} w_ia w_jb C_c,ij`` (``C_c`` the correlated part, the same on every axis)."""
    S = residual_covariance(pose_mean_covariance(profile, starts, durations, n_samples, fs), w)
    phi = float(profile.axis_correlation)
    if not phi:
        return S
    corr = np.diag(np.full(len(n_samples), profile.placement[0] ** 2))
    for term, values in profile.components:
        corr = corr + centred(pose_difference_variance(term, values[0], starts, durations))
    s = w.sum(axis=1)
    cross = np.outer(s, s) - w @ w.T      # Σ_{a≠b} w_ia w_jb
    return S + phi * cross * corr


def xsens_source(report: dict) -> dict:
    """The ``fitted['xsens_mti']`` entry of :func:`build_profiles` from the measured report
    (``results/discrepancy/measured/xsens_mti.json``): the stochastic layer's final model of
    each axis, in counts."""
    st = report.get("stochastic")
    if not st:
        raise ProfileError("the Xsens report has no stochastic layer: "
                           + (report.get("stochastic_error") or "not run"))
    models = []
    for ax in ("x", "y", "z"):
        fit = st["axes"][ax]["fit_after"]
        m = {}
        for term, v in fit.items():
            key = TERMS[term].shape_key
            m[term] = (float(v["value"]), float(v[key])) if key else float(v["value"])
        models.append(m)
    named = {ax: st["axes"][ax]["named"] for ax in ("x", "y", "z")}
    return {"models": models, "fs": float(st["fs"]), "unit_to_counts": 1.0, "white_match": False,
            "description": f"Xsens MTi session, stochastic layer on its rests (named: {named})"}


def wander_axis_correlation(report: dict) -> float:
    """The joint model's correlation of its named bias wander between the axes (0 without one)."""
    nm = report.get("noise_model") or {}
    return float(nm.get("axis_correlation") or 0.0) if wander_named(nm) else 0.0


def wander_components(report: dict) -> tuple[tuple[str, tuple], ...]:
    """The joint model's named bias wander as profile components (same on every axis, data
    unit; a per-placement offset is not a component of the time series: sessions.placement_of)."""
    nm = report.get("noise_model") or {}
    if not nm.get("estimated"):
        return ()
    return tuple((term, (value,) * 3) for term, value in process_in(nm).components(nm))


def joint_source(report: dict, name: str) -> dict:
    """A ``fitted`` entry of :func:`build_profiles` from a report's joint noise model (the wander
    null's REML bias wander, the same on every axis, with its correlation between the axes)
    with the white noise of its rests: the
    per-axis sample standard deviation whose mean over a rest has the rest's standard error
    (the static detection's, which counts the samples' correlation), median over the rests."""
    nm = report.get("noise_model") or {}
    if not nm.get("estimated"):
        raise ProfileError(f"the {name} report has no joint wander estimate: "
                           + (nm.get("reason") or "the wander null did not run"))
    p = report["poses"]
    se = np.array(p["mean_std"], float)
    n = np.array(p["n_samples"], float)
    fs = float(report.get("rate") or (report.get("stochastic") or {}).get("fs") or 0.0)
    if not fs > 0:
        raise ProfileError(f"the {name} report does not give its sampling rate")
    white = np.sqrt(np.median(se ** 2 * n[:, None], axis=0))  # median: a few long, drifting rests inflate the mean
    models = []
    for a in range(3):
        m = {"white": float(white[a]) / math.sqrt(fs)}
        m.update({term: values[a] for term, values in wander_components(report)})
        models.append(m)
    placement = process_in(nm).placement_size(nm)
    return {"models": models, "fs": fs, "unit_to_counts": 1.0, "white_match": False, "placement": placement,
            "axis_correlation": wander_axis_correlation(report),
            "description": f"{name}: the joint model's bias wander ({nm.get('process', 'none')}) and the rests' white "
                           f"noise"}


def profile_table(profiles: dict, session) -> list[dict]:
    """One row per profile and axis: the terms, the white noise, and what the profile does to
    the pose means of the session: RMS over poses of the pose-mean standard deviation beyond the
    samples' own white noise and rounding (the time-correlated terms, and the rounding bias of
    sub-count noise), in counts and relative to the white one (``wander_over_white``)."""
    win = session.trimmed_windows()
    n_s = (win[:, 1] - win[:, 0]).astype(float)
    starts, durations = win[:, 0] / session.rate, n_s / session.rate
    rows = []
    for name, p in profiles.items():
        C = pose_mean_covariance(p, starts, durations, n_s, session.rate)
        for a, ax in enumerate("xyz"):
            # white = the samples' own noise and their rounding (what the pose SE shows); the
            # rest (rounding bias of sub-count noise, a per-placement offset, time-correlated
            # terms) is the wander
            vw = float(np.mean((p.white[a] ** 2 + 1.0 / 12.0) / n_s))
            vx = float(np.mean(np.diag(C[a]))) - vw
            terms = "+".join(["white"] + [t for t, _ in p.components] + (["placement"] if p.placement[a] else []))
            rows.append({"profile": name, "kind": p.kind, "axis": ax, "terms": terms, "real": p.real,
                         "white_counts": p.white[a], "pose_mean_white_counts": math.sqrt(vw),
                         "wander_pose_mean_counts": math.sqrt(max(vx, 0.0)),
                         "wander_over_white": math.sqrt(max(vx, 0.0) / vw),
                         "components": "; ".join([f"{t}=" + (f"({float(v[a][0]):.4g}, {float(v[a][1]):.4g} s)"
                                                            if isinstance(v[a], tuple) else f"{float(v[a]):.4g}")
                                                  for t, v in p.components]
                                                 + ([f"placement={p.placement[a]:.4g}"] if p.placement[a] else [])),
                         "description": p.description})
    return rows


__all__ = ["AXIS_PERMUTATIONS", "FITTED_SOURCES", "FLICKER_FLOOR", "NoiseProfile", "ProfileError", "REAL_RECORDS",
           "build_profiles", "centred", "independent_recordings", "joint_source", "placement_offsets",
           "pose_mean_covariance", "pose_mean_white", "pose_residual_covariance", "profile_table", "residual_covariance", "rounding_bias_variance", "screened_windows",
           "session_length", "simulate_profile", "usable_windows", "wander_axis_correlation", "wander_components", "window_of",
           "xsens_source"]
