"""Figures of the discrepancy benchmark and of the ADIS16405 reference (matplotlib; return
Figures, :func:`accelcal.plotting.save_figure` writes them).  Each is drawn from the
stage's tidy tables only.

* :func:`plot_fpr`: false-positive rate per noise profile, wander vs white null, exact 95 % CIs.
* :func:`plot_confusion`: one confusion matrix (row of the benchmark × outcome) per profile.
* :func:`plot_power`: detection rate vs size (power curves) and naming accuracy per profile.
* :func:`plot_rows`: the outlier-pose and two-effect rows per profile, both nulls.
* :func:`plot_evidence`: per real session whose excess the effects leave, each candidate's
  minimum detectable effect against its estimate, or the poses it needs.
* :func:`plot_adis_allan`: the ADIS16405 Allan deviation to ~1000 s, its fitted model, and the
  pose-mean wander predicted vs observed on session-shaped pieces.

The figures of one recording's analysis (before/after residuals, Allan deviation) are in
:mod:`accelcal.discrepancy.figures`.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from accelcal.discrepancy.wander_process import wander_named
from accelcal.effects import EFFECT_IDS, EFFECTS
from accelcal.plotting import RC, plt

from .benchmark import CONSTANT_TEMPERATURE, ERROR, NONE, NOT_IDENTIFIABLE, OUTLIER

#: Display names: the outcomes that are not effects, and each effect's label (:mod:`accelcal.effects`).
LABELS = {NONE: "none", NOT_IDENTIFIABLE: "not identif.", CONSTANT_TEMPERATURE: "temp. (T const)",
          ERROR: "error", OUTLIER: "outlier pose", **{e.id: e.label for e in EFFECTS.values()}}
COLORS = {e: f"C{i}" for i, e in enumerate(EFFECT_IDS)}
NULL_STYLE = {"wander": {"color": "C0", "marker": "o", "label": "wander null (time-correlated noise)"},
              "white": {"color": "C3", "marker": "s", "label": "white null (negative control)"},
              "oracle": {"color": "C2", "marker": "^", "label": "oracle (the same tests, true noise covariance)"}}


def _label(x: str) -> str:
    return "+".join(LABELS.get(p, p) for p in x.split("+"))


def _main_null(nulls) -> str:
    return "wander" if "wander" in set(nulls) else sorted(set(nulls))[0]


def plot_fpr(summary: pd.DataFrame, profiles_table: pd.DataFrame, alpha: float, profiles):
    """False-positive rate (anything named on an effect-free recording) per profile and null,
    exact 95 % intervals on the effective number of independent recordings; shaded: the
    goal ≤ α, dashed: 2α.  One row per profile (config order, top to bottom)."""
    fp = summary[summary.metric == "false_positive_rate"]
    ww = profiles_table.groupby("profile", sort=False)["wander_over_white"].mean()
    nulls = [n for n in NULL_STYLE if n in set(fp.null)]
    main = _main_null(nulls) if nulls else ""
    with plt.rc_context(RC):
        fig, ax = plt.subplots(figsize=(8.0, 1.0 + 0.34 * len(profiles)), layout="constrained")
        y = np.arange(len(profiles))[::-1]
        for k, null in enumerate(nulls):
            d = fp[fp.null == null].set_index("profile").reindex(profiles)
            dy = (k - (len(nulls) - 1) / 2) * 0.22
            xerr = np.vstack([d.value - d.ci_low, d.ci_high - d.value])
            st = NULL_STYLE[null]
            ax.errorbar(d.value, y - dy, xerr=xerr, ls="none", capsize=2.5, ms=5, lw=1.1, color=st["color"],
                        marker=st["marker"], label=st["label"])
            for yi, v, hi, verdict in zip(y - dy, d.value, d.ci_high, d.verdict):
                if np.isfinite(v):
                    ax.annotate(f"{v:.3f}" + (" ✗" if null == main and verdict == "fail" else ""), (hi, yi),
                                xytext=(4, 0), textcoords="offset points", fontsize=6, va="center",
                                color=st["color"])
        ax.axvspan(0, alpha, color="C2", alpha=0.12, lw=0, label=f"goal: ≤ α = {alpha:g}")
        ax.axvline(2 * alpha, color="C2", ls="--", lw=1, label=f"upper 95% bound must be ≤ 2α = {2 * alpha:g}")
        first = fp[fp.null == main].set_index("profile").reindex(profiles)
        ticks = [f"{p}  (wander {ww.get(p, np.nan):.2f}, n {int(a) if np.isfinite(a) else 0}"
                 + (f", eff. {b:.0f}" if np.isfinite(b) and abs(b - a) > 0.5 else "") + ")"
                 for p, a, b in zip(profiles, first.n, first.n_independent)]
        ax.set_yticks(y, ticks, fontsize=7)
        ax.set_xlabel("false-positive rate: share of effect-free sessions with an effect or outlier named "
                      "(exact 95% CI)", fontsize=8)
        ax.set_xlim(0, max(0.25, float(np.nanmax(fp.ci_high)) * 1.12) if len(fp) else 1)
        ax.set_ylim(-0.6, len(profiles) - 0.4)
        ax.set_title(f"Effect-free sessions per noise profile (✗ = {main}-null verdict fails)\nwander = pose-mean "
                     "std of the profile's non-white noise / white pose-mean std", fontsize=8)
        # below the axes: inside, it covered the labels of the bottom rows
        fig.legend(*ax.get_legend_handles_labels(), loc="outside lower center", ncol=2, fontsize=6.5)
    return fig


def plot_confusion(scores: pd.DataFrame, size_mde: float, profiles, null: str | None = None):
    """Per profile: rows = benchmark rows at ``size_mde`` (plus none and constant T), columns = outcome."""
    null = null or _main_null(scores.null)
    d0 = scores[(scores.null == null) & ((scores.truth == NONE) | np.isclose(scores.size_mde, size_mde)
                                         | (scores.truth == CONSTANT_TEMPERATURE))]
    truths = [t for t in (NONE, *EFFECT_IDS) if t in set(d0.truth)]
    truths += sorted(t for t in set(d0.truth) if "+" in t) + [t for t in (OUTLIER, CONSTANT_TEMPERATURE)
                                                              if t in set(d0.truth)]
    cols = [*EFFECT_IDS, OUTLIER, NONE, NOT_IDENTIFIABLE, ERROR]
    ncol = 4
    nrow = math.ceil(len(profiles) / ncol)
    with plt.rc_context(RC):
        fig, axs = plt.subplots(nrow, ncol, figsize=(11.0, 2.55 * nrow + 0.6), layout="constrained", squeeze=False)
        for ax, prof in zip(axs.flat, profiles):
            d = d0[d0.profile == prof]
            F = np.zeros((len(truths), len(cols)))
            for i, t in enumerate(truths):
                dt = d[d.truth == t]
                for j, c in enumerate(cols):
                    F[i, j] = (dt.outcome == c).mean() if len(dt) else np.nan
            ax.imshow(F, cmap="Blues", vmin=0, vmax=1, aspect="auto")
            for i, t in enumerate(truths):
                exp = d[d.truth == t].expected.iloc[0] if (d.truth == t).any() else ""
                for e in exp.split("+"):  # a pair: either effect may come first
                    if e in cols:
                        j = cols.index(e)
                        ax.add_patch(plt.Rectangle((j - 0.5, i - 0.5), 1, 1, fill=False, ec="C3", lw=1.0))
                for j in range(len(cols)):
                    if F[i, j] >= 0.05:
                        ax.text(j, i, f"{F[i, j]:.2f}".lstrip("0"), ha="center", va="center", fontsize=5,
                                color="w" if F[i, j] > 0.6 else "k")
            ax.set_xticks(range(len(cols)), [LABELS.get(c, c) for c in cols], rotation=90, fontsize=5.5)
            ax.set_yticks(range(len(truths)), [_label(t) for t in truths], fontsize=5.5)
            ax.grid(False)
            ok = d[d.truth != NONE]
            ax.set_title(f"{prof}: correct {ok.correct.mean():.2f}" if len(ok) else prof, fontsize=7.5)
        for ax in axs.flat[len(profiles):]:
            ax.set_visible(False)
        fig.suptitle(f"Outcome of the loop ({null} null) per hidden row at {size_mde:g} × its oracle MDE "
                     f"(red box: a correct first outcome; two effects: either of the pair; "
                     f"rows: hidden, columns: named first)", fontsize=8.5)
    return fig


def plot_power(rates: pd.DataFrame, power: float, profiles, curve_profiles, sizes):
    """Top: detection rate vs size for the power-curve profiles (wander null solid, white
    dashed where it ran, the oracle dotted); bottom: naming accuracy (effect named first) per profile at the main ``sizes``
    (every profile has them), wander null."""
    effects = [e for e in EFFECT_IDS if e in set(rates.truth)]
    main = _main_null(rates.null)
    cmap = plt.get_cmap("tab10")
    with plt.rc_context(RC):
        fig, axs = plt.subplots(2, len(effects), figsize=(11.5, 6.4), layout="constrained", squeeze=False)
        for j, e in enumerate(effects):
            ax = axs[0, j]
            for k, prof in enumerate(curve_profiles):
                for null, ls in (("wander", "-"), ("white", "--"), ("oracle", ":")):
                    r = rates[(rates.truth == e) & (rates.profile == prof) & (rates.null == null)].sort_values(
                        "size_mde")
                    if not len(r):
                        continue
                    yerr = np.vstack([r.detection_rate - r.detection_ci_low, r.detection_ci_high - r.detection_rate])
                    ax.errorbar(r.size_mde * (1 + 0.02 * k), r.detection_rate, yerr=yerr, color=cmap(k), ls=ls,
                                marker="o", ms=3, lw=1, capsize=1.5,
                                label=f"profile {prof}, {null} null" if j == 0 else None)
            ax.plot([1.0], [power], marker="*", color="k", ms=9, ls="none",
                    label=f"oracle test's power at 1 MDE ({power:g})" if j == 0 else None)
            ax.set_xscale("log")
            ticks = sorted(set(rates.size_mde[rates.truth == e]))
            ax.set_xticks(ticks, [f"{t:g}" for t in ticks])
            ax.minorticks_off()
            ax.set_ylim(-0.02, 1.02)
            ax.set_title(LABELS[e], fontsize=9)
            ax.set_xlabel("size [× oracle MDE]")
            ax = axs[1, j]
            r = rates[(rates.truth == e) & (rates.null == main)]
            x = np.arange(len(profiles))
            main_sizes = sorted(sizes)
            for k, s in enumerate(main_sizes):
                rs = r[np.isclose(r.size_mde, s)].set_index("profile").reindex(profiles)
                if rs.accuracy.isna().all():
                    continue
                yerr = np.vstack([rs.accuracy - rs.accuracy_ci_low, rs.accuracy_ci_high - rs.accuracy])
                ax.errorbar(x + 0.2 * (k - (len(main_sizes) - 1) / 2), rs.accuracy, yerr=yerr, ls="none", marker="o",
                            ms=3, capsize=1.5, lw=0.8, color=plt.get_cmap("viridis")(k / max(1, len(main_sizes) - 1)),
                            label=f"{s:g} MDE" if j == 0 else None)
            ax.set_xticks(x, profiles, rotation=90, fontsize=6)
            ax.set_ylim(-0.02, 1.02)
            ax.axhline(power, color="k", lw=0.7, ls=":")
        axs[0, 0].set_ylabel("detection rate (named), 95% CI")
        axs[1, 0].set_ylabel(f"named first ({main} null), 95% CI")
        # below the panels: inside the first one it covered points at either end of the curve
        fig.legend(*axs[0, 0].get_legend_handles_labels(), loc="outside lower center", ncol=5, fontsize=6.5)
        axs[1, 0].legend(fontsize=6, loc="lower left", title="size", title_fontsize=6)
        fig.suptitle("Power of the loop per effect: top, detection rate vs size for the power-curve profiles; "
                     "bottom, naming accuracy per noise profile (dotted: the design power)", fontsize=9)
    return fig


def plot_rows(rates: pd.DataFrame, profiles):
    """Accuracy of the outlier-pose rows (named and located) and of the two-effect rows (both
    named, nothing else) per profile, each size, every null that ran on them and the oracle."""
    kinds = [(OUTLIER, "outlier pose: named, at the right pose (the white null has no outlier test: 0 by design)")]
    kinds += [(t, f"{_label(t)}: both named, nothing else") for t in sorted(set(rates.truth)) if "+" in t]
    with plt.rc_context(RC):
        fig, axs = plt.subplots(len(kinds), 1, figsize=(9.0, 2.6 * len(kinds) + 0.8), layout="constrained",
                                squeeze=False)
        x = np.arange(len(profiles))
        for ax, (truth, title) in zip(axs[:, 0], kinds):
            r = rates[rates.truth == truth]
            combos = [(n, s) for n in NULL_STYLE for s in sorted(set(r.size_mde)) if ((r.null == n)
                                                                                      & np.isclose(r.size_mde, s)).any()]
            for k, (null, s) in enumerate(combos):
                rs = r[(r.null == null) & np.isclose(r.size_mde, s)].set_index("profile").reindex(profiles)
                yerr = np.vstack([rs.accuracy - rs.accuracy_ci_low, rs.accuracy_ci_high - rs.accuracy])
                st = NULL_STYLE[null]
                ax.errorbar(x + 0.1 * (k - (len(combos) - 1) / 2), rs.accuracy, yerr=yerr, ls="none", capsize=1.5,
                            lw=0.8, ms=4, color=st["color"], marker=st["marker"],
                            mfc="none" if s < max(r.size_mde) else st["color"], label=f"{null} null, {s:g} MDE")
            ax.set_xticks(x, profiles, rotation=30, ha="right", fontsize=7)
            ax.set_ylim(-0.02, 1.02)
            ax.set_ylabel("correct (95% CI)")
            ax.set_title(title, fontsize=8.5)
        # one legend below the panels: inside, it covered the points at 1.0 of the last profiles
        fig.legend(*axs[0, 0].get_legend_handles_labels(), loc="outside lower center", ncol=4, fontsize=6.5)
        fig.suptitle("Outlier-pose and two-effect rows of the benchmark per noise profile", fontsize=9)
    return fig


def plot_adis_allan(curves: pd.DataFrame, allan: pd.DataFrame, check: pd.DataFrame):
    """ADIS16405: measured Allan deviation (68 % CI) to ~1000 s per axis with the BIC-chosen
    library model and its terms (fitted range shaded); last panel: pose-mean wander on
    session-shaped pieces, observed vs predicted by the reference model and by the
    stochastic layer on the pieces' own ≤ 10 s rests."""
    axes = list(dict.fromkeys(curves.axis))
    with plt.rc_context(RC):
        fig, axs = plt.subplots(1, len(axes) + 1, figsize=(12.0, 3.9), layout="constrained")
        for ax, a in zip(axs, axes):
            c = curves[curves.axis == a]
            m = allan[allan.axis == a]
            ax.errorbar(m.tau_s, 1e3 * m.adev, yerr=1e3 * np.vstack([m.adev - m.adev_ci_low, m.adev_ci_high - m.adev]),
                        fmt="o", color="k", ms=3, lw=0.8, capsize=1.5, label="measured (68% CI)", zorder=4)
            ax.plot(c.tau_s, 1e3 * c.adev_model, color="C3", lw=1.4, label="chosen model")
            for k, col in enumerate(x for x in c.columns if x.startswith("adev_") and x not in
                                    ("adev_measured", "adev_model")):
                ax.plot(c.tau_s, 1e3 * c[col], ls="--", lw=0.8, color=f"C{k}", label=col[5:])
            fitted = c[c.fitted]
            ax.axvspan(fitted.tau_s.min(), fitted.tau_s.max(), color="0.9", zorder=0, label="fitted range")
            ax.set(xscale="log", yscale="log", xlabel="τ [s]")
            ax.set_ylim(0.3 * 1e3 * c.adev_measured.min(), 2 * 1e3 * c.adev_measured.max())
            ax.set_title(f"axis {a}", fontsize=9)
        axs[0].set_ylabel("Allan deviation [mm/s²]")
        axs[0].legend(fontsize=6, loc="lower left")
        ax = axs[-1]
        d = check.set_index("axis")
        rows = [a for a in [*axes, "all"] if a in d.index]
        x = np.arange(len(rows))
        obs = np.sqrt(d.loc[rows, "observed_var"])
        lo = np.sqrt(d.loc[rows, "observed_ci_low"].clip(lower=0))
        hi = np.sqrt(d.loc[rows, "observed_ci_high"])
        ax.bar(x - 0.27, 1e3 * np.sqrt(d.loc[rows, "se_var"]), 0.18, color="0.7", label="calibration's pose SE")
        ax.bar(x - 0.09, 1e3 * obs, 0.18, color="k", yerr=1e3 * np.vstack([obs - lo, hi - obs]), capsize=2,
               label="observed (95% CI over pieces)")
        ax.bar(x + 0.09, 1e3 * np.sqrt(d.loc[rows, "reference_var"]), 0.18, color="C3", label="reference model")
        if "layer_var" in d:
            ax.bar(x + 0.27, 1e3 * np.sqrt(d.loc[rows, "layer_var"]), 0.18, color="C0",
                   label=f"layer on ≤10 s rests ({int(d['layer_pieces'].max())} pieces)")
        ax.set_xticks(x, rows)
        ax.set_ylabel("pose-mean scatter about the session mean [mm/s²]")
        ax.set_title(f"pose-mean scatter, {int(d['pieces'].max())} pieces", fontsize=9)
        ax.legend(fontsize=6, loc="upper left")
        fig.suptitle("ADIS16405, 2.78 h at rest: Allan deviation and what it means for the pose means of a "
                     "calibration session", fontsize=9)
    return fig


