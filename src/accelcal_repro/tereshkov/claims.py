"""Claims ledger rows of Tereshkov (paper id ``tereshkov``), computed from result tables.

Inputs are the tables of :mod:`accelcal_repro.tereshkov.montecarlo`:

* ``summary``: :func:`~accelcal_repro.tereshkov.montecarlo.convergence_summary` of the
  ``field`` and ``straight`` scenarios (one row per scenario × sensor);
* ``observability``: :func:`~accelcal_repro.tereshkov.montecarlo.observability_table`;
* ``artificial``: :func:`~accelcal_repro.tereshkov.montecarlo.artificial_summary`;
* ``sweep``: :func:`~accelcal_repro.tereshkov.montecarlo.sweep_summary`.

Every rule is stated in the claim text; the thresholds come from the ``claims``
section of the config (:data:`DEFAULT_RULES`).  Convergence time and steady-state
error are defined in :mod:`accelcal_repro.tereshkov.montecarlo`.

Every rule reads a mean, an RMS or a settling time over simulated runs, which one run
already gives and which can fall on either side of its threshold: each needs one run
(:data:`MINIMUM_RUNS`; below it, a table without runs, the row is
``not_testable_at_this_scale``).
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import pandas as pd

from ..claims import COLUMNS, Claim, ClaimRule, LedgerError, MinimumSample, judge_rules, validate_rows

PAPER = "tereshkov"
#: The least number of simulated runs every rule needs (module docstring).
MINIMUM_RUNS = MinimumSample(1, "simulated runs", "a mean or RMS over runs needs one")

#: Rule thresholds (config ``tereshkov.claims``).
DEFAULT_RULES = {
    "gyro_convergence_s": 120.0,  # paper, Sec. 3
    "accel_convergence_s": 300.0,  # paper, Sec. 3
    "convergence_ratio_range": (0.5, 2.0),
    "accel_slower_factor": 2.0,  # paper: "more than twice longer"
    "gyro_ss_rms_dps": 0.02,  # paper: 0.01 (test 1) and 0.02 (test 2) deg/s RMS
    "accel_ss_rms_mps2": 0.04,  # paper: 0.04 m/s² RMS in both tests
    "unobservable_min_ratio": 0.5,
    "straight_torque_max_fraction": 0.1,
    "installation_max_deg": 15.0,
}


def _row(summary: pd.DataFrame, scenario: str, sensor: str) -> pd.Series:
    sel = summary[(summary["scenario"] == scenario) & (summary["sensor"] == sensor)]
    if len(sel) != 1:
        raise LedgerError(f"summary has {len(sel)} rows for scenario {scenario!r}, sensor {sensor!r}; expected 1")
    return sel.iloc[0]


def _span(r: dict) -> str:
    lo, hi = r["convergence_ratio_range"]
    return f"{lo:g}-{hi:g}"


def _in_range(x, lo, hi) -> bool:
    return bool(math.isfinite(x) and lo <= x <= hi)


def _gyro_time(x, claim):
    tg = float(x.fg["t_conv"])
    ev = (f"{x.summary_path}: field scenario ({x.runs} runs): 95% settling at {tg:.0f} s elapsed, after "
          f"{x.fg['update_time_at_conv']:.0f} s of straight-motion updating (the gyro estimate updates "
          f"{100 * x.fg['update_fraction']:.0f}% of the time); straight-only runs: {x.sg['t_conv']:.0f} s")
    return claim.judge(tg, _in_range(tg / x.r["gyro_convergence_s"], *x.r["convergence_ratio_range"]), ev,
                       fmt="{:.0f} s", scale=x.field)


def _accel_time(x, claim):
    ta = float(x.fa["t_conv"])
    ev = (f"{x.summary_path}: field scenario ({x.runs} runs): 95% settling at {ta:.0f} s elapsed, after "
          f"{x.fa['update_time_at_conv']:.0f} s of turning updates (the estimate updates "
          f"{100 * x.fa['update_fraction']:.0f}% of the time, only in settled turns)")
    return claim.judge(ta, _in_range(ta / x.r["accel_convergence_s"], *x.r["convergence_ratio_range"]), ev,
                       fmt="{:.0f} s", scale=x.field)


def _accel_slower(x, claim):
    ta, tg = float(x.fa["t_conv"]), float(x.fg["t_conv"])
    ratio = ta / tg if (math.isfinite(ta) and math.isfinite(tg) and tg > 0) else float("nan")
    ev = f"{x.summary_path}: accel {ta:.0f} s / gyro {tg:.0f} s"
    return claim.judge(ratio, ratio > x.r["accel_slower_factor"], ev, fmt="{:.2f}×", scale=x.field)


def _steady_rule(sensor: str, key: str, unit: str, paper_value: str) -> ClaimRule:
    """The steady-state RMS bias error of ``sensor`` against the paper's accuracy ``r[key]``."""
    what = "roll and pitch gyro" if sensor == "gyro" else "x and y accelerometer"

    def rule(x):
        return (f"Steady-state {what} bias estimation error of {paper_value}. Rule: reproduced if the simulated "
                f"steady-state RMS error is at most {x.r[key]:g} {unit} (the paper's accuracy is attained; the "
                "simulation has only the stated white sensor and GNSS noise, the field tests had more error sources)")

    def verdict(x, claim):
        row_ = x.fg if sensor == "gyro" else x.fa
        v = float(row_["ss_rms"])
        ev = (f"{x.summary_path}: field scenario ({x.runs} runs), RMS of estimate - truth over runs, both axes and "
              f"the steady-state window; mean |error| {row_['e_ss']:.4g} {unit}; straight-only runs: "
              f"{_row(x.summary, 'straight', sensor)['ss_rms']:.4g} {unit}")
        return claim.judge(v, v <= x.r[key], ev, fmt="{:.4f} " + unit, scale=x.field)
    return ClaimRule(f"{sensor}_steady_state_rms", paper_value, rule, ("summary", "r"), verdict)


