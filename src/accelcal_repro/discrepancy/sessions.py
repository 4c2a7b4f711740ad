"""Every real session accounted for: what the joint model names, how much of the residual excess
it explains, whether a re-simulation with it closes the gap, and what stays stable between
sessions of one IMU.

Inputs are the public outputs of the loop: the discrepancy report of each recording
(``results/discrepancy/measured/<recording>.json``, the JSON of ``accelcal discrepancy``)
and the recording itself (canonical CSV).  Tables, one row per item (figures and claims
are computed from them):

* :func:`named_rows`: what is named, deterministic (effects, outlier poses) and
  stochastic (the joint model's bias wander with its size, correlation time and 95 %
  intervals; the terms the stochastic layer names from the rests), and what could not be
  tested and why.
* :func:`excess_rows`: the pose-residual scatter the model predicts against the observed
  one.  ``observed`` = ``sqrt(χ²/dof)`` of the base model's residuals against the rests'
  white noise (the excess: 2.5–2.9 on the Xsens); ``predicted`` = the same
  ratio the joint noise model implies, with the interval its wander's interval gives;
  ``explained`` = ``(predicted² − 1)/(observed² − 1)``, the share of the excess variance
  the model accounts for.
* :func:`resimulate`: the whole session simulated again — its own time base, poses,
  motions and temperature; in every pose the calibrated model's prediction plus the rest's
  own short-term noise plus a pose-mean error of its standard error, and a wander simulated
  over the whole time base — under the model *before* (base calibration, white noise of
  the rests) and *after* (the named effects and outliers, and the joint noise model: its
  white scale, its wander or per-placement offset), and fitted by
  the same base model as the measured data.  :func:`gap_rows` compares the distribution of the
  measured normalised pose residuals with the simulated ones: the ratio of their RMS, the
  two-sample Kolmogorov–Smirnov distance, and where the measured excess falls in the
  simulated distribution of the excess.  The gap shrinks if the named items were what was
  missing.
* :func:`accelcal_repro.discrepancy.evidence.evidence_rows`: for a session whose excess stays unexplained, the evidence
  against each candidate: its test, its estimate, and the share of the excess χ² it
  would remove.
* :func:`stability_rows`: the sessions of one IMU: each parameter per session with its
  standard error, Cochran's heterogeneity test ``Q = Σ w_k (p_k − p̄_w)²`` against
  ``χ²(K − 1)`` (``w = 1/se²``), Holm-adjusted over the parameters, and the verdict
  stable / not stable at level α.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pandas as pd

from accelcal import distributions as dist
from accelcal.discrepancy.fit import evaluate, fit, forward, pose_data, pose_data_from_static
from accelcal.discrepancy.statistics import holm
from accelcal.discrepancy.stochastic import rest_segments, stochastic_layer
from accelcal.discrepancy.wander_process import process_in
from accelcal.errors import AccelcalError
from accelcal.model import m_from_params
from accelcal.recording import Recording
from accelcal.static import detect_static_recording

from .profiles import NoiseProfile, placement_offsets, simulate_profile, wander_axis_correlation, wander_components

BASE_PARAMETERS = ("b_x", "b_y", "b_z", "s_x", "s_y", "s_z", "theta_xy", "theta_zx", "theta_zy")


# --------------------------------------------------------------------------- poses


def with_disjoint_rests(rec: Recording) -> tuple[Recording, str]:
    """``rec`` with its detected rests as known intervals if the detection returns overlapping ones.

    WORKAROUND (remove when :func:`accelcal.static.detect_static` returns disjoint spans):
    two quiet runs separated by a blip shorter than one window minus twice the trim give
    spans that overlap (IMU-TK fork data2: samples 35-585 and 548-809), which the wander
    null's :func:`accelcal.discrepancy.poses.pose_data` refuses.  The overlap is split at its
    middle; the recording then carries the rests as known intervals, so that every later
    step (both layers, the re-simulations) uses the same poses.  Returns the recording and
    a note ('' when nothing was changed).
    """
    if rec.intervals is not None:
        return rec, ""
    iv = detect_static_recording(rec).intervals.copy()
    bad = np.flatnonzero(iv[1:, 0] < iv[:-1, 1])
    if not bad.size:
        return rec, ""
    for k in bad:
        mid = (iv[k + 1, 0] + iv[k, 1]) // 2
        iv[k, 1], iv[k + 1, 0] = mid, mid
    note = (f"static detection returned overlapping rests {[(int(a), int(b)) for a, b in iv[bad]]}...; split at the "
            f"middle of each overlap and used as known intervals")
    return dataclasses.replace(rec, intervals=iv, labels=None), note


def poses_of(rec: Recording):
    """The poses the workflow's reports use (:func:`with_disjoint_rests`, then the static detection)."""
    return detect_static_recording(with_disjoint_rests(rec)[0])


