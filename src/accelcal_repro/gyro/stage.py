"""The gyro stage: its pieces (each a workflow job) and its claims, with verdicts computed from its tables.

Pieces (``workflow/rules/gyro.smk`` runs each as a job; :func:`run` all in one process, for
tests): :func:`integrator_table` (:mod:`.integrators`), :func:`monte_carlo_tables`
(:mod:`.montecarlo`), :func:`coverage_tables` (:mod:`.coverage`), :func:`ipopt_table` (:mod:`.ipopt_check`), :func:`accelcal_repro.gyro.report.run`
(the real sessions and the peers) and :func:`claims`.  ``config`` is the workflow config's
``gyro`` section (``config/config.yaml``).

Claims (paper key ``gyro``: the project's own goals for the gyroscope, judged like the
papers'), each rule stated in its text:

* the integrator chosen from the measured error, and the scale-factor bias IMU-TK's RK4
  induces at hand-motion rates;
* the iterative estimate at the Cramér–Rao bound; where the one-step estimate is enough
  and where it is not; Gauss-Newton finds IPOPT's minimum;
* the 95 % intervals' coverage in a Monte Carlo with a wandering bias (:mod:`.coverage`),
  and the session-to-session χ²/dof of scales and misalignments on the real sessions;
* on the real sessions: the figure of merit against IMU-TK (published results, and its run
  from source when the config names it), the Xsens sensitivities against the data sheet,
  the imucal session against imucal itself.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd

from . import coverage, integrators, montecarlo, report
from ..claims import COLUMNS, Claim, MinimumSample
from .integrators import choose, integrator_study
from .ipopt_check import crosscheck
from .loop_benchmark import loop_claims
from .montecarlo import monte_carlo, summary

#: Standard deviation of the median of m independent unit normals (order statistics: m = 3
#: the middle one, m = 6 the mean of the middle two), relative to one of them.
_MEDIAN_SD = {3: 0.670, 6: 0.535}
_Z = 2.0


def ratio_rule_minimum(margin: float) -> MinimumSample:
    """Trials a rule "the median RMS / CRLB of a kind is within ``margin`` of its limit" needs:
    an RMS over T trials has relative standard deviation 1/sqrt(2T) (chi distribution), the
    median of the 3 scales sd 0.670 of that; ``_Z`` of them must fit inside ``margin`` (ratio
    about 1): T >= (z 0.670 / margin)^2 / 2.  Fewer, and the sampling noise alone decides."""
    needed = math.ceil((_Z * _MEDIAN_SD[3] / margin) ** 2 / 2)
    return MinimumSample(needed, "Monte Carlo trials per configuration",
                         f"with fewer, {_Z:g} standard errors of a median RMS / CRLB exceed the rule's margin "
                         f"{margin:g}")

INTEGRATOR_CHOICE = Claim("gyro", "integrator_choice", "The Magnus-4 integrator (cubic rate) has the smallest median "
                          "angle error of the five integrators at hand-motion rates (at most 5 deg per sample)",
                          "magnus4")
RK4_BIAS = Claim("gyro", "rk4_scale_bias", "IMU-TK's RK4 integration induces a scale-factor bias below 10 ppm up to "
                 "250 deg/s at 100 Hz", "< 10 ppm")
ITERATIVE_EFFICIENT = Claim("gyro", "iterative_efficient", "The iterative gyro estimate reaches the Cramér–Rao bound: "
                            "the median RMS error / CRLB of scales and of misalignments is within 0.8-1.2 in every "
                            "Monte Carlo configuration", "0.8-1.2")
ONE_STEP_BASE = Claim("gyro", "one_step_enough_at_base", "The one-step estimate (one linearised solve about C = I) is "
                      "within 20 % of the bound for 2 % scale errors, 1 deg misalignments and MEMS noise", "<= 1.2")
ONE_STEP_NOT = Claim("gyro", "one_step_not_enough", "The one-step estimate exceeds 1.5x the bound somewhere in the "
                     "grid (large errors from nominal, low noise, long motions)", "> 1.5")
GN_IPOPT = Claim("gyro", "gauss_newton_equals_ipopt", "Gauss-Newton with the analytic Jacobian finds IPOPT's minimum "
                 "of the same cost (within 0.1 standard error)", "< 0.1 s.e.")
FOM_IMUTK = Claim("gyro", "figure_of_merit_vs_imutk", "accelcal's gyro calibration carries gravity from rest to rest "
                  "at least as well as IMU-TK's (RMS misfit, own bias) on every session both calibrate (IMU-TK's "
                  "published results; its run from source where given)", "every session")
XSENS_SHEET = Claim("gyro", "xsens_data_sheet", "The Xsens gyro sensitivities (counts per rad/s) agree with the data "
                    "sheet's within 0.2 %", "< 0.2 %")
COVERAGE = Claim("gyro", "interval_coverage", "With the noise model between the rests, the gyro's 95 % intervals of "
                 "scale and misalignment cover the truth 0.93-0.97 of the time in a Monte Carlo with a wandering "
                 "bias and per-motion errors (pooled over the nine parameters)", "0.93-0.97")
STABILITY = Claim("gyro", "session_stability", "Session to session, the gyro scales and misalignments agree within "
                  "their standard errors: χ²/dof <= 2, pooled over the scales and over the misalignments, for the "
                  "IMU-TK fork sessions and for SNU good2/good3 (biases excluded: a turn-on bias)", "<= 2")
#: Samples (trials x 9 parameters) the coverage rule needs: 2 binomial s.e. of 0.95 within the 0.02 margin.
COVERAGE_MINIMUM = MinimumSample(math.ceil(0.95 * 0.05 / 0.01 ** 2), "parameter draws (trials x 9)",
                                 "with fewer, 2 binomial standard errors of the coverage exceed the rule's 0.02 margin")
IMUCAL_AGREES = Claim("gyro", "imucal_agrees", "On imucal's example session accelcal's Ferraris fit (nominal axes, "
                      "as imucal) agrees with imucal's on every scale and misalignment within 3 standard errors",
                      "<= 3 s.e.")


def claims(integ: pd.DataFrame, mc: pd.DataFrame, ipopt: pd.DataFrame, fom: pd.DataFrame,
           peer_parameters: pd.DataFrame, imucal_parameters: pd.DataFrame | None = None,
           coverage: pd.DataFrame | None = None, stability: pd.DataFrame | None = None,
           loop: pd.DataFrame | None = None) -> pd.DataFrame:
    """The stage's claims (module docstring) from its tables (``coverage``: the summary of
    :mod:`.coverage`; ``stability``: the sessions' table of :mod:`.report`; ``loop``: the gyro
    loop benchmark's summary, :mod:`.loop_benchmark`)."""

    rows = []
    best = choose(integ)
    rows.append(INTEGRATOR_CHOICE.row("reproduced" if best == "magnus4" else "not_reproduced", best,
                                      "results/gyro/integrators.csv: median rel_angle_rms_ppm over rate/fs <= 5 deg"))
    hand = integ[(integ.rate_dps <= 250) & (integ.fs_hz == 100) & (integ.method == "rk4")]
    rk4 = float(hand.abs_scale_bias_ppm.max()) if len(hand) else float("nan")
    rows.append(RK4_BIAS.judge(rk4, rk4 < 10, "results/gyro/integrators.csv: abs_scale_bias_ppm", "{:.2g} ppm"))
    s = summary(mc)
    trials = float(mc.trials.min()) if "trials" in mc and len(mc) else float("nan")
    window, limit = ratio_rule_minimum(0.2).at(trials), ratio_rule_minimum(0.5).at(trials)
    it = s["iterative"].to_numpy()
    lo, hi = float(np.nanmin(it)), float(np.nanmax(it))
    rows.append(ITERATIVE_EFFICIENT.judge(hi, lo > 0.8 and hi < 1.2, "results/gyro/montecarlo.csv: ratio, median per kind",
                                          scale=window, shown=f"{lo:.2f}-{hi:.2f}"))
    base = float(s["one_step"].loc["base"].max())
    rows.append(ONE_STEP_BASE.judge(base, base <= 1.2, "results/gyro/montecarlo.csv: config base", "{:.2f}", scale=window))
    worst = float(s["one_step"].to_numpy().max())
    rows.append(ONE_STEP_NOT.judge(worst, worst > 1.5, "results/gyro/montecarlo.csv: largest median ratio", "{:.2f}",
                                   scale=limit))
    d = float(ipopt.max_diff_in_se.iloc[0])
    rows.append(GN_IPOPT.judge(d, d < 0.1, "results/gyro/ipopt_check.csv", "{:.3f} s.e."))
    rows.append(_fom_claim(fom))
    x = peer_parameters[(peer_parameters.session == "xsens") & (peer_parameters.peer == "factory")
                        & peer_parameters.parameter.str.startswith("K_")] if len(peer_parameters) else []
    if len(x):
        rel = float(np.max(np.abs(x.ours / x.peer_value - 1)))
        rows.append(XSENS_SHEET.judge(100 * rel, rel < 2e-3, "results/gyro/sessions/peer_parameters.csv: K_x..K_z, peer "
                                      "factory", "{:.2f} %"))
    else:
        rows.append(XSENS_SHEET.not_reproducible("the Xsens session was not calibrated (see gyro/sessions/sessions.csv)"))
    if imucal_parameters is not None and len(imucal_parameters):
        d = imucal_parameters[imucal_parameters.calibration == "imucal"].diff_in_se.abs().max()
        rows.append(IMUCAL_AGREES.judge(d, d <= 3.0, "results/gyro/sessions/imucal_parameters.csv: diff_in_se", "{:.2f} s.e."))
    else:
        rows.append(IMUCAL_AGREES.not_reproducible("imucal's session was not calibrated (gyro/sessions/sessions.csv)"))
    rows.append(_coverage_claim(coverage))
    rows.append(_stability_claim(stability))
    rows += loop_claims(loop)
    return pd.DataFrame(rows, columns=COLUMNS)


