"""Claims-ledger rows of Burkhard, Sharma, Skaloud (2024), computed from the stage's tables.

One row per claim of the paper (``shared/papers/README.md``, section 1), each decided
by a function of :mod:`accelcal_repro.burkhard2024.checks` with the thresholds of the config
(``burkhard2024.claims``); the rule is part of the claim text.  Table 1 (field tests) is
written by the measured-data stage (:mod:`accelcal_repro.measured.claims`) as
``not_reproducible``.

Each rule needs a least sample before its verdict can depend on the data (:data:`MINIMUM`;
below it the row is ``not_testable_at_this_scale``): the rules with a tolerance of ``z``
standard errors need two Monte Carlo trials per grid point (with one, the standard error
is undefined and the rule can only fail, or, for Fig. 1(b)'s "no rise", never fail); the
others one trial, or one timing per method.
"""

from __future__ import annotations

from collections.abc import Mapping
from types import SimpleNamespace

import numpy as np
import pandas as pd

from ..claims import COLUMNS, Claim, ClaimRule, MinimumSample, Scale, judge_rules, validate_rows
from . import checks
from ..timing import preferred_backend
from .grid import Experiment, select

PAPER = "burkhard2024"
#: Values stated in the paper (Sec. 2).
PAPER_MAX_SCALE_PCT = 0.5
PAPER_MAX_NONORTH_PCT = 1.0
PAPER_NONORTH_RANGE_PCT = (1.0, 2.0)
PAPER_SPEEDUP = {"full_lls": 35.0, "bias_lls": 20.0}
_NONORTH_LO, _NONORTH_HI = PAPER_NONORTH_RANGE_PCT

_TRIALS, _PAIRS = "Monte Carlo trials per grid point", "paired Monte Carlo trials per grid point"
_SE = MinimumSample(2, _TRIALS, "a standard error needs two trials")
_ONE = MinimumSample(1, _TRIALS, "an RMS over trials needs one")
#: The least sample each rule needs (module docstring): the table it is counted in and the minimum.
MINIMUM = {
    "fig1a_full_lls_equals_nlls": ("summary", _SE),
    "fig1a_bias_lls_better_than_nlls": ("comparisons", MinimumSample(2, _PAIRS, "a standard error needs two pairs")),
    "max_errors_scale_nonorth": ("summary", _ONE),
    "max_errors_same_lls_nlls": ("comparisons", MinimumSample(1, _PAIRS, "a ratio of RMS errors needs one pair")),
    "fig1b_error_decreases_with_poses": ("summary", _SE),
    "fig1c_bias_nlls_diverges_lls_flat": ("summary", _ONE),
    "fig1e_bias_lls_superior_identity": ("summary", _ONE),
    "fig1d_scale_error_sensitive_to_g": ("summary", _ONE),
    "fig1d_nonorth_error_1_2pct": ("summary", _ONE),
    "speed_full": ("timing", MinimumSample(1, "timings per method", "a median ratio needs one timing")),
    "speed_bias": ("timing", MinimumSample(1, "timings per method", "a median ratio needs one timing")),
}


def _scale(cid: str, tables: Mapping[str, pd.DataFrame], exp: Experiment | None, methods=(), n_poses=None) -> Scale:
    """The sample of rule ``cid``: the fewest trials (pairs, timings) over the rows it reads."""
    which, minimum = MINIMUM[cid]
    t = tables[which]
    if which == "timing":
        t = t[(t["mode"] == "single") & t["method"].isin(methods) & (t["n_poses"] == n_poses)]
        col = "n_timings"
    else:
        t = select(t, exp)
        col = "n_trials" if which == "summary" else "n_pairs"
    n = pd.to_numeric(t[col], errors="coerce").min() if col in t and len(t) else np.nan
    return minimum.at(float(n))


def _row(claim: Claim, check: checks.Check, source: str, shown: str | None = None, fmt: str = "{:.3g}",
         scale: Scale | None = None) -> dict:
    """Ledger row from a check; ``shown`` replaces the formatted value (NaN: not reproduced)."""
    return claim.judge(check.value, bool(check), f"{source}: {check.detail}", fmt, scale=scale, shown=shown)


def _range(r) -> str:
    return f"[{r[0]:g}, {r[1]:g}] m/s²"


def _full_lls_equals_nlls(x, claim):
    c = checks.full_lls_equals_nlls(x.summary, x.comparisons, x.a, x.rng, x.r["equal_rel_tol"],
                                    x.r["efficiency_tol"], x.z)
    return _row(claim, c, x.comparisons_path, fmt="{:.2g}% max rel. diff.", scale=_scale(claim.claim_id, x.tables, x.a))