def _unobservable(x, claim):
    obs, r = x.observability, x.r
    st = obs[obs["mode"] == "straight"]["sensitivity"]
    tu = obs[obs["mode"] == "turn"]["sensitivity"]
    frac = float(st.mean() / tu.mean()) if len(st) and len(tu) and tu.mean() > 0 else float("nan")
    fr_straight = float(x.sa["final_ratio"])
    fr_field = float(x.fa["final_ratio"])
    passed = (fr_straight >= r["unobservable_min_ratio"] and fr_field < r["unobservable_min_ratio"]
              and frac <= r["straight_torque_max_fraction"])
    ev = (f"{x.summary_path}: steady/initial mean |accel error| straight-only {fr_straight:.2f}, field "
          f"{fr_field:.3f}; {x.observability_path}: torque change per m/s² of bias shift {st.mean():.4f} °/s "
          f"(straight) vs {tu.mean():.3f} °/s (turns; eq. 13 predicts "
          f"{(obs[obs['mode'] == 'turn']['predicted_rms_dps'] / obs[obs['mode'] == 'turn']['shift_mps2']).mean():.3f})")
    scale = MINIMUM_RUNS.at(min(x.runs, int(x.sa["runs"]), obs["run"].nunique() if "run" in obs else x.runs))
    return claim.judge(frac, passed, ev, fmt="{:.3f} (straight/turn torque sensitivity)", scale=scale)


def _artificial(x, claim):
    a = x.artificial.set_index("axis")
    if "xy" not in a.index:
        raise LedgerError("artificial summary has no 'xy' row")
    v = float(a.loc["xy", "rms_vs_artificial"])
    ev = (f"{x.artificial_path}: RMS(estimate - artificial) {v:.4f} m/s² (includes the unknown intrinsic bias, as in "
          f"the paper); RMS(with - without - artificial) {a.loc['xy', 'rms_difference']:.4f}; RMS(estimate - total "
          f"true bias) {a.loc['xy', 'rms_vs_truth']:.4f}")
    runs = x.artificial_runs if x.artificial_runs is not None else float("nan")
    return claim.judge(v, v <= x.r["accel_ss_rms_mps2"], ev, fmt="{:.4f} m/s²", scale=MINIMUM_RUNS.at(runs))


