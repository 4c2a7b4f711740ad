"""Benchmark of the discrepancy loop: simulated sessions with hidden effects under realistic noise.

Generator (:func:`simulate_case`).  A raw multi-position session like the Xsens example
(16-bit counts, ≈ 415 counts per m/s², rounded to integer counts), ``n_poses`` gravity
directions uniform on the sphere, rests joined by hand-like motions
(:func:`accelcal.simulation.simulate_recording`), a temperature column that cycles
``temp_cycles`` times over the session (so that temperature is not collinear with time:
with two cycles their correlation over the poses is ≈ 0.4).  The sensor noise is one of
the benchmark's noise profiles (:mod:`accelcal_repro.discrepancy.profiles`: white only,
Gauss–Markov and flicker bias wander, rate random walk, sub-count noise with rounding,
the models fitted to the Xsens session and to the 2.78 h ADIS16405 recording, and windows
of that recording itself), added to the whole time series.

Hidden effects are sized in units of their *oracle* minimum detectable effect: the size
at which the loop's nested F-test (level ``α/m`` over the ``m`` tests of its first round:
the candidates and, if enabled, the outlier family of the wander null; the configured
power) would detect the effect along its random direction ``d`` if it knew
the true covariance of the pose residuals under the profile (generalised least squares
with :func:`accelcal_repro.discrepancy.profiles.pose_mean_covariance`), computed on the
true pose design (:func:`oracle_mde`).  For the white profile it is the loop's own MDE
(:meth:`accelcal.discrepancy.identifiability.Identifiability.mde_along`); under wander it is
larger, because a wandering bias hides part of any slow effect.  Rows (``truth``):

* ``none``: no effect (false-positive rate);
* one row per effect and size (power curve, confusion matrix);
* ``a+b``: two effects at once, each at the size times its own MDE (the loop should name
  both, in any order);
* ``outlier_pose``: one pose (not the initial rest) shifted, along its gravity direction,
  by the size times the MDE of a single-pose shift (tested at ``α/(n m)``: the ``n``
  poses, the ``m`` tests of the round) — a bump or a transient offset during one rest;
* ``temperature_const``: the temperature effect of the largest size, but the
  temperature column never changes, so it acts as a constant offset the bias absorbs:
  expected outcome ``not_identifiable``.

Every recording draws from its own stream, derived from the config seed, its profile, row
and replicate (:func:`accelcal_repro.montecarlo.grid_seed`), so it does not depend on the
chunking.  Detection (:func:`detect_case`) gets the recording only (time, integer counts,
temperature: what a user's CSV holds), never the key, and runs the loop under each
requested null hypothesis on the same pose means (``wander``, and ``white``: the loop of
the white-noise loop, the negative control).  Scoring: :mod:`accelcal_repro.discrepancy.scoring`.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
import pandas as pd

from accelcal.discrepancy.detect import discrepancy
from accelcal.effects import EFFECT_IDS, effect
from accelcal.discrepancy.fit import Fit, PoseData, evaluate, fit_at, forward, pose_data, pose_data_from_static
from accelcal.discrepancy.identifiability import Identifiability, applicable, identifiability
from accelcal.discrepancy.rules import Rules, null_name
from accelcal.discrepancy.statistics import critical_noncentrality
from accelcal.errors import AccelcalError
from accelcal.evaluation import residual_sigma
from accelcal.model import m_from_params
from accelcal.recording import Recording
from accelcal.simulation import random_directions, simulate_recording
from accelcal.static import detect_static_recording

from ..montecarlo import grid_seed
from .oracle import named_set
from .profiles import NoiseProfile, placement_offsets, pose_residual_covariance, simulate_profile, window_of

NONE = "none"
NOT_IDENTIFIABLE = "not_identifiable"
OUTLIER = "outlier_pose"
CONSTANT_TEMPERATURE = "temperature_const"
ERROR = "error"
#: The null hypotheses of the loop the benchmark can compare.
NULLS = ("wander", "white")
#: Largest number of pose designs drawn until every candidate is identifiable on the truth.
MAX_REDRAWS = 20


@dataclass(frozen=True)
class Session:
    """Simulated session (config ``discrepancy.benchmark.session``)."""

    g: float = 9.80665
    n_poses: int = 30
    rate: float = 100.0
    rest_s: float = 6.0
    move_s: float = 2.0
    init_rest_s: float = 20.0
    noise_counts: float = 3.3
    offset_counts: float = 32768.0
    bias_range_counts: float = 600.0
    sensitivity: float = 415.0
    sensitivity_rel_range: float = 0.01
    nonorth_range_deg: tuple = (0.1, 1.5)
    temp_mean: float = 25.0
    temp_amplitude: float = 5.0
    temp_cycles: float = 2.0
    temp_resolution: float = 0.01
    trim_s: float = 0.25

    @classmethod
    def from_config(cls, cfg: dict) -> Session:
        return cls(**{k: (tuple(v) if isinstance(v, list) else v) for k, v in cfg.items()})

    @property
    def n_samples(self) -> int:
        """Samples of the whole session."""
        r = self.rate
        return int(round(self.init_rest_s * r)) + (self.n_poses - 1) * (int(round(self.move_s * r))
                                                                        + int(round(self.rest_s * r)))

    def rest_windows(self, n_samples: int | None = None) -> np.ndarray:
        """``[start, stop)`` sample range of every rest of the simulated session.

        ``n_samples``: the length of the simulated time series, which must be the
        session's (:attr:`n_samples`, the default).
        """
        rate = self.rate
        n_init, n_rest, n_move = (int(round(v * rate)) for v in (self.init_rest_s, self.rest_s, self.move_s))
        starts = [0] + [n_init + i * n_move + (i - 1) * n_rest for i in range(1, self.n_poses)]
        stops = [n_init] + [s + n_rest for s in starts[1:]]
        out = np.array([starts, stops]).T
        assert out[-1, 1] == (self.n_samples if n_samples is None else n_samples)
        return out

    def trimmed_windows(self, n_samples: int | None = None) -> np.ndarray:
        """The rests the static detection will see: trimmed by ``trim_s`` next to every motion."""
        m = int(round(self.trim_s * self.rate))
        win = self.rest_windows(n_samples) + np.array([[m, -m]])
        win[0, 0] = 0  # the session's start borders no motion
        return win


# --------------------------------------------------------------------------- rows


def suffixes(eid: str) -> tuple[str, ...]:
    """The effect's parameters as the key and detection columns name them: the axis (``x``,
    ``y``, ``z``) of a per-axis effect, the order ``m`` of a harmonic one."""
    return tuple(name.split("_", 1)[1] for name in effect(eid).parameters)


def effects_of(truth: str) -> tuple[str, ...]:
    """The effects hidden in a row (``'quadratic+temperature'`` → both; none for the others)."""
    if truth in (NONE, OUTLIER):
        return ()
    if truth == CONSTANT_TEMPERATURE:
        return ("temperature",)
    return tuple(truth.split("+"))


def expected_outcome(truth: str) -> str:
    """What a correct detector reports for a recording of row ``truth`` (two effects: both, '+'-joined)."""
    return NOT_IDENTIFIABLE if truth == CONSTANT_TEMPERATURE else truth


def check_truth(truth: str) -> None:
    if truth in (NONE, OUTLIER, CONSTANT_TEMPERATURE):
        return
    effs = truth.split("+")
    if not 1 <= len(effs) <= 2 or len(set(effs)) != len(effs) or any(e not in EFFECT_IDS for e in effs):
        raise AccelcalError(f"unknown benchmark row {truth!r}: none, {OUTLIER}, {CONSTANT_TEMPERATURE}, an effect "
                            f"id or two joined by '+' ({', '.join(EFFECT_IDS)})")


def plan(profiles, effects, sizes, seeds: int, seeds_none: int, seeds_constant: int, *, pairs=(),
         outlier: bool = True, extra_sizes: dict | None = None, constant_profiles=None,
         none_counts: dict | None = None) -> pd.DataFrame:
    """Every benchmark recording: ``recording, profile, truth, size_mde, replicate`` (fixed order).

    Parameters
    ----------
    profiles : sequence of str
        Noise profiles; each gets every row.
    effects : sequence of str
        Single-effect rows.
    sizes : sequence of float
        Sizes [× oracle MDE] of the effect, pair and outlier rows.
    seeds, seeds_none, seeds_constant : int
        Recordings per (row, size), effect-free recordings, constant-temperature recordings.
    pairs : sequence of (str, str)
        Two-effect rows.
    outlier : bool
        Include the ``outlier_pose`` rows.
    extra_sizes : dict, optional
        ``{profile: sizes}``: further sizes of the single-effect rows (power curves).
    constant_profiles : sequence of str, optional
        Profiles with the constant-temperature row (default: all).
    none_counts : dict, optional
        ``{profile: n}``: effect-free recordings of these profiles instead of ``seeds_none``
        (the real-record profiles, whose recordings share a few windows of noise).
    """
    rows = []
    for prof in profiles:
        rows += [(prof, NONE, 0.0, r) for r in range((none_counts or {}).get(prof, seeds_none))]
        sz = sorted(set(map(float, sizes)) | set(map(float, (extra_sizes or {}).get(prof, ()))))
        for e in effects:
            rows += [(prof, e, s, r) for s in sz for r in range(seeds)]
        for a, b in pairs:
            rows += [(prof, f"{a}+{b}", float(s), r) for s in sizes for r in range(seeds)]
        if outlier:
            rows += [(prof, OUTLIER, float(s), r) for s in sizes for r in range(seeds)]
        if seeds_constant and (constant_profiles is None or prof in constant_profiles):
            rows += [(prof, CONSTANT_TEMPERATURE, float(max(sizes)), r) for r in range(seeds_constant)]
    df = pd.DataFrame(rows, columns=["profile", "truth", "size_mde", "replicate"])
    for t in df.truth.unique():
        check_truth(t)
    df.insert(0, "recording", [f"{p}__{t}_{s:g}_{r:04d}" for p, t, s, r in
                               zip(df.profile, df.truth, df.size_mde, df.replicate)])
    return df


def chunk(df: pd.DataFrame, n_chunks: int, k: int) -> pd.DataFrame:
    """Chunk ``k`` of ``n_chunks``: every ``n_chunks``-th recording (balances rows over chunks)."""
    if not 0 <= k < n_chunks:
        raise AccelcalError(f"chunk {k} outside 0..{n_chunks - 1}")
    return df.iloc[k::n_chunks]


# --------------------------------------------------------------------------- design and oracle


@dataclass(frozen=True)
class Oracle:
    """GLS information of the hidden discrepancies on the true design under the profile's noise.

    ``whiten``: inverse of the lower Cholesky factor of the covariance of the pose
    residuals [1/unit of g]; ``Q0`` an orthonormal basis of the whitened Jacobian of the
    base model (n, 9) at the truth.
    """

    whiten: np.ndarray
    Q0: np.ndarray
    n: int

    @classmethod
    def build(cls, data, p_true, cov_r) -> Oracle:
        W = np.linalg.inv(np.linalg.cholesky(cov_r))
        _, J, _ = evaluate(p_true, data, ())
        Q0, _ = np.linalg.qr(W @ J)
        return cls(W, Q0, len(data))

    def _info(self, J1: np.ndarray) -> np.ndarray:
        Jw = self.whiten @ J1
        Jp = Jw - self.Q0 @ (self.Q0.T @ Jw)
        return Jp.T @ Jp

    def effect_mde(self, data, p_true, eid: str, direction, rules: Rules, n_tests: int) -> float:
        """Size ``a`` along unit ``direction`` at which the nested F-test at ``α/n_tests`` has the configured power."""
        k = effect(eid).size
        _, J, _ = evaluate(np.concatenate([p_true, np.zeros(k)]), data, (eid,))
        info = self._info(J[:, -k:])
        lam = critical_noncentrality(k, self.n - 9 - k, rules.alpha / max(n_tests, 1), rules.power)
        d = np.asarray(direction, float)
        v = float(d @ info @ d)
        return float(np.sqrt(lam / v)) if v > 0 else float("inf")

    def shift_mde(self, pose: int, rules: Rules, n_tests: int = 1) -> float:
        """Residual shift of one pose [unit of g] that a test at ``α/(n n_tests)`` (the ``n``
        poses, the ``n_tests`` members of the round's Holm family) detects with the power."""
        e = np.zeros((self.n, 1))
        e[pose, 0] = 1.0
        v = float(self._info(e)[0, 0])
        lam = critical_noncentrality(1, self.n - 10, rules.alpha / (self.n * max(n_tests, 1)), rules.power)
        return float(np.sqrt(lam / v)) if v > 0 else float("inf")


# --------------------------------------------------------------------------- generator


@dataclass(frozen=True)
class _Sensor:
    """A simulated sensor: sensitivities [counts per unit of g], non-orthogonality angles
    [rad], the matrix ``M`` they make and the bias [counts]."""

    sensitivity: np.ndarray
    nonorth: np.ndarray
    M: np.ndarray
    bias: np.ndarray


def _draw_sensor(rng, ss: Session) -> _Sensor:
    sens = ss.sensitivity * (1 + rng.uniform(-ss.sensitivity_rel_range, ss.sensitivity_rel_range, 3))
    lo, hi = ss.nonorth_range_deg
    th = np.deg2rad(rng.uniform(lo, hi, 3) * rng.choice((-1.0, 1.0), 3))
    bias = ss.offset_counts + rng.uniform(-ss.bias_range_counts, ss.bias_range_counts, 3)
    return _Sensor(sens, th, m_from_params(sens - 1.0, th), bias)


def simulate_case(truth: str, size_mde: float, replicate: int, *, seed: int, session: Session, rules: Rules,
                  profile: NoiseProfile | None = None, records: dict | None = None) -> tuple[Recording, dict]:
    """One benchmark recording and its key row.

    Parameters
    ----------
    truth : str
        A row of :func:`plan` (``none``, an effect id, ``a+b``, ``outlier_pose``, ``temperature_const``).
    size_mde : float
        Size of the hidden discrepancy in units of its oracle MDE along its direction.
    replicate : int
    seed : int
        Config seed.
    session : Session
    rules : Rules
        The detection rules (α, power, candidates) that define the MDE.
    profile : NoiseProfile, optional
        The sensor noise; default white noise of ``session.noise_counts`` per sample.
    records : dict, optional
        Real noise records of the ``real`` profiles (:func:`accelcal_repro.discrepancy.profiles.simulate_profile`).
    """
    check_truth(truth)
    profile = profile or NoiseProfile("white", (session.noise_counts,) * 3)
    rng = np.random.default_rng(grid_seed(seed, f"discrepancy/{profile.name}/{truth}", float(size_mde),
                                          int(replicate)))
    ss = session
    sensor = _draw_sensor(rng, ss)
    phase = rng.uniform(0, 2 * np.pi)
    effs = effects_of(truth)
    dirs = {e: _unit(rng.standard_normal(effect(e).size)) for e in effs}  # the effects' directions
    noise_rng = np.random.default_rng(rng.integers(2 ** 63))
    design = _draw_design(rng, ss, profile, rules, sensor, phase, truth)
    t, win, n_eff = design.t, design.windows, design.n_eff

    oracle, w = _oracle(design, profile, ss)
    # the loop's first round tests the candidates and the outlier family together (Holm)
    family = len(design.candidates) + bool(rules.outlier_pose)
    params, key_eff = _effect_sizes(design, oracle, dirs, size_mde, rules, family)

    temp = _temperature(design, ss, truth, phase)
    # Centre the covariates as the fitter does (mean over the poses), so that the injected
    # parameters are what the extended model estimates.
    dtemp = temp - (design.temp_pose.mean() if truth != CONSTANT_TEMPERATURE else ss.temp_mean)
    z = forward(design.x, sensor.M, sensor.bias, params, dt=t - design.t_mid.mean(), dtemp=dtemp)
    z = z + simulate_profile(profile, noise_rng, len(t), ss.rate, replicate=int(replicate), records=records)
    z = z + placement_offsets(profile, noise_rng, ss.rest_windows(len(t))[:, 0], len(t))

    outlier = {"outlier_pose": -1, "outlier_t": np.nan, "outlier_shift_mde": np.nan, "outlier_shift": np.nan}
    if truth == OUTLIER:
        _owed_draw(rng, len(t))
        outlier = _shift_one_pose(z, rng, ss, design, oracle, w, size_mde, rules, family)
    rec = Recording(t, np.round(z), temp, f"{profile.name}__{truth}_{size_mde:g}_{replicate:04d}")
    # Real-noise profiles reuse the windows of one record: the scoring counts independent ones.
    window = window_of(profile, replicate, len(records[profile.real]), len(t))[0] if profile.real else -1

    key = {"profile": profile.name, "profile_kind": profile.kind, "truth": truth, "expected": expected_outcome(truth),
           "effects_injected": "+".join(effs) if truth != CONSTANT_TEMPERATURE else "temperature",
           "size_mde": float(size_mde), "replicate": int(replicate), "noise_window": window, "n_poses": ss.n_poses,
           "redraws": design.redraws, **outlier, **key_eff, **_sensor_columns(design, sensor),
           "temp_range": float(np.ptp(temp))}
    return rec, key


def _shift_one_pose(z: np.ndarray, rng, ss: Session, design: _Design, oracle: Oracle, w: np.ndarray,
                    size_mde: float, rules: Rules, family: int) -> dict:
    """Shift one pose's samples in ``z`` (in place) along its residual's gradient ``w``, by
    ``size_mde`` times the MDE of a single-pose shift; its key columns."""
    k = int(rng.integers(1, ss.n_poses))  # never the initial rest: it sets the motion threshold
    s_mde = oracle.shift_mde(k, rules, family)
    shift = size_mde * s_mde * rng.choice((-1.0, 1.0))
    delta = shift * w[k] / float(w[k] @ w[k])  # moves the residual of pose k by `shift`
    a_, b_ = ss.rest_windows(len(design.t))[k]
    z[a_:b_] += delta[None, :]
    return {"outlier_pose": k, "outlier_t": float(design.t_mid[k]), "outlier_shift_mde": s_mde,
            "outlier_shift": float(shift)}


@dataclass(frozen=True)
class _Design:
    """A simulated session before its effects and noise: the true specific force ``x`` (unit
    of g) and temperature along the time ``t``, the trimmed rest windows the detection will
    see with their mid times, mean temperatures and sample counts, the true pose means as
    :class:`PoseData`, the true parameters, the base model at the truth, the applicable
    candidates and their identifiability on it, and the designs drawn before this one."""

    t: np.ndarray
    x: np.ndarray
    temp: np.ndarray
    windows: np.ndarray
    t_mid: np.ndarray
    temp_pose: np.ndarray
    n_eff: np.ndarray
    data: PoseData
    p_true: np.ndarray
    base: Fit
    candidates: list[str]
    identifiability: dict[str, Identifiability]
    redraws: int


def _draw_design(rng, ss: Session, profile: NoiseProfile, rules: Rules, sensor: _Sensor, phase: float,
                 truth: str) -> _Design:
    """Pose directions, redrawn (at most :data:`MAX_REDRAWS` times) until every candidate is
    identifiable on the true design."""
    g = ss.g
    for redraws in range(MAX_REDRAWS):
        if redraws:
            _owed_draw(rng, len(t))
        u = random_directions(rng, ss.n_poses)
        # noise-free: its zero-weighted noise draw is owed, made only if ``rng`` draws again
        sim = simulate_recording(rng, u, g, np.eye(3), np.zeros(3), 0.0, rate=ss.rate, rest_s=ss.rest_s,
                                 move_s=ss.move_s, init_rest_s=ss.init_rest_s, draw_noise=False)
        t, x = sim["t"], sim["acc"]  # true specific force (unit of g) along the whole session
        span = t[-1] - t[0] + 1.0 / ss.rate
        temp = ss.temp_mean + ss.temp_amplitude * np.sin(2 * np.pi * ss.temp_cycles * t / span + phase)
        # The design the detection will see: trimmed rests, their mid times and temperatures.
        win = ss.trimmed_windows(len(t))
        t_mid = np.array([0.5 * (t[a] + t[b - 1]) for a, b in win])
        temp_pose = np.array([temp[a:b].mean() for a, b in win])
        n_eff = (win[:, 1] - win[:, 0]).astype(float)
        white_var = np.asarray(profile.white) ** 2 + 1.0 / 12.0  # white noise + rounding to integer counts
        mean_std = np.sqrt(white_var[None, :] / n_eff[:, None])
        M, bias = sensor.M, sensor.bias
        z_pose = forward(g * u, M, bias, {})
        data = pose_data(z_pose, g, mean_std, t_mid, temp_pose, sigma=residual_sigma(z_pose, mean_std, M, bias))
        p_true = np.concatenate([bias, sensor.sensitivity - 1.0, sensor.nonorth])
        base = fit_at(data, (), p_true)
        cands, _ = applicable(data, rules.candidates)
        idents = {e: identifiability(data, base, e, rules, len(cands)) for e in cands}
        if all(i.identifiable for i in idents.values()):
            return _Design(t, x, temp, win, t_mid, temp_pose, n_eff, data, p_true, base, cands, idents, redraws)
    raise AccelcalError(f"{truth}: no pose design with every candidate identifiable in {MAX_REDRAWS} draws")


def _owed_draw(rng, n: int) -> None:
    """The noise draw a design's noise-free :func:`simulate_recording` (``draw_noise=False``)
    left owing, made before ``rng`` draws again: the stream goes on as if it had drawn it."""
    rng.standard_normal((n, 3))


def _effect_sizes(design: _Design, oracle: Oracle, dirs: dict, size_mde: float, rules: Rules,
                  family: int) -> tuple[dict, dict]:
    """The hidden effects' parameters, ``size_mde`` times each one's oracle MDE along its
    direction, and their key columns (MDEs, parameters, directions)."""
    params, key_eff = {}, {}
    for e, d in dirs.items():
        a = oracle.effect_mde(design.data, design.p_true, e, d, rules, family)
        # the white loop's MDE at the same level (its own check above is at α/len(cands)): the
        # same information, the critical non-centrality of the round's family
        ident = design.identifiability[e]
        lam = critical_noncentrality(effect(e).size, ident.dof, rules.alpha / max(family, 1), rules.power)
        a_white = dataclasses.replace(ident, lambda_crit=lam).mde_along(d)
        params[e] = size_mde * a * d
        key_eff.update({f"mde_along_{e}": a, f"mde_along_white_{e}": a_white,
                        **{f"param_{e}_{ax}": float(v) for ax, v in zip(suffixes(e), params[e])},
                        **{f"direction_{e}_{ax}": float(v) for ax, v in zip(suffixes(e), d)}})
    if dirs:  # the first (or only) effect also under generic names
        e = next(iter(dirs))
        key_eff.update({"mde_along": key_eff[f"mde_along_{e}"],
                        **{f"param_{ax}": key_eff[f"param_{e}_{ax}"] for ax in suffixes(e)},
                        **{f"direction_{ax}": key_eff[f"direction_{e}_{ax}"] for ax in suffixes(e)}})
    return params, key_eff


# --------------------------------------------------------------------------- detection


def null_available(null: str) -> bool:
    """Can this library's loop test under ``null``?  ``white`` always (the white-noise loop); ``wander``
    once :class:`~accelcal.discrepancy.rules.Rules` has the ``null`` setting (earlier names read as their new one)."""
    null = null_name(null)
    if null not in NULLS:
        raise AccelcalError(f"unknown null hypothesis {null!r}; known: {', '.join(NULLS)}")
    return null == "white" or "null" in {f.name for f in dataclasses.fields(Rules)}


def nulls_for(truth: str, nulls: dict) -> list[str]:
    """The null hypotheses to run on a recording of row ``truth``: config ``benchmark.nulls``
    maps each null to ``all``, ``effect_free`` (only the ``none`` rows) or ``none``; the
    nulls this library lacks are left out (:func:`null_available`)."""
    out = []
    for null, rows in ((null_name(k), v) for k, v in nulls.items()):
        if rows not in ("all", "effect_free", "none"):
            raise AccelcalError(f"benchmark.nulls.{null}: {rows!r} is not all, effect_free or none")
        if null_available(null) and (rows == "all" or (rows == "effect_free" and truth == NONE)):
            out.append(null)
    return out


def rules_with_null(rules: Rules, null: str) -> Rules:
    """``rules`` testing under ``null`` (:func:`null_available` must hold)."""
    if not null_available(null):
        raise AccelcalError(f"the discrepancy loop of this library has no {null!r} null hypothesis")
    if "null" in {f.name for f in dataclasses.fields(Rules)}:
        return dataclasses.replace(rules, null=null_name(null))
    return rules


def _result_row(res) -> dict:
    s = res.statistics()
    row = {"outcome": res.outcome, "effect": res.effect, "effects": "+".join(res.effects),
           "not_identifiable": "+".join(res.not_identifiable), "n_poses_detected": s["n_poses"],
           **{k: s[k] for k in ("gap_before", "gap_after", "gap_expected_before", "gap_expected_after",
                                "gap_lopo_before", "gap_lopo_after", "excess_before", "excess_after")}}
    row["outlier_t_detected"] = ";".join(f"{o.t:.3f}" for o in res.outliers)
    row["outlier_poses_detected"] = ";".join(str(o.pose) for o in res.outliers)
    row["named_set"] = named_set(res.effects, [o.pose for o in res.outliers])
    for c in res.candidates:
        if c.round == 1:
            row[f"p_{c.effect}"] = c.p_value
            row[f"p_adj_{c.effect}"] = c.p_adjusted
            row[f"identifiable_{c.effect}"] = c.identifiable
            row[f"passed_{c.effect}"] = c.passed
    first = [c for c in res.candidates if c.named and c.round == 1]
    if first:
        row.update({f"estimate_{a}": v for a, v in zip(suffixes(first[0].effect), first[0].estimate)})
        row.update({f"se_{a}": v for a, v in zip(suffixes(first[0].effect), first[0].se)})
    return row


def _null_of(rules: Rules) -> str:
    return getattr(rules, "null", "white")


def _detect(data, rules: Rules) -> dict:
    row = {"null": _null_of(rules), "outcome": ERROR, "effect": "", "effects": "", "error": ""}
    try:
        res = discrepancy(data, rules, report=False)  # the decisions: no interval of the final noise model
    except AccelcalError as err:  # includes a model that does not converge: an error, never 'none'
        row["error"] = str(err).splitlines()[0]
    else:
        row.update(_result_row(res))
    return row


def detect_nulls(rec: Recording, g: float, rules: Rules, nulls=("white",), oracle=None) -> list[dict]:
    """The loop on one recording under each null hypothesis (same static poses): one row per null.

    What ``accelcal discrepancy`` does before its stochastic layer.  A recording the
    pipeline cannot handle gives rows with ``outcome='error'`` and the message.  No
    timings: the table must be byte-identical on a rerun (wall times are in the job's
    benchmark file).  ``oracle`` (optional): ``(data, rows) -> row`` on the same poses, given
    the loop's rows (:func:`accelcal_repro.discrepancy.oracle.oracle_detection`), one row more.
    """
    try:
        data = pose_data_from_static(detect_static_recording(rec), g, rec.acc, rec.rate)
    except AccelcalError as err:
        names = [*nulls, *(["oracle"] if oracle is not None else [])]
        return [{"null": n, "outcome": ERROR, "effect": "", "effects": "", "error": str(err).splitlines()[0]}
                for n in names]
    rows = [_detect(data, rules_with_null(rules, n)) for n in nulls]
    return rows + ([oracle(data, rows)] if oracle is not None else [])


def detect_case(rec: Recording, g: float, rules: Rules) -> dict:
    """:func:`detect_nulls` under the null of ``rules`` itself: one row."""
    try:
        data = pose_data_from_static(detect_static_recording(rec), g, rec.acc, rec.rate)
    except AccelcalError as err:
        return {"null": _null_of(rules), "outcome": ERROR, "effect": "", "effects": "",
                "error": str(err).splitlines()[0]}
    return _detect(data, rules)


def _sensor_columns(design: _Design, sensor: _Sensor) -> dict:
    """The key's columns of the drawn sensor and of the candidates' absorbed fractions."""
    return {**{f"absorbed_{e}": design.identifiability[e].absorbed for e in EFFECT_IDS if e in design.identifiability},
            **{f"bias_{a}": float(v) for a, v in zip("xyz", sensor.bias)},
            **{f"sensitivity_{a}": float(v) for a, v in zip("xyz", sensor.sensitivity)},
            **{f"nonorth_deg_{k}": float(v) for k, v in zip(("xy", "zx", "zy"), np.rad2deg(sensor.nonorth))}}


def _temperature(design: _Design, ss: Session, truth: str, phase: float) -> np.ndarray:
    """The recorded temperature (constant for ``temperature_const``), at the sensor's resolution."""
    temp = design.temp
    if truth == CONSTANT_TEMPERATURE:
        temp = np.full_like(design.t, ss.temp_mean + ss.temp_amplitude * np.sin(phase))
    return np.round(temp / ss.temp_resolution) * ss.temp_resolution


def _oracle(design: _Design, profile: NoiseProfile, ss: Session) -> tuple[Oracle, np.ndarray]:
    """The oracle of a design: the covariance of the pose residuals the profile implies (unit
    of g²), and the residuals' gradients ``∂r/∂z`` (unweighted)."""
    w = -design.base.J[:, :3] * design.base.sigma[:, None]  # ∂r/∂z = -∂r/∂b
    t, win, n_eff = design.t, design.windows, design.n_eff
    cov = pose_residual_covariance(profile, t[win[:, 0]], n_eff / ss.rate, n_eff, ss.rate, w)
    return Oracle.build(design.data, design.p_true, cov), w


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


__all__ = ["CONSTANT_TEMPERATURE", "ERROR", "NONE", "NOT_IDENTIFIABLE", "NULLS", "OUTLIER", "Oracle", "Session",
           "check_truth", "chunk", "detect_case", "detect_nulls", "effects_of", "nulls_for", "expected_outcome", "null_available",
           "plan", "rules_with_null", "simulate_case"]
