"""The gyro loop's benchmark: simulated sessions with one effect hidden, through the user's route.

Each case simulates a multi-position recording (:func:`accelcal.gyro.simulate.simulate_recording`:
an initial rest, ``n_motions`` random turns between rests, white noise), hides one candidate
effect of :data:`accelcal.discrepancy.gyro_loop.CANDIDATES` in the raw gyro samples, and
runs what ``accelcal discrepancy`` runs: the static poses, the accelerometer calibration,
the gyro calibration, then the gyro loop.  Effect-free cases give the false-positive rate
(anything named); a case with an effect of ``k`` times its minimum detectable effect
(the loop's own MDE on an effect-free session of the same design) gives the power (that
effect named).

The hidden effects (one parameter each, on the x gyro): ``g_sensitivity`` ``G_xz`` (the
x gyro reads ``G f_z``), ``scale_asymmetry`` (negative x rates read ``1 + a`` times),
``rate_nonlinearity`` (x reads ``q ω|ω|``), ``motion_bias`` (x reads ``Δb`` while moving),
``time_offset`` (the gyro ``δ`` late, whole samples; the loop calls it not identifiable between
the gyro's still rests, so it has no MDE and no power row), ``sample_clock`` (a sample clock whose
rate wanders, ``1 + A sin(2π t/P)``, as the stamps record it, while the samples were taken
``1 + w A sin(2π t/P)``: ``w = 1`` stamps right, the nominal rate wrong; simulated at 1 kHz
without noise, interpolated onto the sample times, noise added after).  ``clock_rate`` is
not hidden: a common rate error is absorbed by the scales between rests.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from accelcal.calibration import calibrate_recording
from accelcal.discrepancy.gyro_loop import gyro_discrepancy, gyro_motions
from accelcal.gyro.recording import MIN_RESTS, calibrate_recording_gyro
from accelcal.gyro.simulate import simulate_recording
from accelcal.recording import Recording

from ..claims import Claim, MinimumSample
from ..discrepancy.claims import minimum
from ..discrepancy.scoring import clopper_pearson

#: The parameter each hidden effect sets (first of its candidate's on the x gyro).
HIDDEN = {"g_sensitivity": "G_xz", "scale_asymmetry": "a_x", "rate_nonlinearity": "q_x", "time_offset": "delta_t",
          "motion_bias": "db_x", "sample_clock": "w_stamps"}
LOOP_SIZE = Claim("gyro", "loop_false_positives", "On effect-free simulated sessions the gyro loop names an effect "
                  "at a family-wise rate no larger than alpha = 0.05: the upper end of its 95 % Clopper-Pearson "
                  "interval is at most 2 alpha", "upper bound <= 0.10")
LOOP_POWER = Claim("gyro", "loop_power_3x_mde", "At 3 times its minimum detectable effect every hidden gyro effect "
                   "is named on at least 80 % of simulated sessions", ">= 0.8")
#: Effect-free sessions before the size rule decides: the accelerometer loop's rule, one function
#: (a loop whose true rate is 0.7 alpha = 0.035 fails it with probability below 1 % at this size and
#: every larger one: 280 at alpha 0.05; 0.050 on 200, 0.16 on 150, 0.27 on 100: binomial, Clopper-Pearson).
SIZE_MINIMUM = minimum("fpr_decided", unit="effect-free sessions")
#: Sessions per candidate at 3x MDE: the power's binomial s.e. at 0.8 below 0.09.
POWER_MINIMUM = MinimumSample(20, "sessions per candidate at 3x MDE", "with fewer, the power's binomial standard "
                              "error exceeds 0.09")
#: The stamps' clock-rate wander of the ``sample_clock`` cases: amplitude (relative) and period [s].
CLOCK = {"amplitude": 0.01, "period_s": 45.0}
DESIGN = {"n_motions": 24, "angle_deg": 100.0, "peak_rate_dps": 150.0, "rest_s": 3.0, "init_rest_s": 10.0,
          "gyro_noise": 0.003, "acc_noise": 0.01}


def _hide(sim: dict, effect: str | None, size: float) -> np.ndarray:
    gyro = np.array(sim["gyro"], float)
    if effect is None or size == 0.0:
        return gyro
    w = sim["rates"]
    if effect == "g_sensitivity":
        gyro[:, 0] += size * _specific_force(sim)[:, 2]
    elif effect == "scale_asymmetry":
        gyro[:, 0] += size * np.where(w[:, 0] < 0, w[:, 0], 0.0)
    elif effect == "rate_nonlinearity":
        gyro[:, 0] += size * w[:, 0] * np.abs(w[:, 0])
    elif effect == "motion_bias":
        gyro[:, 0] += size * (np.linalg.norm(w, axis=1) > 0)
    elif effect == "time_offset":
        k = int(round(size / (sim["t"][1] - sim["t"][0])))  # whole samples: no interpolation that smooths the noise
        if k:
            gyro = np.concatenate([np.repeat(gyro[:1], k, axis=0), gyro[:-k]])
    else:
        raise KeyError(effect)
    return gyro


def _specific_force(sim: dict) -> np.ndarray:
    """The simulated specific force, from the accelerometer's truth (``acc = M f + b + noise``)."""
    return (np.asarray(sim["acc"]) - sim["acc_bias"]) @ np.linalg.inv(sim["M"]).T