def plot_sessions(reports: dict, sims: dict, gaps: pd.DataFrame):
    """Per real session: the distribution (ECDF) of the measured normalised pose residuals
    |r/σ| of the base model against those of the session re-simulated with the model before
    (base calibration, white noise of the rests) and after (what the loop named added)."""
    names = list(reports)
    ncol = min(3, len(names))
    nrow = math.ceil(len(names) / ncol)
    with plt.rc_context(RC):
        fig, axs = plt.subplots(nrow, ncol, figsize=(3.8 * ncol, 3.0 * nrow + 0.5), layout="constrained",
                                squeeze=False)
        for ax, name in zip(axs.flat, names):
            rep = reports[name]
            meas = np.abs(np.array(rep["poses"]["residual_before"]) / np.array(rep["poses"]["sigma"]))
            x = np.sort(meas)
            ax.step(x, np.arange(1, x.size + 1) / x.size, where="post", color="k", lw=1.6, label="measured")
            g = gaps[gaps.recording == name].set_index("model")
            nothing = not rep.get("effects") and not wander_named(rep.get("noise_model"))
            for model, col in (("before", "C0"), ("after", "C3")):
                if model == "after" and nothing:  # nothing named: the model after is the one before
                    continue
                z = sims[name]
                z = np.sort(np.abs(z[(z.model == model) & (z.pose >= 0)].z.to_numpy()))
                if not z.size or model not in g.index:
                    continue
                r = g.loc[model]
                ax.plot(z, np.arange(1, z.size + 1) / z.size, color=col, lw=1.1,
                        label=f"re-simulated, {model}: excess {r.excess_sim_median:.2f}, KS {r.ks_distance:.2f}")
            named = "+".join(rep.get("effects", [])) or "no effect"
            nm = rep.get("noise_model") or {}
            wander = nm.get("process", "") if wander_named(rep.get("noise_model")) else "no wander"
            ax.set_title(f"{name}: {rep['n_poses']} poses, excess {g.excess_measured.iloc[0]:.2f}\n"
                         f"named: {named}; {wander}" if len(g) else f"{name}: {rep['n_poses']} poses (no dof)",
                         fontsize=7.5)
            ax.set_xlabel("|pose residual| / its white noise σ_i", fontsize=7.5)
            ax.legend(fontsize=5.5, loc="lower right")
            m = "after" if "after" in g.index and not nothing else "before"
            if len(g) and "half_consistency_measured" in g and np.isfinite(g.loc[m, "half_consistency_measured"]):
                r = g.loc[m]
                ax.text(0.98, 0.45, f"halves of each pose agree (r):\nmeasured {r.half_consistency_measured:.2f}, "
                        f"re-simulated {m} {r.half_consistency_sim_median:.2f}\n"
                        f"[{r.half_consistency_sim_q025:.2f}, {r.half_consistency_sim_q975:.2f}]",
                        transform=ax.transAxes, ha="right", va="center", fontsize=5.5,
                        bbox={"fc": "w", "ec": "0.7", "lw": 0.5})
        for ax in axs.flat[len(names):]:
            ax.set_visible(False)
        axs[0, 0].set_ylabel("cumulative share of poses")
        fig.suptitle("Real sessions re-simulated before / after what the loop names: gap to the measured residuals",
                     fontsize=8.5)
    return fig


