"""Noise profiles of the discrepancy benchmark: the sensor noise a simulated session carries.

A profile is a noise model per axis in the session's data unit (raw counts), added to the
whole time series (rests and motions: a bias wander does not pause while the sensor is
moved) before the samples are rounded to integer counts.  Three kinds:

* **parametric** (config ``discrepancy.benchmark.profiles``): white noise of
  ``noise_counts`` per sample (the session's, unless the profile sets its own) plus
  terms of the stochastic layer's library (:data:`accelcal.discrepancy.stochastic.TERMS`)
  whose sizes are given in units of ``σ_pm``, the white noise of one pose mean
  (``noise_counts / sqrt(samples of a trimmed rest)``; 0.141 counts for the Xsens-like
  session):

  - ``gauss_markov: [[k, T_c], ...]``: one first-order Gauss–Markov bias per pair, of
    standard deviation ``k σ_pm`` and correlation time ``T_c`` seconds (``session``: the
    session's length);
  - ``bias_instability: k``: flicker bias whose Allan floor ``0.664 B`` is ``k σ_pm``;
  - ``random_walk: k``: rate random walk whose Allan deviation at the session length,
    ``K sqrt(T_s/3)``, is ``k σ_pm``;
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
  same rescaling), no model at all.  Replicate ``r`` takes the disjoint window
  ``r mod W`` (``W`` = windows of session length in the record) with the axis
  permutation ``⌊r / W⌋ mod 6``; only ``W`` recordings are independent, which the
  scoring's confidence interval accounts for (:func:`independent_recordings`).

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
from dataclasses import asdict, dataclass
from itertools import permutations

import numpy as np

from accelcal.discrepancy.stochastic import TERMS, pose_difference_variance, simulate_noise
from accelcal.errors import AccelcalError

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
    kind : {'parametric', 'fitted', 'real'}
    description : str
    """

    name: str
    white: tuple
    components: tuple = ()
    real: str = ""
    real_scale: tuple = (1.0, 1.0, 1.0)
    kind: str = "parametric"
    description: str = ""

    def model(self, axis: int, fs: float) -> dict:
        """The axis's noise model as :func:`accelcal.discrepancy.stochastic.model_avar` takes it
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
                   d.get("description", ""))


# --------------------------------------------------------------------------- building profiles


def pose_mean_white(session) -> float:
    """``σ_pm``: white noise of one pose mean of the session [counts] (trimmed rest, rounding included)."""
    n = int(round((session.rest_s - 2 * session.trim_s) * session.rate))
    return math.sqrt(session.noise_counts ** 2 + 1.0 / 12.0) / math.sqrt(n)


def session_length(session) -> float:
    """Length of the simulated session [s]."""
    return session.init_rest_s + (session.n_poses - 1) * (session.move_s + session.rest_s)


def _parametric(name: str, spec: dict, session) -> NoiseProfile:
    known = {"noise_counts", "gauss_markov", "bias_instability", "random_walk", "description"}
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
    return NoiseProfile(name, (white,) * 3, tuple(comps), kind="parametric", description=spec.get("description", ""))


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


def build_profiles(specs, session, *, fitted: dict | None = None) -> dict[str, NoiseProfile]:
    """Every configured profile, resolved to counts, in config order.

    Parameters
    ----------
    specs : sequence of dict
        Config ``discrepancy.benchmark.profiles``: ``[{name: ..., **spec}]`` (module docstring).
    session : Session
    fitted : dict, optional
        ``{source: {"models": [3 per-axis models {term: value}], "fs": Hz, "unit_to_counts":
        float or 3 floats, "white_match": bool}}`` for the fitted and real profiles.
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
        out[name] = _from_model(name, f["models"], fs, scale, kind, src if kind == "real" else "",
                                spec.get("description", f.get("description", "")))
    return out


# --------------------------------------------------------------------------- simulation


def record_windows(n_record: int, n: int) -> int:
    """Disjoint windows of ``n`` samples in a record of ``n_record``."""
    return n_record // n