def clock_recording(rng, size: float, design=None, fs: float = 100.0, fine: int = 10) -> Recording:
    """A recording whose stamps record a wandering sample clock (module docstring), its samples
    taken on a clock that wanders ``size`` times as much."""
    d = {**DESIGN, **(design or {})}
    sim = simulate_recording(rng, **{**d, "fs": fs * fine, "gyro_noise": 0.0, "acc_noise": 0.0})
    t_fine = sim["t"]
    n = int(len(t_fine) / fine * 0.97)  # the wander may stretch the clock by its amplitude
    grid = np.arange(n) / fs
    wander = CLOCK["amplitude"] * np.sin(2 * np.pi * grid / CLOCK["period_s"])
    stamps = np.concatenate([[0.0], np.cumsum((1 + wander[:-1]) / fs)])
    taken = np.concatenate([[0.0], np.cumsum((1 + size * wander[:-1]) / fs)])
    acc = np.column_stack([np.interp(taken, t_fine, sim["acc"][:, k]) for k in range(3)])
    gyro = np.column_stack([np.interp(taken, t_fine, sim["gyro"][:, k]) for k in range(3)])
    acc += d["acc_noise"] * rng.standard_normal(acc.shape)
    gyro += d["gyro_noise"] * rng.standard_normal(gyro.shape)
    return Recording(t=stamps, acc=acc, temp=None, source="clock", unit="m/s^2", gyro=gyro, gyro_unit="rad/s")


def run_case(seed: int, effect: str | None = None, size: float = 0.0, n_boot: int = 199, design=None,
             noise: str = "common") -> dict:
    """One simulated session through the loop: what it named, and the hidden parameter's MDE."""
    rng = np.random.default_rng(seed)
    if effect == "sample_clock":
        rec = clock_recording(rng, size, design)
        sim = {"g": DESIGN.get("g", 9.81)}
    else:
        sim = simulate_recording(rng, **{**DESIGN, **(design or {})})
        rec = Recording(t=sim["t"], acc=sim["acc"], temp=None, source=f"sim{seed}", unit="m/s^2",
                        gyro=_hide(sim, effect, size), gyro_unit="rad/s")
    acc, poses = calibrate_recording(rec, sim["g"], "full_lls", search=True, min_poses=MIN_RESTS)
    gcal = calibrate_recording_gyro(rec, acc, poses, g_sensitivity=False)  # the loop decides it
    res = gyro_discrepancy(gyro_motions(rec, acc, poses, gcal, noise), n_boot=n_boot, seed=seed)
    mde = {}
    for c, row in res.rounds[0].items():
        if row.get("status") == "tested":
            mde[c] = float(row["mde"][row["params"].index(HIDDEN[c])]) if c in HIDDEN else float(row["mde"][0])
    return {"seed": seed, "effect": effect or "none", "size": size, "named": list(res.named),
            "mde": mde, "not_identifiable": [c for c, r in res.rounds[0].items() if r["status"] == "not_identifiable"],
            "excess_before": res.excess_before, "excess_after": res.excess_after,
            "estimates": {c: {p: list(v) for p, v in e.items()} for c, e in res.estimates.items()}}