def evidence_sessions(evidence: pd.DataFrame, reports: dict) -> list[str]:
    """The sessions :func:`plot_evidence` shows: those whose excess the named effects leave
    (``excess_status_white`` neither ``no excess`` nor ``explained``) and that have tested candidates."""
    out = []
    for name, rep in reports.items():
        white = rep.get("excess_status_white", rep.get("excess_status"))
        if white not in ("no excess", "explained", "untestable") and (evidence.recording == name).any():
            out.append(name)
    return out


def plot_evidence(evidence: pd.DataFrame, reports: dict):
    """Per session whose excess the named effects leave: each candidate's minimum detectable
    effect (circle: a larger one would have been named with the design power) and its
    estimate with the upper end of its 95 % interval (bar), as the largest change of a pose
    mean, with its adjusted p-value; a candidate the poses cannot test is written out with
    the poses it needs.  The band: the named per-placement offset (or wander) with its 95 %
    interval; dotted: the median white noise of a pose residual."""
    names = evidence_sessions(evidence, reports)
    if not names:
        names = list(dict.fromkeys(evidence.recording))[:1]
    with plt.rc_context(RC):
        fig, axs = plt.subplots(len(names), 1, figsize=(7.6, 1.0 + 0.42 * max(len(evidence[evidence.recording == n])
                                                                            for n in names) * len(names) + 0.6),
                                layout="constrained", squeeze=False)
        for ax, name in zip(axs[:, 0], names):
            _evidence_panel(ax, evidence[evidence.recording == name], reports[name], name)
        fig.suptitle("What rules each candidate out, or what it needs: minimum detectable effect vs estimate "
                     "(largest change of a pose mean)", fontsize=8.5)
    return fig


