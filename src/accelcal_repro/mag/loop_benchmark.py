"""The magnetometer loop's benchmark: simulated sessions with one effect hidden.

Each case simulates a session turned through the whole sphere (a spiral of the field's
direction from pole to pole and back, a random orientation per case), hard iron, a field of :data:`DESIGN` ``field``
raw units and noise that is not white: AR(1) per axis with lag-1 correlation ``rho``
(a low-passed sensor, as the real sessions' residuals show), and a temperature column that
drifts.  One effect of :data:`accelcal.discrepancy.mag_loop.CANDIDATES` is hidden, with
one parameter: ``soft_iron`` ``A_xy``, ``disturbance`` ``db_x`` during the middle third
of the session, ``temperature`` ``kb_x`` (the x hard iron drifting with temperature).
Effect-free cases give the false-positive rate (anything named); a case with an effect of
``k`` times its minimum detectable effect (the loop's own MDE on effect-free sessions, the
median) gives the power (that effect named).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from accelcal.discrepancy.mag_loop import CANDIDATE_NAMES, mag_discrepancy
from accelcal.mag.fit import FieldSamples
from accelcal.mag.model import rotvec_to_matrix

HIDDEN = {"soft_iron": "A_xy", "disturbance": "db_x", "temperature": "kb_x"}
DESIGN = {"n_samples": 1200, "turns": 8, "field": 50.0, "noise_rel": 0.005, "rho": 0.5,
          "hard_iron": (12.0, -7.0, 4.0), "temp_range": 15.0}


def simulate(rng, effect: str | None = None, size: float = 0.0, design=None) -> tuple[np.ndarray, np.ndarray, float]:
    """Raw field samples (n, 3), temperature (n,) and the noise's std of one simulated session."""
    d = {**DESIGN, **(design or {})}
    n = int(d["n_samples"])
    s = np.linspace(0, 1, n)
    # pole to pole and back, so that a temperature drifting one way is not the sweep's own direction
    th, ph = np.arccos(np.cos(2 * np.pi * s)), 2 * np.pi * d["turns"] * s
    h = np.column_stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)])
    h = h @ rotvec_to_matrix(rng.normal(size=3)).T
    A = np.eye(3) / d["field"]
    if effect == "soft_iron":
        A[0, 1] = A[1, 0] = size
    temp = 25 + d["temp_range"] * (s - 0.5) + 0.2 * rng.standard_normal(n)
    m = np.asarray(d["hard_iron"]) + h @ np.linalg.inv(A).T
    sigma = d["noise_rel"] * d["field"]
    e = rng.standard_normal((n, 3)) * sigma * np.sqrt(1 - d["rho"] ** 2)
    e[0] /= np.sqrt(1 - d["rho"] ** 2)
    for k in range(1, n):  # AR(1) with stationary variance sigma²
        e[k] += d["rho"] * e[k - 1]
    m = m + e
    if effect == "disturbance":
        m[n // 3:2 * n // 3, 0] += size
    elif effect == "temperature":
        m[:, 0] += size * (temp - temp.mean())
    return m, temp, sigma


def run_case(seed: int, effect: str | None = None, size: float = 0.0, n_boot: int = 199, design=None,
             alpha: float = 0.05) -> dict:
    """One simulated session through the loop: what it named, and the hidden parameters' MDE."""
    m, temp, sigma = simulate(np.random.default_rng(seed), effect, size, design)
    res = mag_discrepancy(FieldSamples(m, noise_cov=np.eye(3) * sigma**2), temp, n_boot=n_boot, seed=seed, alpha=alpha)
    mde = {}
    for c, row in res.rounds[0].items():
        if row.get("status") == "tested":
            mde[c] = float(row["mde"][row["params"].index(HIDDEN[c])])
    return {"seed": seed, "effect": effect or "none", "size": size, "named": list(res.named), "mde": mde,
            "excess_before": res.excess_before, "excess_after": res.excess_after}


def run_benchmark(n_null: int = 40, n_effect: int = 15, multiple: float = 3.0, seed: int = 1, n_boot: int = 199,
                  candidates=CANDIDATE_NAMES, design=None, alpha: float = 0.05) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Effect-free cases (FPR) and ``n_effect`` cases per candidate at ``multiple`` × its MDE (power).

    The summary per candidate: ``fpr_any`` (anything named on effect-free sessions), ``fpr_this``
    (that candidate named), ``power`` at ``multiple`` × the median MDE, the MDE, and the share
    of effect-free sessions on which it was identifiable."""
    null = [run_case(seed + i, n_boot=n_boot, design=design, alpha=alpha) for i in range(n_null)]
    rows, summary = list(null), []
    any_named = float(np.mean([bool(r["named"]) for r in null]))
    for c in candidates:
        mdes = [r["mde"][c] for r in null if c in r["mde"]]
        base = {"candidate": c, "parameter": HIDDEN[c], "fpr_any": any_named, "n_null": n_null,
                "fpr_this": float(np.mean([c in r["named"] for r in null])), "identifiable": len(mdes) / n_null}
        if not mdes:
            summary.append({**base, "mde": float("nan"), "power": float("nan"), "n_effect": 0})
            continue
        mde = float(np.median(mdes))
        cases = [run_case(seed + 1000 + i, c, multiple * mde, n_boot=n_boot, design=design, alpha=alpha)
                 for i in range(n_effect)]
        rows += cases
        summary.append({**base, "mde": mde, "power": float(np.mean([c in r["named"] for r in cases])),
                        "n_effect": n_effect})
    return pd.DataFrame(rows), pd.DataFrame(summary)


__all__ = ["DESIGN", "HIDDEN", "run_benchmark", "run_case", "simulate"]