def _bias_lls_better(x, claim):
    c = checks.bias_lls_better_than_nlls(x.comparisons, x.a, x.rng, x.z)
    return _row(claim, c, x.comparisons_path, fmt="{:.3f} max RMS ratio LLS/NLLS",
                scale=_scale(claim.claim_id, x.tables, x.a))


def _max_errors(x, claim):
    c = checks.max_errors_match_paper(x.summary, x.a, x.rng, PAPER_MAX_SCALE_PCT, PAPER_MAX_NONORTH_PCT,
                                      x.r["magnitude_factor"])
    t = checks.max_relative_errors(x.summary, x.a, x.rng).set_index("method")
    shown = None
    if "full_lls" in t.index and np.isfinite(t.loc["full_lls", ["scale_max_pct", "nonorth_max_pct"]]).all():
        shown = (f"scale {t.loc['full_lls', 'scale_max_pct']:.3g}%, non-orth. {t.loc['full_lls', 'nonorth_max_pct']:.3g}%"
                 f" (full LLS, at {t.loc['full_lls', 'scale_at_noise']:g} m/s²)")
    return _row(claim, c, x.summary_path, shown=shown, scale=_scale(claim.claim_id, x.tables, x.a))


def _errors_same(x, claim):
    c = checks.errors_same_for_lls_and_nlls(x.comparisons, x.a, x.rng, x.r["equal_rel_tol"])
    return _row(claim, c, x.comparisons_path, fmt="{:.2g}% max rel. diff.", scale=_scale(claim.claim_id, x.tables, x.a))


def _decreases(x, claim):
    c = checks.decreases_with_poses(x.summary, x.b, x.r["decrease_factor"], x.z)
    return _row(claim, c, x.summary_path, fmt="{:.3g}x smallest drop", scale=_scale(claim.claim_id, x.tables, x.b))


def _bias_g_rule(cid: str, exp: str, fig: str, data: str, text: str, paper_value: str) -> ClaimRule:
    """Fig. 1(c) and 1(e): bias-only LLS flat, bias-only NLLS diverging with the error in g."""
    def rule(x):
        e, r = getattr(x, exp), x.r
        return (f"{fig}: {text} ({e.n_poses[0]} poses, noise {e.noise_std[0]:g} m/s², data with {data}). Rule: "
                f"reproduced if bias-only LLS's RMS bias error stays within {100 * r['flat_rel_tol']:g}% of its value "
                f"at g error 0 over g errors up to {max(e.g_error):g} m/s², and bias-only NLLS's RMS at the largest "
                f"g error is at least {r['diverge_factor']:g}x its value at g error 0 and {r['diverge_factor']:g}x "
                "bias-only LLS's")

    def verdict(x, claim):
        e = getattr(x, exp)
        c = checks.lls_flat_nlls_diverges(x.summary, e, x.r["flat_rel_tol"], x.r["diverge_factor"])
        return _row(claim, c, x.summary_path, fmt="{:.3g}x NLLS/LLS at the largest g error",
                    scale=_scale(cid, x.tables, e))
    return ClaimRule(cid, paper_value, rule, ("summary", exp, "r"), verdict)


def _scale_sensitive(x, claim):
    c = checks.scale_error_sensitive_to_g(x.summary, x.cd, x.r["diverge_factor"])
    return _row(claim, c, x.summary_path, fmt="{:.3g}x growth (smaller of LLS, NLLS)",
                scale=_scale(claim.claim_id, x.tables, x.cd))


def _nonorth_range(x, claim):
    c = checks.nonorth_error_in_range(x.summary, x.cd, PAPER_NONORTH_RANGE_PCT, x.r["magnitude_factor"])
    return _row(claim, c, x.summary_path, fmt="{:.3g}% largest", scale=_scale(claim.claim_id, x.tables, x.cd))


def _speed_detail(x, method: str) -> str:
    """What the speed row adds to its check: the Monte Carlo's per-trial ratio, other pose counts, backends."""
    extra = ""
    if x.mc_timing is not None and len(x.mc_timing):
        mt = x.mc_timing[x.mc_timing["n_poses"] == x.timing_n_poses].set_index("method")["per_trial_s"]
        nl = "full_nlls" if method == "full_lls" else "bias_nlls"
        if method in mt and nl in mt:
            extra = (f"; per Monte Carlo trial ({x.timing_n_poses} poses, batched closed form, median over cases): "
                     f"{mt[nl] / mt[method]:.0f}x")
    ts = x.timing_summary if "backend" in x.timing_summary else x.timing_summary.assign(backend="")
    mine = ts[(ts["mode"] == "single") & (ts["method"] == method) & (ts["interleave"] == x.interleave)]
    default = preferred_backend(ts, method)
    others = mine[(mine["backend"] == default) & (mine["n_poses"] != x.timing_n_poses)]
    extra += "".join(f"; {int(o['n_poses'])} poses: {o['speedup_median']:.1f}x" for _, o in others.iterrows())
    for _, o in mine[(mine["backend"] != default) & (mine["n_poses"] == x.timing_n_poses)].iterrows():
        extra += f"; {o['backend']} reference implementation: {o['speedup_median']:.1f}x"
    return extra