def _evidence_panel(ax, ev: pd.DataFrame, rep: dict, name: str):
    mg = rep.get("unit") == "m/s^2"
    scale = 1e3 / 9.80665 if mg else 1.0
    unit = "mg" if mg else (rep.get("unit") or "data unit")
    cands = ev[ev["item"] == "effect"].reset_index(drop=True)
    noise = ev[ev["item"] == "noise"]
    # σ_i is in the unit of g (the residual's); the data unit per unit of g is the gain 1 + s
    gain = np.mean([1.0 + rep["model_before"]["parameters"][f"s_{a}"]["value"] for a in "xyz"])
    sigma = float(np.median(rep["poses"]["sigma"])) * gain * scale
    ax.axvline(sigma, color="0.5", ls=":", lw=0.9, label=f"pose noise (median σ_i) {sigma:.3g} {unit}")
    if len(noise) and np.isfinite(noise.estimate_data.iloc[0]):
        n0 = noise.iloc[0]
        lo = n0.estimate_low_data if np.isfinite(n0.estimate_low_data) else n0.estimate_data
        hi = n0.estimate_high_data if np.isfinite(n0.estimate_high_data) else 10 * n0.estimate_data
        ax.axvspan(lo * scale, hi * scale, color="C2", alpha=0.15, lw=0)
        ax.axvline(n0.estimate_data * scale, color="C2", lw=1.2,
                   label=f"{n0.candidate}: {n0.estimate_data * scale:.3g} {unit} per axis (95 % band)")
    ymax = len(cands)
    for y, c in cands.iterrows():
        if c.identifiable and np.isfinite(c.mde_data):
            ax.plot(c.mde_data * scale, y, "o", mfc="none", color="C0", ms=6,
                    label="minimum detectable effect (design power)" if y == 0 else None)
            if np.isfinite(c.estimate_data):
                ax.plot([c.estimate_data * scale, c.estimate_high_data * scale], [y, y], color="C3", lw=2,
                        solid_capstyle="butt", label="estimate .. upper 95 %" if y == 0 else None)
            ax.text(1.01, y, f"p_adj {c.p_adjusted:.2g}" + (" named" if c.named else ""), transform=ax.get_yaxis_transform(),
                    va="center", fontsize=6)
        else:
            need = f"needs ≥ {int(c.poses_needed)} poses (has {int(c.n_poses)})" if pd.notna(c.poses_needed) else \
                (c.reasons[:70] + "…" if len(str(c.reasons)) > 70 else c.reasons)
            ax.text(0.02, y, f"not testable here: {need}", transform=ax.get_yaxis_transform(), va="center",
                    fontsize=6, color="0.3")
    ax.set_yticks(range(ymax), [LABELS.get(c, c) for c in cands.candidate])
    ax.set_ylim(ymax - 0.5, -0.5)
    ax.set_xscale("log")
    ax.set_xlabel(f"largest change of a pose mean [{unit}] (at the minimum detectable effect, at the estimate)")
    nm = rep.get("noise_model") or {}
    ax.set_title(f"{name}: {rep['n_poses']} poses, excess {rep.get('excess_before', float('nan')):.3g}; "
                 f"named: {'+'.join(rep.get('effects') or []) or 'no effect'}, {nm.get('term', '')}; "
                 f"excess {rep.get('excess_status', '')} with it", fontsize=7.5)
    ax.legend(fontsize=5.5, loc="lower right")