def _installation_rule(kind: str, label: str) -> ClaimRule:
    """Insensitivity to the ``kind`` installation angles (no row when the sweep left them out)."""
    def rule(x):
        r = x.r
        return (f"The estimation is not sensitive to IMU installation angles up to 10-15° ({label} mounting angles "
                "swept); an installation error acts as a redefinition of the body axes. Rule: reproduced if at every "
                f"swept angle up to {r['installation_max_deg']:g}° the steady-state RMS errors stay within the "
                f"paper's accuracy ({r['gyro_ss_rms_dps']:g} °/s, {r['accel_ss_rms_mps2']:g} m/s²) and the "
                "accelerometer estimate converges, the accelerometer error taken against the equivalent x/y biases "
                "of the installed IMU (sensor-axis biases plus the leak b_z·tan of the tilt of the unestimated z "
                "bias; equal for yaw)")

    def verdict(x, claim):
        sk = x.sweep[x.sweep["kind"] == kind]
        return _installation_row(sk, claim, x.r["installation_max_deg"], x.r, x.sweep_path) if len(sk) else None
    return ClaimRule(f"installation_{kind}", "insensitive up to 10-15°", rule, ("sweep", "r"), verdict)


#: The claims, in the ledger's order: one entry per claim (:class:`accelcal_repro.claims.ClaimRule`).
RULES = (
    ClaimRule(
        "gyro_convergence_time", lambda x: f"≈{x.r['gyro_convergence_s']:g} s",
        lambda x: "The gyro bias filter (time constant 40 s) converges in about "
                  f"{x.r['gyro_convergence_s']:g} s, i.e. three time constants. Rule: reproduced if the 95% settling "
                  "time of the Monte Carlo mean |error| (roll and pitch gyros, simulated field runs) is within "
                  f"{_span(x.r)}x the paper's value",
        ("summary", "r"), _gyro_time),
    ClaimRule(
        "accel_convergence_time", lambda x: f"≈{x.r['accel_convergence_s']:g} s",
        lambda x: "The accelerometer bias filter (time constant 40 s) converges in about "
                  f"{x.r['accel_convergence_s']:g} s. Rule: reproduced if the 95% settling time of the Monte Carlo "
                  "mean |error| (x and y accelerometers, simulated field runs) is within "
                  f"{_span(x.r)}x the paper's value",
        ("summary", "r"), _accel_time),
    ClaimRule(
        "accel_slower_than_gyro", "> 2 (300 s vs 120 s)",
        lambda x: "Accelerometer bias convergence is more than twice as long as gyro bias convergence although both "
                  "filters have the same time constant (weak observability). Rule: reproduced if the ratio of the "
                  f"settling times (field runs) exceeds {x.r['accel_slower_factor']:g}",
        ("summary", "r"), _accel_slower),
    _steady_rule("gyro", "gyro_ss_rms_dps", "°/s", "0.01–0.02 °/s RMS"),
    _steady_rule("accel", "accel_ss_rms_mps2", "m/s²", "0.04 m/s² RMS"),
    ClaimRule(
        "accel_unobservable_straight", "not observable",
        lambda x: "Accelerometer biases are not observable in straight motion (eq. 12: the torque only balances the "
                  "gyro bias). Rule: reproduced if (a) in straight-only runs the accelerometer error stays above "
                  f"{x.r['unobservable_min_ratio']:g} of its initial value while in field runs it falls below, and (b) "
                  "a known accelerometer-bias shift changes the settled straight-motion torque by at most "
                  f"{x.r['straight_torque_max_fraction']:g} of its effect in settled turns",
        ("summary", "observability", "r"), _unobservable),
    ClaimRule(
        "artificial_bias_test", "0.04 m/s² RMS",
        lambda x: "With precisely known artificial accelerometer biases added to the measurements, the estimates "
                  "match them to 0.04 m/s² RMS in the steady state (Fig. 4). Rule: reproduced if the simulated "
                  f"steady-state RMS of (estimate - artificial bias) is at most {x.r['accel_ss_rms_mps2']:g} m/s²",
        ("artificial", "artificial_runs", "r"), _artificial),
    _installation_rule("roll_pitch", "roll and pitch"),
    _installation_rule("yaw", "yaw"),
    ClaimRule(
        "field_tests", "Figs. 2-4",
        lambda x: "Figs. 2-4: bias estimates from the John Deere 5515 and Caterpillar Challenger field tests", (),
        lambda x, claim: claim.not_reproducible(
            "no public data: the tractor recordings are not published; the other rows use simulated field runs")),
)