# --------------------------------------------------------------------------- reading a report


def _params(report: dict, which: str) -> tuple[np.ndarray, tuple[str, ...]]:
    """Parameter vector (base, then each effect's block) and effects of ``model_before``/``model_after``."""
    m = report[f"model_{which}"]
    effects = tuple(m.get("effects", ()))
    return np.array([v["value"] for v in m["parameters"].values()], float), effects


def pose_data_of(report: dict):
    """The report's pose set as :class:`~accelcal.discrepancy.poses.PoseData` (same σ as the loop used)."""
    p = report["poses"]
    temp = p.get("temp")
    return pose_data(np.array(p["mean"], float), report["g"], np.array(p["mean_std"], float), np.array(p["t"], float),
                     None if temp is None else np.array(temp, float), sigma=np.array(p["sigma"], float))


def placement_of(report: dict) -> tuple[float, float, float]:
    """The joint model's named per-placement offset per axis (data unit; zeros without one)."""
    nm = report.get("noise_model") or {}
    return (process_in(nm).placement_size(nm),) * 3


def white_scale_of(report: dict) -> float:
    """The joint model's white scale (the rests' pose-mean variance times it; 1 without one)."""
    nm = report.get("noise_model") or {}
    v = nm.get("white_scale") if nm.get("estimated") else None
    return float(v) if v is not None and np.isfinite(v) else 1.0


# --------------------------------------------------------------------------- named, excess, evidence


def _g(v) -> str:
    """A number of a report (None = NaN or an open end) for a table cell."""
    return "open" if v is None else f"{float(v):.3g}"


def named_rows(name: str, report: dict) -> list[dict]:
    """What the loop names on one session (module docstring): one row per item."""
    def row(layer, item, kind, value="", ci=""):
        return {"recording": name, "layer": layer, "item": item, "kind": kind, "value": value, "ci": ci}

    rows = [row("deterministic", e, "effect") for e in report.get("effects", []) if e != "outlier_pose"]
    for o in report.get("outliers", []) or []:
        rows.append(row("deterministic", "outlier_pose", "outlier",
                        f"pose {o.get('pose')} at t = {_g(o.get('t'))} s, shift {_g(o.get('shift'))} "
                        f"({_g(o.get('shift_sigma'))} sigma), adjusted p {_g(o.get('p_adjusted'))}"))
    nm = report.get("noise_model") or {}
    if nm.get("estimated"):
        if not process_in(nm).named:
            rows.append(row("stochastic (joint)", "none", "no bias wander", "size 0",
                            f"size [{', '.join(map(_g, nm.get('size_ci') or [None, None]))}]"))
        else:
            proc = nm.get("process", "")
            value, ci = process_in(nm).cell(nm, _g)
            if nm.get("axis_correlation") is not None:
                value += f", axis correlation {_g(nm['axis_correlation'])}"
                ci += f", axis correlation [{', '.join(map(_g, nm.get('axis_correlation_ci') or [None, None]))}]"
            rows.append(row("stochastic (joint)", nm.get("term", ""), proc, value, ci))
    elif nm:
        rows.append(row("stochastic (joint)", "not_estimated", "", nm.get("reason") or ""))
    st = report.get("stochastic")
    if st:
        for ax, a in st["axes"].items():
            terms = [t for t in a.get("named", []) if t != "none"]
            rows.append(row(f"stochastic (rests, axis {ax})", "+".join(terms) or "none", "allan"))
    else:
        rows.append(row("stochastic (rests)", "not_run", "", report.get("stochastic_error", "")))
    reasons = report.get("not_identifiable_reasons") or {}
    for e in report.get("not_identifiable", []):
        why = reasons.get(e, "")
        rows.append(row("deterministic", e, "not_identifiable", "; ".join(why) if isinstance(why, list) else str(why)))
    return rows