def _coverage_claim(coverage) -> dict:
    if coverage is None or not len(coverage) or "noise_model" not in coverage:
        return COVERAGE.not_reproducible("no coverage Monte Carlo (gyro/coverage_summary.csv)")
    c = coverage[coverage.noise_model.astype(str) == "True"].set_index("parameter")
    if "all" not in c.index:
        return COVERAGE.not_reproducible("no coverage Monte Carlo (gyro/coverage_summary.csv)")
    v, n = float(c.loc["all", "coverage"]), float(c.loc["all", "n"])
    kinds = ", ".join(f"{k} {c.loc[k, 'coverage']:.3f}" for k in ("scale", "misalignment") if k in c.index)
    return COVERAGE.judge(v, 0.93 <= v <= 0.97, f"results/gyro/coverage_summary.csv: all ({kinds}; "
                          f"± {float(c.loc['all', 'coverage_se']):.3f})", "{:.3f}", scale=COVERAGE_MINIMUM.at(n))


def _stability_claim(stability) -> dict:
    if stability is None or not len(stability) or "chi2_per_dof" not in stability:
        return STABILITY.not_reproducible("no session-to-session table (gyro/sessions/stability.csv)")
    d = stability[stability.parameter.isin(["s_*", "T_*"])]
    if "noise_model" in d:
        d = d[d.noise_model.astype(str) == "True"]
    if not len(d):
        return STABILITY.not_reproducible("fewer than two sessions of one unit were calibrated")
    worst = float(d.chi2_per_dof.max())
    shown = "; ".join(f"{r.group} {r.parameter} {r.chi2_per_dof:.2f}" for r in d.itertuples())
    return STABILITY.judge(worst, worst <= 2.0, "results/gyro/sessions/stability.csv: pooled rows s_*, T_*",
                           shown=shown)


