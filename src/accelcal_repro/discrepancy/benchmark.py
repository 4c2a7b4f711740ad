"""Benchmark of the deterministic layer: recordings with one hidden effect each, a key, a score.

Generator (:func:`simulate_case`).  A raw multi-position session like the Xsens example
(16-bit counts, ≈ 415 counts per m/s², white noise of ≈ 3.3 counts per sample, rounded
to integer counts), ``n_poses`` gravity directions uniform on the sphere, rests joined by
hand-like motions (:func:`accelcal.simulation.simulate_recording`), a temperature column
that cycles ``temp_cycles`` times over the session (so that temperature is not collinear
with time: with two cycles their correlation over the poses is ≈ 0.4).  One effect of the
library is injected with a random direction ``d`` (unit vector in its parameter space)
and the size ``m × a*(d)``, where ``a*(d)`` is its minimum detectable size along ``d``
(:meth:`~accelcal.discrepancy.detect.Identifiability.mde_along`) computed on the *true*
pose design with the noise the generator uses: size 1 is where the nested test alone
would detect it with the configured power.  Rows:

* ``none``: no effect (false-positive rate);
* one row per effect and size (power curve, confusion matrix);
* ``temperature_const``: the temperature effect of the largest size, but the
  temperature column never changes, so it acts as a constant offset the bias absorbs:
  expected outcome ``not_identifiable``.

Every recording draws from its own stream, derived from the config seed, its row and its
replicate number (:func:`accelcal_repro.montecarlo.grid_seed`), so it does not depend on the
chunking.  The generator writes the recording (canonical CSV) and a row of the key;
detection (:func:`detect_case`) reads only the recording.  :func:`score` joins the two.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy import stats

from accelcal.atomic import atomic_output
from accelcal.errors import AccelcalError
from accelcal.evaluation import residual_sigma
from accelcal.model import m_from_params
from ..montecarlo import grid_seed
from accelcal.recording import Recording
from accelcal.simulation import random_directions, simulate_recording
from accelcal.static import detect_static_recording
from accelcal.discrepancy.detect import Rules, applicable, discrepancy, identifiability
from accelcal.discrepancy.effects import EFFECT_IDS
from accelcal.discrepancy.fit import fit_at, forward, pose_data

NONE = "none"
NOT_IDENTIFIABLE = "not_identifiable"
CONSTANT_TEMPERATURE = "temperature_const"
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


def expected_outcome(truth: str) -> str:
    """What a correct detector reports for a recording with hidden effect ``truth``."""
    if truth == CONSTANT_TEMPERATURE:
        return NOT_IDENTIFIABLE
    return truth


def plan(effects, sizes, seeds: int, seeds_none: int, seeds_constant: int) -> pd.DataFrame:
    """Every benchmark recording: ``recording, truth, size_mde, replicate`` (fixed order)."""
    rows = [(NONE, 0.0, r) for r in range(seeds_none)]
    for e in effects:
        rows += [(e, float(s), r) for s in sizes for r in range(seeds)]
    if seeds_constant:
        rows += [(CONSTANT_TEMPERATURE, float(max(sizes)), r) for r in range(seeds_constant)]
    df = pd.DataFrame(rows, columns=["truth", "size_mde", "replicate"])
    df.insert(0, "recording", [f"{t}_{s:g}_{r:04d}" for t, s, r in zip(df.truth, df.size_mde, df.replicate)])
    return df


def chunk(df: pd.DataFrame, n_chunks: int, k: int) -> pd.DataFrame:
    """Chunk ``k`` of ``n_chunks``: every ``n_chunks``-th recording (balances rows over chunks)."""
    if not 0 <= k < n_chunks:
        raise AccelcalError(f"chunk {k} outside 0..{n_chunks - 1}")
    return df.iloc[k::n_chunks]


def _rest_windows(session: Session, n_samples_total: int) -> np.ndarray:
    """``[start, stop)`` sample range of every rest of the simulated session."""
    rate = session.rate
    n_init, n_rest, n_move = (int(round(v * rate)) for v in (session.init_rest_s, session.rest_s, session.move_s))
    starts = [0] + [n_init + i * n_move + (i - 1) * n_rest for i in range(1, session.n_poses)]
    stops = [n_init] + [s + n_rest for s in starts[1:]]
    out = np.array([starts, stops]).T
    assert out[-1, 1] == n_samples_total
    return out


def simulate_case(truth: str, size_mde: float, replicate: int, *, seed: int, session: Session,
                  rules: Rules) -> tuple[Recording, dict]:
    """One benchmark recording and its key row.

    Parameters
    ----------
    truth : str
        ``'none'``, an effect id, or ``'temperature_const'``.
    size_mde : float
        Size of the hidden effect in units of its minimum detectable size along its direction.
    replicate : int
    seed : int
        Config seed.
    session : Session
    rules : Rules
        The detection rules (α, power, candidates) that define the MDE.
    """
    if truth not in (NONE, CONSTANT_TEMPERATURE, *EFFECT_IDS):
        raise AccelcalError(f"unknown benchmark row {truth!r}")
    rng = np.random.default_rng(grid_seed(seed, f"discrepancy/{truth}", float(size_mde), int(replicate)))
    ss = session
    g = ss.g
    sens = ss.sensitivity * (1 + rng.uniform(-ss.sensitivity_rel_range, ss.sensitivity_rel_range, 3))
    lo, hi = ss.nonorth_range_deg
    th = np.deg2rad(rng.uniform(lo, hi, 3) * rng.choice((-1.0, 1.0), 3))
    M = m_from_params(sens - 1.0, th)
    bias = ss.offset_counts + rng.uniform(-ss.bias_range_counts, ss.bias_range_counts, 3)
    phase = rng.uniform(0, 2 * np.pi)
    var_mean = ss.noise_counts ** 2 + 1.0 / 12.0  # white noise + rounding to integer counts
    eff_id = "temperature" if truth == CONSTANT_TEMPERATURE else truth
    d = rng.standard_normal(3)
    d /= np.linalg.norm(d)

    for redraws in range(MAX_REDRAWS):
        u = random_directions(rng, ss.n_poses)
        sim = simulate_recording(rng, u, g, np.eye(3), np.zeros(3), 0.0, rate=ss.rate, rest_s=ss.rest_s,
                                 move_s=ss.move_s, init_rest_s=ss.init_rest_s)
        t, x = sim["t"], sim["acc"]  # true specific force (unit of g) along the whole session
        span = t[-1] - t[0] + 1.0 / ss.rate
        temp = ss.temp_mean + ss.temp_amplitude * np.sin(2 * np.pi * ss.temp_cycles * t / span + phase)
        # The design the detection will see: trimmed rests, their mid times and temperatures.
        win = _rest_windows(ss, len(t))
        m = int(round(ss.trim_s * ss.rate))
        win = win + np.array([[m, -m]])
        win[0, 0] = 0  # the session's start borders no motion
        t_mid = np.array([0.5 * (t[a] + t[b - 1]) for a, b in win])
        temp_pose = np.array([temp[a:b].mean() for a, b in win])
        n_eff = (win[:, 1] - win[:, 0]).astype(float)
        mean_std = np.repeat(np.sqrt(var_mean / n_eff)[:, None], 3, axis=1)
        z_pose = forward(g * u, M, bias, {})
        data = pose_data(z_pose, g, mean_std, t_mid, temp_pose, sigma=residual_sigma(z_pose, mean_std, M, bias))
        p_true = np.concatenate([bias, sens - 1.0, th])
        base = fit_at(data, (), p_true)
        cands, _ = applicable(data, rules.candidates)
        idents = {e: identifiability(data, base, e, rules, len(cands)) for e in cands}
        if all(i.identifiable for i in idents.values()):
            break
    else:
        raise AccelcalError(f"{truth}: no pose design with every candidate identifiable in {MAX_REDRAWS} draws")

    params, a_mde, lam = {}, float("nan"), float("nan")
    if truth != NONE:
        ident = idents[eff_id]
        a_mde, lam = ident.mde_along(d), ident.lambda_crit
        params = {eff_id: size_mde * a_mde * d}
    if truth == CONSTANT_TEMPERATURE:
        temp = np.full_like(t, ss.temp_mean + ss.temp_amplitude * np.sin(phase))
    temp = np.round(temp / ss.temp_resolution) * ss.temp_resolution
    # Centre the covariates as the fitter does (mean over the poses), so that the injected
    # parameters are what the extended model estimates.
    dt = t - t_mid.mean()
    dtemp = temp - (temp_pose.mean() if truth != CONSTANT_TEMPERATURE else ss.temp_mean)
    z = forward(x, M, bias, params, dt=dt, dtemp=dtemp)
    z = np.round(z + ss.noise_counts * rng.standard_normal(z.shape))
    rec = Recording(t, z, temp, f"{truth}_{size_mde:g}_{replicate:04d}")

    phi = params.get(eff_id, np.zeros(3))
    key = {
        "truth": truth, "expected": expected_outcome(truth), "effect_injected": eff_id if truth != NONE else NONE,
        "size_mde": float(size_mde), "replicate": int(replicate), "n_poses": ss.n_poses, "redraws": redraws,
        "mde_along": a_mde, "lambda_crit": lam,
        **{f"direction_{a}": float(v) for a, v in zip("xyz", d if truth != NONE else np.full(3, np.nan))},
        **{f"param_{a}": float(v) for a, v in zip("xyz", phi)},
        **{f"absorbed_{e}": idents[e].absorbed for e in EFFECT_IDS if e in idents},
        **{f"bias_{a}": float(v) for a, v in zip("xyz", bias)},
        **{f"sensitivity_{a}": float(v) for a, v in zip("xyz", sens)},
        **{f"nonorth_deg_{k}": float(v) for k, v in zip(("xy", "zx", "zy"), np.rad2deg(th))},
        "temp_range": float(np.ptp(temp)),
    }
    return rec, key


def write_counts_csv(path, rec: Recording) -> None:
    """Write a simulated recording as canonical CSV with integer counts (what a 16-bit
    sensor logs; ~25 % smaller and faster to write than float text), atomically.

    ``read_recording`` returns the same numbers: counts are integers, ``t`` and ``temp``
    are written with 10 significant digits (they are multiples of 0.01)."""
    acc = np.asarray(rec.acc)
    if not np.array_equal(acc, np.round(acc)):
        raise AccelcalError("write_counts_csv needs integer counts")
    df = pd.DataFrame({"t": rec.t, "ax": acc[:, 0].astype(np.int64), "ay": acc[:, 1].astype(np.int64),
                       "az": acc[:, 2].astype(np.int64)})
    if rec.temp is not None:
        df["temp"] = rec.temp
    with atomic_output(path) as tmp:
        df.to_csv(tmp, index=False, float_format="%.10g")


# --------------------------------------------------------------------------- detection


def detect_case(rec: Recording, g: float, rules: Rules) -> dict:
    """Run the deterministic layer on one recording (what ``accelcal discrepancy`` does
    before its stochastic layer); one row of the detection table.  A recording the
    pipeline cannot handle is a row with ``outcome='error'`` and the message.  No timings:
    the table must be byte-identical on a rerun (wall times are in the job's benchmark file)."""
    row = {"outcome": "error", "effect": "", "effects": "", "error": ""}
    try:
        from accelcal.discrepancy.fit import pose_data_from_static

        poses = detect_static_recording(rec)
        res = discrepancy(pose_data_from_static(poses, g), rules)
    except AccelcalError as err:
        row["error"] = str(err).splitlines()[0]
        return row
    s = res.summary()
    row.update(outcome=res.outcome, effect=res.effect, effects="+".join(res.effects),
               not_identifiable="+".join(res.not_identifiable), n_poses_detected=s["n_poses"],
               gap_before=s["gap_before"], gap_after=s["gap_after"], gap_expected_before=s["gap_expected_before"],
               gap_expected_after=s["gap_expected_after"], gap_lopo_before=s["gap_lopo_before"],
               gap_lopo_after=s["gap_lopo_after"], excess_before=s["excess_before"], excess_after=s["excess_after"])
    for c in res.candidates:
        if c.round == 1:
            row[f"p_{c.effect}"] = c.p_value
            row[f"p_adj_{c.effect}"] = c.p_adjusted
            row[f"identifiable_{c.effect}"] = c.identifiable
            row[f"passed_{c.effect}"] = c.passed
    first = [c for c in res.candidates if c.named and c.round == 1]
    if first:
        c = first[0]
        row.update({f"estimate_{a}": v for a, v in zip("xyz", c.estimate)})
        row.update({f"se_{a}": v for a, v in zip("xyz", c.se)})
    return row


# --------------------------------------------------------------------------- scoring


def clopper_pearson(k, n, level: float = 0.95) -> tuple[np.ndarray, np.ndarray]:
    """Exact binomial interval of ``k`` successes in ``n`` (NaN for ``n = 0``)."""
    k = np.asarray(k, float)
    n = np.asarray(n, float)
    a = (1 - level) / 2
    with np.errstate(invalid="ignore", divide="ignore"):
        lo = np.where(k > 0, stats.beta.ppf(a, k, n - k + 1), 0.0)
        hi = np.where(k < n, stats.beta.ppf(1 - a, k + 1, n - k), 1.0)
    bad = n <= 0
    return np.where(bad, np.nan, lo), np.where(bad, np.nan, hi)


def score_cases(key: pd.DataFrame, detections: pd.DataFrame) -> pd.DataFrame:
    """One row per recording: key, detection and ``correct`` (outcome == expected),
    ``detected`` (the injected effect named first; False on effect-free recordings),
    ``false_positive`` (an effect named on a recording without one)."""
    df = key.merge(detections, on="recording", how="left", validate="one_to_one")
    if df["outcome"].isna().any():
        missing = df.loc[df["outcome"].isna(), "recording"].head(3).tolist()
        raise AccelcalError(f"recordings without a detection row: {missing}")
    named = ~df["outcome"].isin([NONE, NOT_IDENTIFIABLE, "error"])
    df["correct"] = df["outcome"] == df["expected"]
    df["detected"] = (df["effect"] == df["effect_injected"]) & (df["truth"] != NONE)
    df["false_positive"] = (df["truth"] == NONE) & named
    return df


def rates(scores: pd.DataFrame, level: float = 0.95) -> pd.DataFrame:
    """Per row (truth, size): counts of each outcome, detection rate and accuracy with
    Clopper–Pearson intervals."""
    out = []
    for (truth, size), d in scores.groupby(["truth", "size_mde"], sort=False):
        n = len(d)
        k_det = int(d["detected"].sum())
        k_ok = int(d["correct"].sum())
        lo_d, hi_d = clopper_pearson(k_det, n, level)
        if truth == NONE:  # nothing to detect: the row's rate is its false-positive rate (summary)
            k_det, lo_d, hi_d = np.nan, np.nan, np.nan
        lo_a, hi_a = clopper_pearson(k_ok, n, level)
        row = {"truth": truth, "size_mde": size, "n": n, "expected": d["expected"].iloc[0],
               "detected": k_det, "detection_rate": k_det / n, "detection_ci_low": float(lo_d),
               "detection_ci_high": float(hi_d), "correct": k_ok, "accuracy": k_ok / n,
               "accuracy_ci_low": float(lo_a), "accuracy_ci_high": float(hi_a),
               "errors": int((d["outcome"] == "error").sum())}
        for o, c in d["outcome"].value_counts().items():
            row[f"n_{o}"] = int(c)
        out.append(row)
    order = {t: i for i, t in enumerate((NONE, *EFFECT_IDS, CONSTANT_TEMPERATURE))}
    df = pd.DataFrame(out)
    if len(df):
        df = df.sort_values(["truth", "size_mde"], key=lambda c: c.map(order) if c.name == "truth" else c,
                            kind="stable").reset_index(drop=True)
    return df


def crossing(sizes, rate, target: float) -> tuple[float, str]:
    """Size (MDE units) where the detection rate first reaches ``target``, linear in
    log(size) between grid points; NaN with a note if the grid does not bracket it."""
    s = np.asarray(sizes, float)
    r = np.asarray(rate, float)
    o = np.argsort(s)
    s, r = s[o], r[o]
    if not len(s):
        return float("nan"), "no data"
    if r[0] >= target:
        return float("nan"), f"reached at the smallest size {s[0]:g}"
    for i in range(1, len(s)):
        if r[i] >= target:
            f = (target - r[i - 1]) / (r[i] - r[i - 1])
            return float(np.exp(np.log(s[i - 1]) + f * (np.log(s[i]) - np.log(s[i - 1])))), ""
    return float("nan"), f"not reached up to size {s[-1]:g}"


def summary(scores: pd.DataFrame, rate_table: pd.DataFrame, *, alpha: float, power: float,
            confusion_size: float) -> pd.DataFrame:
    """The benchmark's findings, one tidy row per (effect, metric), with verdicts.

    Rules (stated in ``rule``): the false-positive rate is consistent with its goal ≤ α
    when the exact 95 % interval's lower end is ≤ α; the naming accuracy at sizes ≥ 1 MDE
    (pooled over those sizes) is consistent with the configured power when its
    interval's upper end is ≥ power (at 1 MDE the nested test alone detects with that
    power, larger sizes more often).
    """
    rows = []
    none = scores[scores.truth == NONE]
    if len(none):
        k, n = int(none["false_positive"].sum()), len(none)
        lo, hi = clopper_pearson(k, n)
        rows.append({"section": "benchmark", "effect": NONE, "metric": "false_positive_rate", "value": k / n,
                     "ci_low": float(lo), "ci_high": float(hi), "n": n, "target": alpha,
                     "verdict": "pass" if lo <= alpha else "fail",
                     "rule": "exact 95% interval of the rate of naming any effect reaches down to alpha"})
        k = int(none["correct"].sum())
        lo, hi = clopper_pearson(k, n)
        rows.append({"section": "benchmark", "effect": NONE, "metric": "accuracy", "value": k / n,
                     "ci_low": float(lo), "ci_high": float(hi), "n": n, "target": np.nan, "verdict": "",
                     "rule": "outcome 'none' (not_identifiable counts as wrong)"})
    for truth, d in scores[scores.truth != NONE].groupby("truth", sort=False):
        if truth == CONSTANT_TEMPERATURE:
            k, n = int(d["correct"].sum()), len(d)
            lo, hi = clopper_pearson(k, n)
            rows.append({"section": "benchmark", "effect": truth, "metric": "accuracy", "value": k / n,
                         "ci_low": float(lo), "ci_high": float(hi), "n": n, "target": power,
                         "verdict": "pass" if hi >= power else "fail",
                         "rule": "outcome not_identifiable; upper end of the exact 95% interval >= power"})
            continue
        big = d[d.size_mde >= 1.0]
        k, n = int(big["correct"].sum()), len(big)
        lo, hi = clopper_pearson(k, n)
        rows.append({"section": "benchmark", "effect": truth, "metric": "accuracy_ge_1mde", "value": k / n if n else np.nan,
                     "ci_low": float(lo), "ci_high": float(hi), "n": n, "target": power,
                     "verdict": ("pass" if hi >= power else "fail") if n else "",
                     "rule": "named correctly at sizes >= 1 MDE (pooled); upper end of the exact 95% interval >= power"})
        at = d[np.isclose(d.size_mde, confusion_size)]
        if len(at):
            k, n = int(at["correct"].sum()), len(at)
            lo, hi = clopper_pearson(k, n)
            rows.append({"section": "benchmark", "effect": truth, "metric": f"accuracy_at_{confusion_size:g}mde",
                         "value": k / n, "ci_low": float(lo), "ci_high": float(hi), "n": n, "target": np.nan,
                         "verdict": "", "rule": "named correctly at the confusion-matrix size"})
        r = rate_table[rate_table.truth == truth].sort_values("size_mde")
        at1 = r[np.isclose(r.size_mde, 1.0)]
        if len(at1):
            a = at1.iloc[0]
            rows.append({"section": "benchmark", "effect": truth, "metric": "detection_rate_at_1mde",
                         "value": a.detection_rate, "ci_low": a.detection_ci_low, "ci_high": a.detection_ci_high,
                         "n": int(a.n), "target": power, "verdict": "",
                         "rule": "the MDE is defined as the size detected with this power by the nested test alone"})
        for target in (0.5, 0.95):
            v, note = crossing(r.size_mde, r.detection_rate, target)
            rows.append({"section": "benchmark", "effect": truth, "metric": f"size_at_{int(target * 100)}pct_mde",
                         "value": v, "ci_low": np.nan, "ci_high": np.nan, "n": int(r.n.sum()), "target": np.nan,
                         "verdict": "", "rule": note or "linear interpolation in log(size) of the detection rate"})
    return pd.DataFrame(rows, columns=["section", "effect", "metric", "value", "ci_low", "ci_high", "n", "target",
                                       "verdict", "rule"])


__all__ = ["CONSTANT_TEMPERATURE", "NONE", "NOT_IDENTIFIABLE", "Session", "chunk", "clopper_pearson", "crossing",
           "detect_case", "expected_outcome", "plan", "rates", "score_cases", "simulate_case", "summary",
           "write_counts_csv"]