def excess_rows(name: str, report: dict) -> dict:
    """Observed vs predicted pose-residual excess and the share explained (module docstring)."""
    obs = report.get("excess_observed", report.get("excess_before"))
    pred = report.get("excess_predicted", float("nan"))
    nm = report.get("noise_model") or {}
    ci = report.get("excess_predicted_interval") or nm.get("excess_ci") or [float("nan"), float("nan")]
    ci = [float("nan") if v is None else v for v in ci]
    pred = float("nan") if pred is None else pred

    def share(p):
        return (p ** 2 - 1) / (obs ** 2 - 1) if obs is not None and obs > 1 and p is not None else float("nan")

    return {"recording": name, "n_poses": report["n_poses"], "excess_observed": obs, "excess_predicted": pred,
            "excess_predicted_ci_low": ci[0], "excess_predicted_ci_high": ci[1],
            "explained": share(pred), "explained_ci_low": share(ci[0]), "explained_ci_high": share(ci[1]),
            "excess_status": report.get("excess_status", ""),
            "excess_status_white": report.get("excess_status_white", report.get("excess_status", "")),
            "excess_explained_by": "+".join(report.get("excess_explained_by") or []),
            "verdict": (report.get("noise_implication") or {}).get("verdict", "")}


#: What a session of few orientations cannot test, and why (the loop's own limits).
FEW_POSES_LIMITS = {
    "calibration (bias, scale, non-orthogonality)": "the 9-parameter model needs at least 10 distinct orientations",
    "every effect of the library": "an effect adds 3 parameters to the 9 of the model: at least 13 poses; quadratic "
                                   "and cubic are also invisible on the six faces (absorbed by the bias and the scale)",
    "bias wander (wander null)": "the wander's size and correlation time need at least 6 residual degrees of "
                                  "freedom beyond the 9-parameter model: at least 15 poses",
    "outlier poses": "a pose left out must leave the 9-parameter model determined: at least 11 poses",
}


def few_poses_rows(name: str, rec: Recording, measured_summary: pd.DataFrame, stochastic) -> tuple[list, list]:
    """A session of too few orientations for the loop (imucal's Ferraris session: six): what can be
    tested — the bias-only fits' residual excess (results/measured/summary.csv) and the rests'
    noise terms (the stochastic layer on every rest) — and what cannot, with the reason.

    Returns (named rows, excess rows) in the form of :func:`named_rows` and :func:`excess_rows`.
    """
    poses = poses_of(rec)
    named = []

    def row(layer, item, kind, value="", ci=""):
        named.append({"recording": name, "layer": layer, "item": item, "kind": kind, "value": value, "ci": ci})

    try:
        st = stochastic_layer(rest_segments(rec.acc, poses.intervals), rec.rate, seed=stochastic.seed,
                              alpha=stochastic.alpha, max_terms=stochastic.max_terms,
                              candidates=stochastic.candidates, intervals=poses.intervals,
                              n_boot=stochastic.n_boot, n_resim=stochastic.n_resim)
        for a in st.axes:
            row(f"stochastic (rests, axis {a.axis})", "+".join(t for t in a.named if t != "none") or "none", "allan",
                f"{len(poses.intervals)} rests, Allan gap {a.gap_before:.2f} -> {a.gap_after:.2f}")
    except AccelcalError as e:
        row("stochastic (rests)", "not_run", "", str(e).splitlines()[0])
    for item, why in FEW_POSES_LIMITS.items():
        row("deterministic" if "wander" not in item else "stochastic (joint)", item, "not_testable", why)
    excess = []
    for r in measured_summary[measured_summary.recording == name].itertuples():
        excess.append({"recording": name, "n_poses": int(r.n_poses), "excess_observed": float(r.excess),
                       "excess_predicted": float("nan"), "excess_predicted_ci_low": float("nan"),
                       "excess_predicted_ci_high": float("nan"), "explained": float("nan"),
                       "explained_ci_low": float("nan"), "explained_ci_high": float("nan"),
                       "excess_status": f"{r.estimator}: chi2/dof {float(r.reduced_chi2):.3g} on {int(r.dof)} dof",
                       "verdict": "bias-only model (M = I): the excess includes the unit's scale factors"})
    return named, excess