def _fom_claim(fom: pd.DataFrame) -> dict:
    if not len(fom):
        return FOM_IMUTK.not_reproducible("no session with an IMU-TK calibration was calibrated")
    own = fom[fom.bias == "own_bias"].pivot(index="session", columns="calibration", values="rms_deg")
    pairs = [(s, peer) for peer in ("imutk_published", "imutk_run") if peer in own for s in own.index
             if np.isfinite(own.loc[s, peer]) and np.isfinite(own.loc[s, "accelcal"])]
    if not pairs:
        return FOM_IMUTK.not_reproducible("no session with an IMU-TK calibration was calibrated")
    worse = [f"{s} ({p}: {own.loc[s, 'accelcal']:.4g} vs {own.loc[s, p]:.4g} deg)" for s, p in pairs
             if own.loc[s, "accelcal"] > own.loc[s, p]]
    value = f"{len(pairs) - len(worse)} of {len(pairs)}"
    evidence = "results/gyro/sessions/figure_of_merit.csv: own_bias" + (f"; worse: {'; '.join(worse)}" if worse else "")
    return FOM_IMUTK.row("reproduced" if not worse else "not_reproduced", value, evidence)


# ----------------------------------------------------------------------------- pieces
def integrator_table(config: dict) -> pd.DataFrame:

    c = config["integrators"]
    return integrator_study(tuple(c["rates_dps"]), tuple(c["fs_hz"]), angle_deg=float(c["angle_deg"]),
                            n_motions=int(c["motions"]), seed=int(config["seed"]))