def _speed_rule(method: str, cid: str) -> ClaimRule:
    """The paper's speed-up of ``method`` over its NLLS counterpart."""
    paper = PAPER_SPEEDUP[method]
    base = "full NLLS" if method == "full_lls" else "bias-only NLLS"
    name = "Full LLS" if method == "full_lls" else "Bias-only LLS"

    def rule(x):
        return (f"{name} is about {paper:g}x faster than {base}. Rule: reproduced if the median per-problem time ratio "
                f"{base} / {name.split()[0].lower()} LLS at {x.timing_n_poses} poses, measured in one run on identical "
                f"problems ({x.interleave}-interleaved, repeated), is >= {x.r['speed_min_ratio']:g}x (the paper's "
                "order of magnitude; absolute ratios depend on implementation and machine)")

    def verdict(x, claim):
        c = checks.speedup(x.timing_summary, method, x.timing_n_poses, x.interleave, x.r["speed_min_ratio"])
        c = checks.Check(c.value, c.passed, c.detail + _speed_detail(x, method))
        return _row(claim, c, x.timing_path, fmt="{:.1f}×",
                    scale=_scale(cid, x.tables, None, (method, "full_nlls" if method == "full_lls" else "bias_nlls"),
                                 x.timing_n_poses))
    return ClaimRule(cid, f"≈{paper:g}×", rule, ("timing_summary", "mc_timing", "interleave", "timing_n_poses", "r"),
                     verdict)


#: The stage's claims, in the ledger's order: one entry per claim (:class:`accelcal_repro.claims.ClaimRule`).
RULES = (
    ClaimRule(
        "fig1a_full_lls_equals_nlls", "LLS ≈ NLLS",
        lambda x: f"Fig. 1(a): full LLS and full NLLS estimate the bias equally well, and well ({x.a.n_poses[0]} "
                  f"poses, data with M != I). Rule: reproduced if at every noise level in {_range(x.rng)} the RMS bias "
                  f"error of full LLS is within {100 * x.r['equal_rel_tol']:g}% of full NLLS's on the same trials and "
                  f"both are at most {1 + x.r['efficiency_tol']:g}x the Cramer-Rao bound (+{x.z:g} standard errors)",
        ("summary", "comparisons", "a", "r"), _full_lls_equals_nlls),
    ClaimRule(
        "fig1a_bias_lls_better_than_nlls", "LLS < NLLS",
        lambda x: f"Fig. 1(a): bias-only LLS estimates the bias better than bias-only NLLS ({x.a.n_poses[0]} poses, "
                  "data with M != I, so that both bias-only models are misspecified). Rule: reproduced if at every "
                  f"noise level in {_range(x.rng)} the RMS bias error ratio bias-only LLS / bias-only NLLS on the same "
                  f"trials, plus {x.z:g} standard errors, is below 1",
        ("comparisons", "a"), _bias_lls_better),
    ClaimRule(
        "max_errors_scale_nonorth", "≈0.5% (scale), ≈1% (non-orth.)",
        lambda x: "Sec. 2: the maximum estimation errors across the noise range are about 0.5% for the scale factor "
                  "and about 1% for the non-orthogonality (24 poses, not plotted). Reading: RMS over trials of "
                  "||s_est - s|| / ||s|| and ||theta_est - theta|| / ||theta||, maximum over the noise levels in "
                  f"{_range(x.rng)}. Rule: reproduced if both maxima lie within a factor {x.r['magnitude_factor']:g} "
                  "of the paper's values for full LLS and full NLLS",
        ("summary", "a", "r"), _max_errors),
    ClaimRule(
        "max_errors_same_lls_nlls", "same for both",
        lambda x: "Sec. 2: the scale-factor and non-orthogonality errors are the same for full LLS and full NLLS. "
                  f"Rule: reproduced if at every noise level in {_range(x.rng)} their RMS errors on the same trials "
                  f"differ by at most {100 * x.r['equal_rel_tol']:g}%",
        ("comparisons", "a", "r"), _errors_same),
    ClaimRule(
        "fig1b_error_decreases_with_poses", "decreases",
        lambda x: "Fig. 1(b): the estimation error decreases for all entities as the number of poses grows (noise "
                  f"{x.b.noise_std[0]:g} m/s², data with M != I). Rule: reproduced if for every method and entity "
                  "(bias; scale factor and non-orthogonality for the full methods) the RMS error at "
                  f"{max(x.b.n_poses)} poses is at most 1/{x.r['decrease_factor']:g} of that at the fewest poses the "
                  f"method accepts (q+1) and no step to more poses raises it by more than {x.z:g} standard errors",
        ("summary", "b", "r"), _decreases),
    _bias_g_rule("fig1c_bias_nlls_diverges_lls_flat", "cd", "Fig. 1(c)", "M != I",
                 "the bias error of bias-only NLLS diverges with the error in the assumed g, while bias-only LLS "
                 "stays low and constant", "NLLS diverges, LLS flat"),
    _bias_g_rule("fig1e_bias_lls_superior_identity", "e", "Fig. 1(e)", "M = I",
                 "with data generated with M = I, bias-only LLS is superior to bias-only NLLS with respect to "
                 "knowledge of g", "LLS superior"),
    ClaimRule(
        "fig1d_scale_error_sensitive_to_g", "highly sensitive",
        lambda x: "Fig. 1(d): the scale-factor error is highly sensitive to the error in the assumed g for both full "
                  f"LLS and full NLLS ({x.cd.n_poses[0]} poses, noise {x.cd.noise_std[0]:g} m/s²). Rule: reproduced "
                  f"if for both the RMS scale-factor error at g error {max(x.cd.g_error):g} m/s² is at least "
                  f"{x.r['diverge_factor']:g}x its value at g error 0",
        ("summary", "cd", "r"), _scale_sensitive),
    ClaimRule(
        "fig1d_nonorth_error_1_2pct", "1-2%",
        lambda x: "Fig. 1(d) text: over the g errors the non-orthogonality error stays in a range of 1%-2% (not "
                  f"plotted; {x.cd.n_poses[0]} poses, noise {x.cd.noise_std[0]:g} m/s², the project's choice: the "
                  "paper does not state it). Reading: RMS over trials of ||theta_est - theta|| / ||theta||. Rule: "
                  f"reproduced if for full LLS and full NLLS it lies in [{_NONORTH_LO / x.r['magnitude_factor']:g}%, "
                  f"{_NONORTH_HI * x.r['magnitude_factor']:g}%] (the paper's range widened by a "
                  f"factor {x.r['magnitude_factor']:g}) at every g error",
        ("summary", "cd", "r"), _nonorth_range),
    _speed_rule("full_lls", "speed_full"),
    _speed_rule("bias_lls", "speed_bias"),
)


