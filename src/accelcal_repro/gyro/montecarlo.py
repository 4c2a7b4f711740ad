"""The one-step gyro estimate beside the iterative one, against the Cramér–Rao bound.

Each trial draws a true gyro matrix (scale errors of ``scale_std``, misalignments of
``misalignment_deg``, nominal ``C0 = I``), a session of ``n_motions`` random motions of
``angle_deg`` at ``rate_dps`` between rests (:func:`accelcal.gyro.simulate.simulate_session`),
gyro white noise ``gyro_noise`` [rad/s per sample at ``fs``] and accelerometer pose noise
``direction_noise`` [rad per tangent component].  Both estimators start from the nominal
model; the bound is the Fisher information of the same first-order model at the truth
(:func:`accelcal.gyro.fit.crlb`), averaged over the trials' covariances.

Configurations: a base case and one factor varied at a time (noise, motions, angle,
rate, distance of the truth from the nominal model).

Tidy tables:

* ``montecarlo.csv``: ``config, factor, value, estimator, parameter, rms_error,
  crlb_std, ratio`` (``ratio`` = RMS error / CRLB std; 1 is efficient);
* ``montecarlo_timing.csv``: ``config, estimator, median_s, p90_s, failures``.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from accelcal.errors import AccelcalError
from accelcal.gyro.fit import crlb
from accelcal.gyro.model import C_PARAMETERS
from accelcal.gyro.simulate import random_gyro_matrix, simulate_session
from accelcal.registry import estimators

BASE = {"n_motions": 20, "angle_deg": 90.0, "rate_dps": 150.0, "fs": 100.0, "gyro_noise": 0.005,
        "direction_noise": 2e-4, "scale_std": 0.02, "misalignment_deg": 1.0}
#: One factor at a time: name -> values (the base value is one of them).
FACTORS = {"gyro_noise": (0.0005, 0.005, 0.05), "n_motions": (8, 20, 60), "angle_deg": (30.0, 90.0, 180.0),
           "rate_dps": (50.0, 150.0, 400.0), "scale_std": (0.005, 0.02, 0.06)}
#: The registry's gyro estimators of motions, by algorithm (the tables' ``estimator`` column).
ESTIMATORS = {e.algorithm: e for e in estimators("gyroscope", data="motions")}
AXIS_LABELS = {"gyro_noise": "gyro noise [rad/s per sample]", "n_motions": "motions",
               "angle_deg": "angle per motion [deg]",
               "rate_dps": "peak rate [deg/s]", "scale_std": "scale errors (std) from nominal"}


def configurations(factors=FACTORS, base=BASE):
    """(config name, factor, value, settings) for the base and every other value of each factor."""
    out = [("base", "base", "", dict(base))]
    for f, values in factors.items():
        for v in values:
            if v != base[f]:
                out.append((f"{f}={v:g}", f, v, {**base, f: v}))
    return out


def run_config(settings: dict, n_trials: int, seed: int, integrator: str = "magnus4"):
    """Errors (trials, 9) of each estimator, the mean CRLB (9, 9), the times and failures."""
    rng = np.random.default_rng(seed)
    errors = {k: [] for k in ESTIMATORS}
    seconds = {k: [] for k in ESTIMATORS}
    failures = {k: 0 for k in ESTIMATORS}
    bounds = []
    noise = settings["gyro_noise"]
    for _ in range(n_trials):
        C = random_gyro_matrix(rng, settings["scale_std"], settings["misalignment_deg"])
        s = simulate_session(rng, n_motions=int(settings["n_motions"]), angle_deg=settings["angle_deg"],
                             peak_rate_dps=settings["rate_dps"], fs=settings["fs"], C=C, gyro_noise=noise,
                             direction_noise=settings["direction_noise"], rest_s=0.5)
        bounds.append(crlb(s.clean, C, integrator))
        for name, e in ESTIMATORS.items():
            try:
                f = e.load()(s.data, np.eye(3), integrator)
            except (AccelcalError, np.linalg.LinAlgError):
                failures[name] += 1
                continue
            errors[name].append((f.C - C).reshape(9))
            seconds[name].append(f.seconds)
    return ({k: np.array(v) for k, v in errors.items()}, np.mean(bounds, axis=0), seconds, failures)


def monte_carlo(n_trials: int = 100, seed: int = 24, factors=FACTORS, base=BASE,
                integrator: str = "magnus4") -> tuple[pd.DataFrame, pd.DataFrame]:
    """The two tidy tables of the module docstring."""
    rows, timing = [], []
    for i, (name, factor, value, settings) in enumerate(configurations(factors, base)):
        errors, bound, seconds, failures = run_config(settings, n_trials, seed + 1000 * i, integrator)
        crlb_std = np.sqrt(np.diag(bound))
        for est, e in errors.items():
            rms = np.sqrt(np.mean(e ** 2, axis=0)) if len(e) else np.full(9, np.nan)
            for p, r, c in zip(C_PARAMETERS, rms, crlb_std):
                rows.append({"config": name, "factor": factor, "value": value, "estimator": est, "parameter": p,
                             "kind": "scale" if p[1] == p[2] else "misalignment", "rms_error": r, "crlb_std": c,
                             "ratio": r / c, "trials": len(e)})
            t = np.array(seconds[est])
            timing.append({"config": name, "estimator": est, "median_s": float(np.median(t)) if len(t) else np.nan,
                           "p90_s": float(np.percentile(t, 90)) if len(t) else np.nan, "trials": n_trials,
                           "failures": failures[est]})
    return pd.DataFrame(rows), pd.DataFrame(timing)


def summary(table: pd.DataFrame) -> pd.DataFrame:
    """Median ratio per configuration, estimator and kind of parameter (scale, misalignment)."""
    return table.groupby(["config", "estimator", "kind"], sort=False).ratio.median().unstack(["estimator", "kind"])


def figure(table: pd.DataFrame):
    """RMS error / CRLB (median over the parameters of a kind) vs each factor, both estimators."""
    import matplotlib.pyplot as plt

    from accelcal.plotting import RC

    factors = [f for f in table.factor.unique() if f != "base"]
    base = table[table.factor == "base"]
    with plt.rc_context(RC):
        fig, axes = plt.subplots(1, len(factors), figsize=(2.1 * len(factors) + 0.8, 3.0), sharey=True,
                                 layout="constrained", squeeze=False)
        for ax, f in zip(axes[0], factors):
            sub = pd.concat([table[table.factor == f], base.assign(value=BASE[f])])
            for est, color in (("one_step", "C3"), ("iterative", "C0")):
                for kind, ls in (("scale", "-"), ("misalignment", "--")):
                    s = sub[(sub.estimator == est) & (sub.kind == kind)].groupby("value").ratio.median()
                    ax.plot(s.index.astype(float), s.values, ls, marker="o", ms=3, color=color,
                            label=f"{est.replace('_', '-')}, {kind}")
            ax.set_xscale("log")
            vals = sorted(float(v) for v in sub.value.unique())
            ax.set_xticks(vals, [f"{v:g}" for v in vals])
            ax.minorticks_off()
            ax.axhline(1.0, color="0.4", lw=0.8)
            ax.set_ylim(bottom=0)
            ax.set_xlabel(AXIS_LABELS.get(f, f))
        axes[0, 0].set_ylabel("RMS error / CRLB")
        axes[0, -1].legend(fontsize=6.5, handlelength=3.0)
        fig.suptitle("gyro: one-step (one linearised solve about C = I) vs iterative, against the Cramér–Rao bound",
                     fontsize=8.5)
    return fig


__all__ = ["BASE", "ESTIMATORS", "FACTORS", "configurations", "figure", "monte_carlo", "run_config", "summary"]