def monte_carlo_tables(config: dict) -> tuple[pd.DataFrame, pd.DataFrame]:

    return monte_carlo(n_trials=int(config["monte_carlo"]["trials"]), seed=int(config["seed"]))


#: Columns of the IPOPT cross-check that are wall times (its timing table).
IPOPT_TIMES = ("gauss_newton_s", "ipopt_build_s", "ipopt_solve_s")


def ipopt_table(config: dict) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The cross-check's result and, apart, its wall times."""

    c = config["ipopt_check"]
    df = crosscheck(seed=int(config["seed"]), n_motions=int(c["motions"]), fs=float(c["fs_hz"]))
    return df.drop(columns=list(IPOPT_TIMES)), df[["motions", *IPOPT_TIMES]]


def coverage_tables(config: dict) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The coverage Monte Carlo of the 95 % intervals (:mod:`.coverage`) and its summary."""

    df = coverage.coverage(int(config["coverage"]["trials"]), int(config["seed"]))
    return df, coverage.summary(df)


def monte_carlo_summary(mc: pd.DataFrame) -> pd.DataFrame:
    """Median RMS error / CRLB per configuration, estimator and kind of parameter (the report's table)."""

    s = summary(mc)
    s.columns = [f"{e}_{k}" for e, k in s.columns]
    return s.reset_index()


def run(out: Path, config: dict, paths: dict, imutk_run: dict | None = None) -> dict[str, pd.DataFrame]:
    """Every piece in one process (tests; the workflow runs them as jobs): tables, figures, claims into ``out``."""
    from accelcal.plotting import save_figure

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    integ = integrator_table(config)
    mc, timing = monte_carlo_tables(config)
    ipopt, ipopt_times = ipopt_table(config)
    cov, cov_summary = coverage_tables(config)
    tabs = report.run(out / "sessions", paths, tuple(config["sessions"]), imutk_run)
    for name, df in (("integrators", integ), ("montecarlo", mc), ("montecarlo_timing", timing),
                     ("montecarlo_summary", monte_carlo_summary(mc)), ("ipopt_check", ipopt),
                     ("ipopt_timing", ipopt_times), ("coverage", cov), ("coverage_summary", cov_summary)):
        df.to_csv(out / f"{name}.csv", index=False)
    save_figure(integrators.figure(integ), out / "integrators")
    save_figure(montecarlo.figure(mc), out / "montecarlo")
    save_figure(report.figure(tabs["figure_of_merit"], tabs["imucal_figure_of_merit"]), out / "figure_of_merit")
    led = claims(integ, mc, ipopt, tabs["figure_of_merit"], tabs["peer_parameters"], tabs["imucal_parameters"],
                 cov_summary, tabs["stability"])
    led.to_csv(out / "claims.csv", index=False)
    return {"integrators": integ, "montecarlo": mc, "timing": timing, "ipopt": ipopt, "claims": led,
            "coverage": cov_summary, **tabs}


__all__ = ["IPOPT_TIMES", "claims", "coverage_tables", "integrator_table", "ipopt_table", "monte_carlo_summary", "monte_carlo_tables",
           "run"]
