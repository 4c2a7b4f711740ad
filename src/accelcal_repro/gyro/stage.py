"""The gyro stage in one call: integrator study, Monte Carlo, real sessions and peers, claims.

:func:`run` writes into ``out``: ``integrators.csv/.png``, ``montecarlo.csv``,
``montecarlo_timing.csv``, ``montecarlo.png``, ``ipopt_check.csv``, ``sessions/*.csv``,
``sessions/figure_of_merit.png`` and ``claims.csv`` (the ledger's columns, ``paper =
gyro``), each claim's verdict computed from those tables by the rule stated in its text.
``config`` keys (all optional): ``seed``, ``mc_trials``, ``integrator_motions``,
``peers_dir`` (IMU-TK's and imucal's recorded outputs, ``tools/gyro_peers.py``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

COLUMNS = ("paper", "claim_id", "claim", "paper_value", "reproduced_value", "verdict", "evidence")


def _claim(cid: str, text: str, target: str, value: str, passed: bool, evidence: str) -> dict:
    return dict(zip(COLUMNS, ("gyro", cid, text, target, value, "reproduced" if passed else "not_reproduced",
                              evidence)))


def claims(integ: pd.DataFrame, mc: pd.DataFrame, ipopt: pd.DataFrame, fom: pd.DataFrame,
           peer_parameters: pd.DataFrame) -> pd.DataFrame:
    """The stage's claims with verdicts computed from its tables."""
    from .integrators import choose
    from .montecarlo import summary

    rows = []
    best = choose(integ)
    hand = integ[(integ.rate_dps <= 250) & (integ.fs_hz == 100)]
    rk4 = float(hand[hand.method == "rk4"].abs_scale_bias_ppm.max())
    rows.append(_claim("integrator_choice", "Magnus-4 (cubic rate) has the smallest median angle error of the five "
                       "integrators at hand-motion rates (<= 5 deg per sample)", "magnus4", best, best == "magnus4",
                       "integrators.csv: median rel_angle_rms_ppm over rate/fs <= 5 deg"))
    rows.append(_claim("rk4_scale_bias", "IMU-TK's RK4 induces a scale-factor bias below 10 ppm up to 250 deg/s at "
                       "100 Hz", "< 10 ppm", f"{rk4:.2g} ppm", rk4 < 10, "integrators.csv: abs_scale_bias_ppm"))
    s = summary(mc)
    it = s["iterative"].to_numpy()
    rows.append(_claim("iterative_efficient", "the iterative gyro estimate reaches the Cramér–Rao bound: median RMS "
                       "error / CRLB of scales and misalignments within 0.8-1.2 in every configuration", "0.8-1.2",
                       f"{np.nanmin(it):.2f}-{np.nanmax(it):.2f}", bool(np.all((it > 0.8) & (it < 1.2))),
                       "montecarlo.csv: ratio, median per kind"))
    one = s["one_step"]
    base = float(one.loc["base"].max())
    worst = float(one.to_numpy().max())
    rows.append(_claim("one_step_enough_at_base", "the one-step estimate (one linearised solve about C = I) is within "
                       "20 % of the bound for 2 % scale errors, 1 deg misalignments and MEMS noise", "<= 1.2",
                       f"{base:.2f}", base <= 1.2, "montecarlo.csv: config base"))
    rows.append(_claim("one_step_not_enough", "the one-step estimate exceeds 1.5x the bound somewhere in the grid "
                       "(large errors from nominal, low noise, long motions)", "> 1.5", f"{worst:.2f}", worst > 1.5,
                       "montecarlo.csv: max median ratio"))
    d = float(ipopt.max_diff_in_se.iloc[0])
    rows.append(_claim("gauss_newton_equals_ipopt", "Gauss-Newton with the analytic Jacobian finds IPOPT's minimum "
                       "(within 0.1 standard error)", "< 0.1 s.e.", f"{d:.3f} s.e.", d < 0.1, "ipopt_check.csv"))
    own = fom[fom.bias == "own_bias"].pivot(index="session", columns="calibration", values="rms_deg")
    if "imutk_run" in own:
        both = own.dropna(subset=["accelcal", "imutk_run"])
        wins = int((both.accelcal <= both.imutk_run).sum())
        rows.append(_claim("figure_of_merit_vs_imutk", "accelcal's gyro calibration carries gravity from rest to rest "
                           "at least as well as IMU-TK's (RMS misfit) on every session both calibrate", "all",
                           f"{wins} of {len(both)}", wins == len(both), "sessions/figure_of_merit.csv, own_bias"))
    x = peer_parameters[(peer_parameters.session == "xsens") & (peer_parameters.peer == "factory")
                        & peer_parameters.parameter.str.startswith("K_")]
    if len(x):
        rel = float(np.max(np.abs(x.ours / x.peer_value - 1)))
        rows.append(_claim("xsens_data_sheet", "the Xsens gyro sensitivities (counts per rad/s) agree with the data "
                           "sheet within 0.2 %", "< 0.2 %", f"{100 * rel:.2f} %", rel < 2e-3,
                           "sessions/peer_parameters.csv: K_x..K_z, peer factory"))
    return pd.DataFrame(rows, columns=COLUMNS)


def run(out: Path, config: dict | None = None) -> dict[str, pd.DataFrame]:
    from accelcal.plotting import save_figure

    from . import integrators, ipopt_check, montecarlo, report

    cfg = dict(config or {})
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    seed = int(cfg.get("seed", 24))
    integ = integrators.integrator_study(seed=seed, n_motions=int(cfg.get("integrator_motions", 20)))
    integ.to_csv(out / "integrators.csv", index=False)
    save_figure(integrators.figure(integ), out / "integrators")
    mc, timing = montecarlo.monte_carlo(n_trials=int(cfg.get("mc_trials", 100)), seed=seed)
    mc.to_csv(out / "montecarlo.csv", index=False)
    timing.to_csv(out / "montecarlo_timing.csv", index=False)
    save_figure(montecarlo.figure(mc), out / "montecarlo")
    ipopt = ipopt_check.crosscheck(seed=seed)
    ipopt.to_csv(out / "ipopt_check.csv", index=False)
    peers = Path(cfg.get("peers_dir", out / "peers"))
    tabs = report.run(out / "sessions", peers)
    save_figure(report.figure(tabs["figure_of_merit"], tabs["imucal_figure_of_merit"]),
                out / "sessions" / "figure_of_merit")
    led = claims(integ, mc, ipopt, tabs["figure_of_merit"], tabs["peer_parameters"])
    led.to_csv(out / "claims.csv", index=False)
    return {"integrators": integ, "montecarlo": mc, "timing": timing, "ipopt": ipopt, "claims": led, **tabs}


__all__ = ["claims", "run"]