def independent_recordings(profile: NoiseProfile, n_recordings: int, n_record: int | None, n: int) -> int:
    """How many of ``n_recordings`` replicates carry independent noise (real profiles reuse windows)."""
    if not profile.real or n_record is None:
        return n_recordings
    return min(n_recordings, record_windows(n_record, n))


def simulate_profile(profile: NoiseProfile, rng: np.random.Generator, n: int, fs: float, *, replicate: int = 0,
                     records: dict | None = None) -> np.ndarray:
    """Noise of ``profile`` for a session of ``n`` samples, shape (n, 3) [counts], not rounded.

    Parametric and fitted profiles: white noise plus every component, each component and
    axis on its own stream spawned from ``rng``.  Real profiles: window ``replicate mod W``
    of the record, axes permuted by ``⌊replicate / W⌋`` (module docstring), demeaned over
    the record, times :attr:`NoiseProfile.real_scale`.
    """
    if profile.real:
        if not records or profile.real not in records:
            raise ProfileError(f"profile {profile.name} needs the {profile.real} noise record")
        rec = records[profile.real]
        w = record_windows(len(rec), n)
        if w < 1:
            raise ProfileError(f"the {profile.real} record ({len(rec)} samples) is shorter than a session ({n})")
        k, perm = replicate % w, AXIS_PERMUTATIONS[(replicate // w) % len(AXIS_PERMUTATIONS)]
        return rec[k * n:(k + 1) * n][:, list(perm)] * np.asarray(profile.real_scale)[None, :]
    seeds = np.random.SeedSequence(int(rng.integers(2 ** 63))).spawn(1 + len(profile.components))
    out = np.random.default_rng(seeds[0]).standard_normal((n, 3)) * np.asarray(profile.white)[None, :]
    for j, (term, values) in enumerate(profile.components):
        crng = np.random.default_rng(seeds[1 + j])
        if all(v == values[0] for v in values):  # the same model on every axis: one call, three columns
            out += simulate_noise(crng, n, fs, {term: values[0]}, size=3)
        else:
            for a in range(3):
                out[:, a] += simulate_noise(crng, n, fs, {term: values[a]})
    return out


# --------------------------------------------------------------------------- screening a real record


@dataclass(frozen=True)
class RecordScreen:
    """Pre-registered screen of a real noise record for transients (config
    ``discrepancy.benchmark.record_screen``; :func:`transient_scan`).

    Attributes
    ----------
    block_s : tuple of float
        Lengths of the blocks whose means are scanned [s]: about a pose's rest finds what
        shifts a pose mean, about a second shorter bumps.  Not single samples: a real
        record's quantised, heavy-tailed samples pass 5 robust standard deviations hundreds
        of times (the ADIS16405: 370 isolated samples over every window, each moving a
        5 s mean by less than a fifth of its white scatter), and a spike that matters for a
        pose mean shows in the block means.
    reference_s : float
        Half-width of the running median of 1 s block means that is each block's local
        reference [s]: long enough that a bump of one block cannot move it, short against
        the record's slow wander.
    z : float
        Flag a block whose deviation from its reference exceeds ``z`` robust standard
        deviations (1.4826 MAD of all the blocks of its length on that axis).
    """

    block_s: tuple = (1.0, 5.0)
    reference_s: float = 60.0
    z: float = 5.0

    def __post_init__(self):
        if not self.block_s or min(self.block_s) <= 0 or not self.reference_s > 0 or not self.z > 0:
            raise ProfileError(f"record screen needs block_s > 0, reference_s > 0 and z > 0; got {self}")

    @classmethod
    def from_config(cls, cfg: dict) -> RecordScreen:
        return cls(tuple(float(b) for b in cfg["block_s"]), float(cfg["reference_s"]), float(cfg["z"]))


def _block_means(c: np.ndarray, b: int, offset: int) -> tuple[np.ndarray, np.ndarray]:
    """Starts and means of the disjoint blocks of ``b`` samples from ``offset``, from the cumulative sum ``c`` (n+1,)."""
    starts = np.arange(offset, len(c) - b, b)
    return starts, (c[starts + b] - c[starts]) / b


def _local_reference(x: np.ndarray, fs: float, reference_s: float) -> np.ndarray:
    """Per sample: the running median of the 1 s block means within ±``reference_s`` of its second."""
    from scipy.ndimage import median_filter

    sec = max(int(round(fs)), 1)
    m = x[: len(x) // sec * sec].reshape(-1, sec).mean(axis=1)
    ref = median_filter(m, size=2 * int(round(reference_s)) + 1, mode="nearest")
    return np.pad(np.repeat(ref, sec), (0, len(x) - len(ref) * sec), mode="edge")  # the last partial second


def transient_scan(record: np.ndarray, fs: float, screen: RecordScreen) -> list[dict]:
    """Transients (spikes, bumps, steps) of a real noise record, found from the record alone.

    Every axis is compared with its own local level (:func:`_local_reference`) in blocks of
    each length of ``screen.block_s``, on two grids offset by half a block (so that a bump
    straddling a block edge is seen whole); a block is flagged when its deviation exceeds
    ``screen.z`` robust standard deviations of all the blocks of its length on that axis.
    The criterion knows nothing of the loop or of the sessions cut from the record: it is
    fixed before the windows are used, so it cannot be tuned to the loop's detections.

    Parameters
    ----------
    record : ndarray, shape (n, 3)
    fs : float
        Sampling rate [Hz].
    screen : RecordScreen

    Returns
    -------
    list of dict
        One per run of overlapping flagged blocks of one axis and block length: ``axis``,
        ``block_s``, ``start``, ``stop`` (samples, ``[start, stop)``), ``z`` (the largest
        signed deviation in robust standard deviations) and ``deviation`` (record unit).
    """
    x = np.asarray(record, float)
    if x.ndim != 2 or x.shape[1] != 3 or not np.all(np.isfinite(x)):
        raise ProfileError(f"a noise record must be finite with shape (n, 3); got shape {x.shape}")
    events = []
    for a in range(3):
        ref = _local_reference(x[:, a], fs, screen.reference_s)
        cx = np.concatenate([[0.0], np.cumsum(x[:, a] - ref)])
        for block_s in screen.block_s:
            b = max(int(round(block_s * fs)), 1)
            grids = [_block_means(cx, b, off) for off in sorted({0, b // 2})]
            d_all = np.concatenate([d for _, d in grids])
            s = 1.4826 * float(np.median(np.abs(d_all - np.median(d_all))))
            if not s > 0:
                raise ProfileError(f"record screen: axis {a} has no scatter in blocks of {block_s} s")
            hits = sorted((int(st), float(d / s)) for starts, d in grids for st, d in zip(starts, d)
                          if abs(d) > screen.z * s)
            for st, z in hits:  # merge overlapping flagged blocks into one event
                if events and events[-1]["axis"] == a and events[-1]["block_s"] == block_s \
                        and st <= events[-1]["stop"]:
                    ev = events[-1]
                    ev["stop"] = max(ev["stop"], st + b)
                    if abs(z) > abs(ev["z"]):
                        ev["z"], ev["deviation"] = z, z * s
                else:
                    events.append({"axis": a, "block_s": block_s, "start": st, "stop": st + b, "z": z,
                                   "deviation": z * s})
    return events


def clean_windows(n_record: int, n: int, events) -> tuple[int, ...]:
    """Indices of the disjoint windows of ``n`` samples that hold no event of :func:`transient_scan`."""
    bad = set()
    for ev in events:
        bad.update(range(ev["start"] // n, (ev["stop"] - 1) // n + 1))
    return tuple(k for k in range(record_windows(n_record, n)) if k not in bad)


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
    low-noise profiles (:func:`rounding_bias_variance`) too, and every time-correlated
    component as ``−½ P D P`` over the pose intervals ``[starts, starts + durations)`` [s].
    """
    n_samples = np.asarray(n_samples, float)
    C = np.zeros((3, len(n_samples), len(n_samples)))
    for a in range(3):
        s = profile.white[a]
        C[a] += np.diag((s ** 2 + 1.0 / 12.0) / n_samples + rounding_bias_variance(s))
        for term, values in profile.components:
            C[a] += centred(pose_difference_variance(term, values[a], starts, durations))
    return C


def residual_covariance(C: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Covariance of the scalar pose residuals, ``Σ_ij = Σ_a w_ia w_ja C_a,ij``, with ``w = ∂r/∂z`` (n, 3)."""
    return np.einsum("ia,ja,aij->ij", w, w, C)


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


def joint_source(report: dict, name: str) -> dict:
    """A ``fitted`` entry of :func:`build_profiles` from a report's joint noise model (the colored
    null's REML bias wander, the same on every axis) with the white noise of its rests: the
    per-axis sample standard deviation whose mean over a rest has the rest's standard error
    (the static detection's, which counts the samples' correlation), median over the rests."""
    nm = report.get("noise_model") or {}
    if not nm.get("estimated"):
        raise ProfileError(f"the {name} report has no joint wander estimate: "
                           + (nm.get("reason") or "the colored null did not run"))
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
        if nm.get("term") not in (None, "none"):
            if nm.get("process") == "random_walk":
                m["random_walk"] = float(nm["random_walk_K"])
            else:
                m["gauss_markov"] = (float(nm["size"]), float(nm["tau_s"]))
        models.append(m)
    return {"models": models, "fs": fs, "unit_to_counts": 1.0, "white_match": False,
            "description": f"{name}: the joint model's bias wander ({nm.get('process', 'none')}) and the rests' white "
                           f"noise"}


def profile_table(profiles: dict, session) -> list[dict]:
    """One row per profile and axis: the terms, the white noise, and what the profile does to
    the pose means of the session: RMS over poses of the pose-mean standard deviation beyond the
    samples' own white noise and rounding (the time-correlated terms, and the rounding bias of
    sub-count noise), in counts and relative to the white one (``wander_over_white``)."""
    from .benchmark import _trimmed_windows

    win = _trimmed_windows(session, session.n_samples)
    n_s = (win[:, 1] - win[:, 0]).astype(float)
    starts, durations = win[:, 0] / session.rate, n_s / session.rate
    rows = []
    for name, p in profiles.items():
        C = pose_mean_covariance(p, starts, durations, n_s, session.rate)
        for a, ax in enumerate("xyz"):
            # white = the samples' own noise and their rounding (what the pose SE shows); the
            # rest (rounding bias of sub-count noise, time-correlated terms) is the wander
            vw = float(np.mean((p.white[a] ** 2 + 1.0 / 12.0) / n_s))
            vx = float(np.mean(np.diag(C[a]))) - vw
            terms = "+".join(["white"] + [t for t, _ in p.components])
            rows.append({"profile": name, "kind": p.kind, "axis": ax, "terms": terms, "real": p.real,
                         "white_counts": p.white[a], "pose_mean_white_counts": math.sqrt(vw),
                         "wander_pose_mean_counts": math.sqrt(max(vx, 0.0)),
                         "wander_over_white": math.sqrt(max(vx, 0.0) / vw),
                         "components": "; ".join(f"{t}=" + (f"({float(v[a][0]):.4g}, {float(v[a][1]):.4g} s)"
                                                           if isinstance(v[a], tuple) else f"{float(v[a]):.4g}")
                                                 for t, v in p.components),
                         "description": p.description})
    return rows


__all__ = ["AXIS_PERMUTATIONS", "FITTED_SOURCES", "FLICKER_FLOOR", "NoiseProfile", "ProfileError", "REAL_RECORDS",
           "build_profiles", "centred", "independent_recordings", "pose_mean_covariance", "pose_mean_white",
           "profile_table", "record_windows", "residual_covariance", "rounding_bias_variance", "session_length",
           "joint_source", "simulate_profile", "xsens_source"]