def plot_stability(stability: pd.DataFrame, estimates: pd.DataFrame):
    """Sessions of one IMU: every parameter per session with its standard error, relative to
    the weighted mean over the sessions, with Cochran's test (Holm-adjusted p) in the title."""
    alt = stability[stability.yardstick == "se_scaled"].set_index("parameter")
    stability = stability[stability.yardstick == "se"]
    pars = list(dict.fromkeys(stability.parameter))
    ncol = min(5, len(pars))
    nrow = math.ceil(len(pars) / ncol)
    with plt.rc_context(RC):
        fig, axs = plt.subplots(nrow, ncol, figsize=(2.4 * ncol, 2.3 * nrow + 0.6), layout="constrained",
                                squeeze=False)
        for ax, par in zip(axs.flat, pars):
            st = stability[stability.parameter == par].iloc[0]
            e = estimates[(estimates.parameter == par) & estimates.recording.isin(
                [c[6:] for c in stability.columns if c.startswith("value_") and np.isfinite(st[c])])]
            x = np.arange(len(e))
            ax.errorbar(x, e.value - st.weighted_mean, yerr=1.96 * e.se, fmt="o", ms=4, capsize=2,
                        color="C2" if st.stable else "C3")
            ax.axhline(0, color="0.5", lw=0.8)
            ax.set_xticks(x, [r.split("_")[-1] for r in e.recording], fontsize=7)
            p_alt = alt.loc[par, "p_adjusted"] if par in alt.index else float("nan")
            ax.set_title(f"{par}: {'stable' if st.stable else 'NOT stable'}\np_adj {st.p_adjusted:.2g} "
                         f"(scatter only: {p_alt:.2g})", fontsize=7)
            ax.tick_params(axis="y", labelsize=6)
            ax.set_ylabel({"b": "bias [data unit]", "s": "scale factor [-]", "t": "angle [rad]"}[par[0]], fontsize=6.5)
        for ax in axs.flat[len(pars):]:
            ax.set_visible(False)
        fig.suptitle("One IMU, several sessions: each parameter minus its weighted mean over the sessions (95% "
                     "intervals, the rests' noise inflated by any excess)\ngreen: consistent (Cochran's Q, Holm); in "
                     "brackets the adjusted p with the residual scatter alone as yardstick", fontsize=8)
    return fig


__all__ = ["COLORS", "LABELS", "NULL_STYLE", "plot_adis_allan", "plot_confusion", "plot_fpr", "plot_power",
           "plot_rows", "plot_sessions", "plot_stability"]