def tereshkov_claims(summary: pd.DataFrame, observability: pd.DataFrame, artificial: pd.DataFrame,
                     sweep: pd.DataFrame, rules: dict | None = None, *,
                     summary_path: str = "results/tereshkov/summary.csv",
                     observability_path: str = "results/tereshkov/observability.csv",
                     artificial_path: str = "results/tereshkov/artificial_summary.csv",
                     sweep_path: str = "results/tereshkov/sweep_summary.csv",
                     artificial_runs: float | None = None) -> pd.DataFrame:
    """All Tereshkov rows of the ledger (columns :data:`accelcal_repro.claims.COLUMNS`; :data:`RULES`).

    ``artificial_runs``: the runs behind ``artificial`` (which does not count them; None: unknown).
    """
    fg, fa = _row(summary, "field", "gyro"), _row(summary, "field", "accel")
    sg, sa = _row(summary, "straight", "gyro"), _row(summary, "straight", "accel")
    runs = int(fg["runs"])
    ctx = SimpleNamespace(
        summary=summary, observability=observability, artificial=artificial, sweep=sweep,
        r=dict(DEFAULT_RULES) | dict(rules or {}), fg=fg, fa=fa, sg=sg, sa=sa, runs=runs, field=MINIMUM_RUNS.at(runs),
        summary_path=summary_path, observability_path=observability_path, artificial_path=artificial_path,
        sweep_path=sweep_path, artificial_runs=artificial_runs)
    return validate_rows(pd.DataFrame(judge_rules(PAPER, RULES, ctx), columns=list(COLUMNS)),
                         source="tereshkov claims")


def _installation_row(sk: pd.DataFrame, c: Claim, amax: float, r: dict, sweep_path: str) -> dict:
    def val(sensor, a, col="ss_rms", ref="equivalent"):
        s = sk[(sk["sensor"] == sensor) & (sk["angle_deg"] == a)]
        if "reference" in s:
            s = s[s["reference"] == ref]
        return float(s[col].iloc[0]) if len(s) else float("nan")

    angles = sorted(sk["angle_deg"].unique())
    within = [a for a in angles if a <= amax + 1e-9]

    def ok(a, ref):
        return (val("gyro", a, ref=ref) <= r["gyro_ss_rms_dps"] and val("accel", a, ref=ref) <= r["accel_ss_rms_mps2"]
                and val("accel", a, "final_ratio", ref) < r["unobservable_min_ratio"])

    passed = bool(within) and all(ok(a, "equivalent") for a in within)
    first_bad = {ref: next((a for a in angles if not ok(a, ref)), None) for ref in ("equivalent", "sensor_axes")}
    worst_acc = max(val("accel", a) for a in within) if within else float("nan")

    def per(ref):
        return "; ".join(f"{a:g}°: {val('gyro', a, ref=ref):.4f} °/s, {val('accel', a, ref=ref):.4f} m/s²"
                         for a in angles)

    def bad(ref):
        return f"first fails at {first_bad[ref]:g}°" if first_bad[ref] is not None else "within at every angle"

    tilt = "; ".join(f"{a:g}°: {val('attitude', a):.3f}°" for a in angles)
    ev = (f"{sweep_path}: steady-state RMS (gyro, accel) vs equivalent biases per angle: {per('equivalent')} "
          f"({bad('equivalent')}); vs sensor-axis biases: {per('sensor_axes')} ({bad('sensor_axes')}); "
          f"AHRS tilt error RMS: {tilt}")
    scale = MINIMUM_RUNS.at(float(sk["runs"].min()) if "runs" in sk else float("nan"))
    return c.judge(worst_acc, passed, ev, fmt="{:.4f} m/s² worst accel RMS up to " + f"{amax:g}°", scale=scale)


__all__ = ["DEFAULT_RULES", "MINIMUM_RUNS", "PAPER", "RULES", "tereshkov_claims"]