def diagnostics_row(name: str, rec: Recording, report: dict) -> dict:
    """Evidence about an excess that neither an effect nor the wander explains.

    * ``within_pose_drift``: RMS over poses and axes of the difference between the means of
      the second and the first half of each pose, in units of its standard error
      (``2 se``: each half has ``√2 se``): 1 for stationary rests; larger when the poses
      settle or creep while they are averaged (a pose offset that is not noise between poses).
    * ``half_consistency``: correlation over poses of the base-model residuals computed from
      the first halves and from the second halves: near 1 when the residuals are a property
      of the pose (placement, orientation), near 0 when they are noise.
    * ``time_spearman``, ``time_p``: rank correlation of the normalised residuals with the pose
      time (a drift or a slow wander orders them in time).
    """
    p = report["poses"]
    ranges = _rest_ranges(rec, report)
    se = np.array(p["mean_std"], float)
    acc = np.asarray(rec.acc, float)
    drift = []
    for i, (a, b) in enumerate(ranges):
        h = (a + b) // 2
        drift.append((acc[h:b].mean(axis=0) - acc[a:h].mean(axis=0)) / (2 * se[i]))
    r = np.array(p["residual_before"], float) / np.array(p["sigma"], float)
    from scipy import stats  # here: scipy.stats costs ~1 s to import, and few jobs need it

    rho, pval = stats.spearmanr(np.array(p["t"], float), r)
    return {"recording": name, "n_poses": len(ranges), "within_pose_drift": float(np.sqrt(np.mean(np.square(drift)))),
            "half_consistency": half_consistency(rec, ranges, pose_data_of(report)),
            "time_spearman": float(rho), "time_p": float(pval)}