def run_benchmark(n_null: int = 20, n_effect: int = 10, multiples=(0.5, 1.0, 3.0), seed: int = 1, n_boot: int = 999,
                  candidates=tuple(HIDDEN), noise: str = "common", design=None) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Effect-free cases (FPR) and ``n_effect`` cases per candidate and multiple of its MDE (power).

    Returns the per-case rows and the summary, one row per candidate and multiple: the
    family-wise false-positive rate (anything named on an effect-free session) with its
    Clopper-Pearson 95 % interval, the rate of that candidate named on them (``fpr_this``;
    for ``sample_clock`` on sessions of its own whose stamps wander while the samples are even),
    the power (that candidate named), the MDE used (median over the effect-free sessions)
    and the share of them on which it was identifiable.
    """
    kw = {"n_boot": n_boot, "noise": noise, "design": design}
    null = [run_case(seed + i, **kw) for i in range(n_null)]
    rows, summary = list(null), []
    k = int(sum(bool(r["named"]) for r in null))
    lo, hi = clopper_pearson(k, n_null)
    fpr = {"fpr_any": k / max(n_null, 1), "fpr_lo": float(lo), "fpr_hi": float(hi), "n_null": n_null}
    for c in candidates:
        own = null
        if c == "sample_clock":  # its effect-free sessions: stamps that wander, samples taken evenly (w = 0)
            own = [run_case(seed + 500 + i, c, 0.0, **kw) for i in range(n_null)]
            rows += own
        mdes = [r["mde"][c] for r in own if c in r["mde"]]
        this = float(np.mean([c in r["named"] for r in own])) if own else float("nan")
        for j, mult in enumerate(multiples):
            row = {"candidate": c, "parameter": HIDDEN[c], "multiple": float(mult), **fpr, "fpr_this": this,
                   "identifiable": len(mdes) / max(n_null, 1)}
            if not mdes:
                summary.append({**row, "mde": float("nan"), "power": float("nan"), "n_effect": 0})
                continue
            mde = float(np.median(mdes))
            cases = [run_case(seed + 1000 * (j + 1) + i, c, mult * mde, **kw) for i in range(n_effect)]
            rows += cases
            summary.append({**row, "mde": mde, "power": float(np.mean([c in r["named"] for r in cases])),
                            "n_effect": n_effect})
    return pd.DataFrame(rows), pd.DataFrame(summary)


def loop_claims(summary: pd.DataFrame | None) -> list[dict]:
    """The benchmark's two ledger rows (:data:`LOOP_SIZE`, :data:`LOOP_POWER`) from its summary."""
    if summary is None or not len(summary) or "fpr_hi" not in summary:
        why = "no gyro loop benchmark (gyro/loop/benchmark_summary.csv)"
        return [LOOP_SIZE.not_reproducible(why), LOOP_POWER.not_reproducible(why)]
    src = "results/gyro/loop/benchmark_summary.csv"
    first = summary.iloc[0]
    size = LOOP_SIZE.judge(float(first.fpr_hi), float(first.fpr_hi) <= 0.10,
                           f"{src}: fpr_any {first.fpr_any:.3f} [{first.fpr_lo:.3f}, {first.fpr_hi:.3f}]",
                           scale=SIZE_MINIMUM.at(float(first.n_null)))
    at3 = summary[(summary.multiple == 3.0) & (summary.n_effect > 0)]
    if not len(at3):
        return [size, LOOP_POWER.not_reproducible("no candidate identifiable on the simulated sessions")]
    worst = float(at3.power.min())
    shown = ", ".join(f"{r.candidate} {r.power:.2f}" for r in at3.itertuples())
    power = LOOP_POWER.judge(worst, worst >= 0.8, f"{src}: power at multiple 3 ({shown})",
                             scale=POWER_MINIMUM.at(float(at3.n_effect.min())))
    return [size, power]


def benchmark_tables(config: dict) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The workflow's gyro loop benchmark (config ``gyro.loop.benchmark``): cases and summary."""
    c = config["loop"]["benchmark"]
    cases, summary = run_benchmark(int(c["n_null"]), int(c["n_effect"]), tuple(float(m) for m in c["multiples"]),
                                   seed=int(config["seed"]), n_boot=int(c["n_boot"]),
                                   noise=config["loop"].get("noise", "common"))
    cases = cases.assign(named=cases.named.map(lambda v: ",".join(v) or "none"),
                         not_identifiable=cases.not_identifiable.map(",".join),
                         mde=cases.mde.map(lambda m: ";".join(f"{k}={v:.4g}" for k, v in m.items())),
                         estimates=cases.estimates.map(lambda e: ",".join(e)))
    return cases, summary


__all__ = ["CLOCK", "DESIGN", "HIDDEN", "LOOP_POWER", "LOOP_SIZE", "benchmark_tables", "clock_recording", "loop_claims", "run_benchmark", "run_case"]