def burkhard2024_claims(summary: pd.DataFrame, comparisons: pd.DataFrame, timing_summary: pd.DataFrame,
                        mc_timing: pd.DataFrame | None, experiments: Mapping[str, Experiment], rules: Mapping, *,
                        interleave: str = "block", timing_n_poses: int = 24,
                        summary_path: str = "results/burkhard2024/summary.csv",
                        comparisons_path: str = "results/burkhard2024/comparisons.csv",
                        timing_path: str = "results/burkhard2024/timing_summary.csv") -> pd.DataFrame:
    """The ledger rows of the paper's simulation claims and speed claims (:data:`RULES`).

    Parameters
    ----------
    summary, comparisons : DataFrame
        :func:`accelcal_repro.montecarlo.summarize` and :func:`~accelcal_repro.montecarlo.compare_methods`
        of the stage's Monte Carlo.
    timing_summary : DataFrame
        :func:`accelcal_repro.timing.summarize_timing` of the benchmark.
    mc_timing : DataFrame or None
        :func:`accelcal_repro.montecarlo.summarize_mc_timing` (per-trial times inside the Monte Carlo).
    experiments : mapping
        The stage's experiments (:func:`accelcal_repro.burkhard2024.grid.experiments_from_config`).
    rules : mapping
        ``burkhard2024.claims`` of the config (thresholds).
    """
    ctx = SimpleNamespace(
        summary=summary, comparisons=comparisons, timing_summary=timing_summary, mc_timing=mc_timing, r=rules,
        rng=tuple(rules["paper_noise_range"]), z=float(rules["z"]),
        a=experiments["fig1a"], b=experiments["fig1b"], cd=experiments["fig1cd"], e=experiments["fig1e"],
        tables={"summary": summary, "comparisons": comparisons, "timing": timing_summary},
        interleave=interleave, timing_n_poses=timing_n_poses, summary_path=summary_path,
        comparisons_path=comparisons_path, timing_path=timing_path)
    rows = judge_rules(PAPER, RULES, ctx)
    return validate_rows(pd.DataFrame(rows, columns=list(COLUMNS)), source="burkhard2024 claims")


__all__ = ["MINIMUM", "PAPER_MAX_NONORTH_PCT", "PAPER_MAX_SCALE_PCT", "PAPER_NONORTH_RANGE_PCT", "PAPER_SPEEDUP",
           "RULES", "burkhard2024_claims"]