def half_consistency(rec: Recording, ranges, data) -> float:
    """Correlation over poses of the base-model residuals fitted to the means of the first and of
    the second half of each pose (:func:`diagnostics_row`)."""
    acc = np.asarray(rec.acc, float)
    halves = []
    for part in (0, 1):
        z = np.array([acc[a:(a + b) // 2].mean(axis=0) if part == 0 else acc[(a + b) // 2:b].mean(axis=0)
                      for a, b in ranges])
        half = pose_data(z, data.g, data.mean_std * math.sqrt(2), data.t, data.temp, sigma=data.sigma * math.sqrt(2))
        halves.append(fit(half).residuals)
    return float(np.corrcoef(halves[0], halves[1])[0, 1])


# --------------------------------------------------------------------------- re-simulation


def _rest_ranges(rec: Recording, report: dict) -> np.ndarray:
    """Sample ranges ``[start, stop)`` of the report's poses in the recording."""
    p = report["poses"]
    a = np.searchsorted(rec.t, np.array(p["t_start"], float) - 1e-9)
    b = np.searchsorted(rec.t, np.array(p["t_end"], float) + 1e-9)
    n = np.array(p["n_samples"], int)
    if not np.array_equal(b - a, n):
        raise AccelcalError(f"{rec.source}: the report's poses do not match the recording's samples")
    return np.column_stack([a, b])


def _outlier_shifts(report: dict, data, p, effects) -> np.ndarray:
    """Per pose, the shift of its mean (data unit, shape (n, 3)) that moves its residual by the
    named outlier's estimated ``shift``, along the residual's gradient."""
    out = np.zeros((len(data), 3))
    outliers = report.get("outliers") or []
    if not outliers:
        return out
    _, J, _ = evaluate(p, data, effects)
    grad = -J[:, :3]  # ∂r/∂z = −∂r/∂b
    for o in outliers:
        i = int(o["pose"])
        out[i] = float(o["shift"]) * grad[i] / float(grad[i] @ grad[i])
    return out


def simulate_session(rec: Recording, report: dict, which: str, profile: NoiseProfile, rng,
                     white_scale: float = 1.0) -> Recording:
    """The session again under the model ``which`` ('before' or 'after'): every pose of the report
    (its samples, as the loop averaged them) replaced by

    * the model's prediction (the pose's direction at exactly g through the calibration and the
      effects of ``which``),
    * the rest's own measured short-term noise: its samples about their mean, circularly
      shifted by a random lag (zero mean, the rest's own scatter and autocorrelation, hence
      its own standard error),
    * a pose-mean error drawn from the rest's standard error (what white noise leaves in a
      mean: the rests' noise model), times ``sqrt(white_scale)`` (the joint model's),
    * the per-placement offset of ``profile`` (one draw per pose, constant over it),
    * the time-correlated components of ``profile`` (its white term is not used), simulated
      over the whole time base so that a wander runs on through the motions,
    * for 'after', the named outlier poses' estimated shifts;

    everything else as measured.  The recording carries the poses as known intervals, so the
    re-simulation is averaged over exactly the samples the measured poses were: only the
    noise model between the pose means differs between 'before', 'after' and the data."""
    data = pose_data_of(report)
    p, effects = _params(report, which)
    _, _, x = evaluate(p, data, effects, jacobian=False)
    if x is None:
        raise AccelcalError(f"{rec.source}: the {which} model cannot be inverted at the pose means")
    x = x * (data.g / np.linalg.norm(x, axis=1))[:, None]  # each pose at exactly g
    M = m_from_params(p[3:6], p[6:9])
    params = {e: p[9 + 3 * i: 12 + 3 * i] for i, e in enumerate(effects)}
    ranges = _rest_ranges(rec, report)
    acc = np.array(rec.acc, float)
    wander = NoiseProfile(profile.name, (0.0, 0.0, 0.0), profile.components)
    noise = simulate_profile(wander, rng, len(rec.t), float(1.0 / np.median(np.diff(rec.t))))
    se = np.array(report["poses"]["mean_std"], float)
    measured = np.asarray(rec.acc, float)
    shifts = _outlier_shifts(report, data, p, effects) if which == "after" else np.zeros((len(ranges), 3))
    shifts = shifts + placement_offsets(profile, rng, np.arange(len(ranges)), len(ranges))  # one draw per pose
    for i, (a, b) in enumerate(ranges):
        dt = rec.t[a:b] - data.t_ref
        dtemp = None if rec.temp is None or data.temp is None else rec.temp[a:b] - data.temp_ref
        short = np.roll(measured[a:b] - measured[a:b].mean(axis=0), int(rng.integers(b - a)), axis=0)
        z = forward(np.repeat(x[i][None], b - a, axis=0), M, p[:3], params, dt=dt, dtemp=dtemp) + short \
            + math.sqrt(white_scale) * se[i] * rng.standard_normal(3) + noise[a:b] + shifts[i]
        # not rounded: the rest's own noise is already quantised, and rounding it again after
        # adding a constant would shift every sample of the pose alike (up to half a count)
        acc[a:b] = z
    return dataclasses.replace(rec, acc=acc, intervals=ranges, labels=None,
                               source=f"{rec.source} (re-simulated, {which})")


def base_residuals(rec: Recording, g: float) -> np.ndarray:
    """Normalised residuals ``r_i/σ_i`` of the base model on a recording's poses."""
    data = pose_data_from_static(poses_of(rec), g)
    return fit(data).weighted


def resimulate(rec: Recording, report: dict, *, n_rep: int, seed: int, white_only_after: bool = False) -> pd.DataFrame:
    """Normalised base-model residuals of ``n_rep`` re-simulations per model (module docstring).

    Returns one row per (model, replicate, pose): ``model`` ('before'/'after'), ``replicate``,
    ``pose``, ``z`` (= r/σ), and the replicate's ``half_consistency`` (:func:`half_consistency`);
    replicates whose pose extraction or fit fails are skipped and counted in the ``failed``
    rows (``pose = -1``).
    """
    before = NoiseProfile("before", (0.0, 0.0, 0.0))  # the rests' own noise (simulate_session)
    after = NoiseProfile("after", (0.0, 0.0, 0.0), () if white_only_after else wander_components(report),
                         axis_correlation=0.0 if white_only_after else wander_axis_correlation(report),
                         placement=(0.0,) * 3 if white_only_after else placement_of(report))
    scales = {"before": 1.0, "after": 1.0 if white_only_after else white_scale_of(report)}
    rows = []
    for which, prof in (("before", before), ("after", after)):
        failed = 0
        for k in range(n_rep):
            rng = np.random.default_rng([seed, k])  # common random numbers across the two models
            try:
                sim = simulate_session(rec, report, which, prof, rng, scales[which])
                z = base_residuals(sim, report["g"])
                hc = half_consistency(sim, sim.intervals, pose_data_of(report))
            except AccelcalError:
                failed += 1
                continue
            rows += [{"model": which, "replicate": k, "pose": i, "z": float(v), "half_consistency": hc}
                     for i, v in enumerate(z)]
        rows.append({"model": which, "replicate": -1, "pose": -1, "z": float(failed), "half_consistency": np.nan})
    return pd.DataFrame(rows)


GAP_COLUMNS = ["recording", "model", "replicates", "failed", "rms_measured", "rms_simulated", "rms_ratio",
               "ks_distance", "ks_p_value", "excess_measured", "excess_sim_median", "excess_sim_q025",
               "excess_sim_q975", "excess_measured_quantile", "half_consistency_measured",
               "half_consistency_sim_median", "half_consistency_sim_q025", "half_consistency_sim_q975"]


def _quantiles(v: pd.Series, prefix: str) -> dict:
    v = v.dropna()
    if not len(v):
        return {f"{prefix}_{k}": np.nan for k in ("median", "q025", "q975")}
    return {f"{prefix}_median": float(v.median()), f"{prefix}_q025": float(v.quantile(0.025)),
            f"{prefix}_q975": float(v.quantile(0.975))}


def gap_rows(name: str, report: dict, sims: pd.DataFrame, rec: Recording | None = None) -> list[dict]:
    """Measured vs re-simulated normalised residuals: RMS ratio, KS distance, the measured excess
    against the simulated distribution of the excess, and (given the recording) the measured
    consistency of the two halves of each pose against the simulated one, per model."""
    meas = np.array(report["poses"]["residual_before"], float) / np.array(report["poses"]["sigma"], float)
    dof = report.get("dof_before", len(meas) - 9)
    if dof < 1:
        return []
    exc_meas = math.sqrt(float(meas @ meas) / dof)
    hc_meas = half_consistency(rec, _rest_ranges(rec, report), pose_data_of(report)) if rec is not None else np.nan
    from scipy import stats  # here: scipy.stats costs ~1 s to import, and few jobs need it

    rows = []
    for which, d in sims[sims.pose >= 0].groupby("model", sort=False):
        z = d.z.to_numpy()
        per_rep = d.groupby("replicate").z.apply(lambda v: math.sqrt(float(v @ v) / dof))
        ks = stats.ks_2samp(np.abs(meas), np.abs(z))
        failed = int(sims[(sims.model == which) & (sims.pose < 0)].z.iloc[0])
        rows.append({"recording": name, "model": which, "replicates": int(per_rep.size), "failed": failed,
                     "rms_measured": float(np.sqrt(np.mean(meas ** 2))), "rms_simulated": float(np.sqrt(np.mean(z ** 2))),
                     "rms_ratio": float(np.sqrt(np.mean(meas ** 2) / np.mean(z ** 2))),
                     "ks_distance": float(ks.statistic), "ks_p_value": float(ks.pvalue),
                     "excess_measured": exc_meas, "excess_sim_median": float(per_rep.median()),
                     "excess_sim_q025": float(per_rep.quantile(0.025)), "excess_sim_q975": float(per_rep.quantile(0.975)),
                     "excess_measured_quantile": float(np.mean(per_rep <= exc_meas)),
                     "half_consistency_measured": hc_meas, **_quantiles(d.groupby("replicate").half_consistency.first(),
                                                                        "half_consistency_sim")})
    return rows


# --------------------------------------------------------------------------- one IMU, several sessions


def stability_rows(estimates: pd.DataFrame, alpha: float, se_column: str = "se") -> pd.DataFrame:
    """Heterogeneity of each parameter across sessions (module docstring).

    Parameters
    ----------
    estimates : DataFrame
        Columns ``recording``, ``parameter``, ``value`` and the standard error ``se_column``.
    alpha : float
    se_column : str
    """
    estimates = estimates.assign(se=estimates[se_column])
    rows = []
    for par, d in estimates.groupby("parameter", sort=False):
        d = d[np.isfinite(d.value) & (d.se > 0)]
        k = len(d)
        if k < 2:
            continue
        w = 1.0 / d.se.to_numpy() ** 2
        v = d.value.to_numpy()
        mean = float(np.sum(w * v) / np.sum(w))
        q = float(np.sum(w * (v - mean) ** 2))
        rows.append({"parameter": par, "sessions": k, "weighted_mean": mean, "pooled_se": float(1 / np.sqrt(w.sum())),
                     "spread": float(v.max() - v.min()), "spread_over_se": float((v.max() - v.min()) / np.sqrt(np.mean(d.se ** 2))),
                     "Q": q, "dof": k - 1, "p_value": float(dist.chi2_sf(q, k - 1)),
                     **{f"value_{r}": float(x) for r, x in zip(d.recording, v)},
                     **{f"se_{r}": float(s) for r, s in zip(d.recording, d.se)}})
    out = pd.DataFrame(rows)
    if len(out):
        out["p_adjusted"] = holm(out.p_value.to_numpy())
        out["stable"] = out.p_adjusted >= alpha
    return out


def estimates_of(name: str, report: dict, which: str = "before") -> list[dict]:
    """``recording, parameter, value, se`` of a report's model.

    ``se`` is the larger of the standard error from the rests' noise (``se_noise``) and the
    one scaled by the residual scatter (``se``): the pose noise, inflated by any excess, never
    deflated when the residuals scatter less than the rests predict (IMU-TK fork sessions:
    excess 0.5-0.9).
    """
    m = report[f"model_{which}"]["parameters"]
    return [{"recording": name, "parameter": k, "value": v["value"], "se": max(v["se"], v["se_noise"]),
             "se_scaled": v["se"], "se_noise": v["se_noise"]} for k, v in m.items()]


__all__ = ["BASE_PARAMETERS", "FEW_POSES_LIMITS", "GAP_COLUMNS", "diagnostics_row", "few_poses_rows", "poses_of",
           "with_disjoint_rests", "base_residuals", "estimates_of", "excess_rows", "gap_rows", "named_rows",
           "placement_of", "pose_data_of", "resimulate", "simulate_session", "stability_rows",
           "white_scale_of"]
