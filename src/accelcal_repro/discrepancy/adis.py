"""The 2.78 h static ADIS16405 recording: what slow bias wander looks like on a real MEMS.

Three questions, each a tidy table (figures and claims are computed from them):

1. **Allan deviation to ~1000 s** (:func:`reference_allan`): the overlapping Allan
   deviation of the whole record (10⁶ samples at 100 Hz, unit m/s²), octaves up to the
   largest τ with white-FM edf ≥ 3, with 68 % chi-square intervals.
2. **Do the stochastic layer's long-τ terms describe it?** (:func:`fit_long_tau`): every
   model of the library's terms (white plus any subset of quantization, flicker, random
   walk, ramp, and at most one Gauss–Markov) fitted by the layer's Gamma likelihood
   (:func:`accelcal.noise.fit_avar`) on τ from ``tau_min`` (1 s: the
   pose means of a calibration average 5–45 s, shorter τ does not reach them) to
   ``tau_max``; the model with the smallest BIC is the axis's reference model.  Reported:
   its coefficients, deviance, and the worst and RMS ratio of measured to model Allan
   deviation over the fitted τ (the misfit in per cent a user would see).
3. **What do calibration-length rests predict?** (:func:`session_check`): the record
   is cut into disjoint pieces laid out as the benchmark's session (an initial rest, then
   ``n_poses − 1`` short rests between motions); on each piece the pose means are taken
   over the trimmed rests exactly as a calibration would.  The *observed* scatter of
   those pose means about their session mean, pooled over pieces and axes, is compared
   with what the calibration's own standard errors imply (its ratio is the excess the
   loop sees) and with what (a) the reference model of question 2 and (b) the stochastic
   layer run on the piece's own rests (the ≤ 10 s view of the Xsens session)
   predict for the same layout (:func:`accelcal.discrepancy.stochastic.pose_difference_variance`).
   The ratio predicted / observed is the check: 1 when a model extrapolates correctly
   from its τ range to the session.
"""

from __future__ import annotations

import math
from itertools import combinations

import numpy as np
import pandas as pd

from accelcal.discrepancy.stochastic import pose_difference_variance, rest_segments, stochastic_layer
from accelcal.noise import TERMS, allan_variance, fit_avar

from accelcal.static import integrated_autocorr_time

from .profiles import centred

AXES = ("x", "y", "z")
#: Terms the long-τ fit may add to white noise (one two-parameter term at most).
LONG_TAU_TERMS = ("quantization", "bias_instability", "random_walk", "drift_ramp", "gauss_markov")


def noise_of(rec, g0: float = 9.80665) -> np.ndarray:
    """The record's accelerometer in m/s² about its mean, shape (n, 3) (the file is in g)."""
    acc = np.asarray(rec.acc, float) * g0
    return acc - acc.mean(axis=0)


def reference_allan(acc: np.ndarray, fs: float, min_edf: float = 3.0):
    """Allan variance of the whole record and its tidy table (axis, tau, adev, 68 % interval, edf)."""
    av = allan_variance([acc], fs, min_edf=min_edf)
    lo, hi = av.adev_interval(0.683)
    rows = [{"axis": ax, "tau_s": float(t), "adev": float(av.adev[i, j]), "adev_ci_low": float(lo[i, j]),
             "adev_ci_high": float(hi[i, j]), "edf_white": float(av.edf[i]), "n_terms": int(av.n_terms[i])}
            for j, ax in enumerate(AXES) for i, t in enumerate(av.taus)]
    return av, pd.DataFrame(rows)


def _models():
    """White plus every subset of :data:`LONG_TAU_TERMS` (at most one two-parameter term)."""
    out = []
    for k in range(len(LONG_TAU_TERMS) + 1):
        for sub in combinations(LONG_TAU_TERMS, k):
            out.append(("white",) + sub)
    return out


def fit_long_tau(av, fs: float, tau_min: float, tau_max: float) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Every library model fitted per axis on ``tau_min <= τ <= tau_max``; BIC picks the reference.

    Returns
    -------
    models : DataFrame
        One row per (axis, model): ``terms``, ``deviance``, ``n_params``, ``bic``,
        ``chosen``, ``max_ratio``/``rms_log_ratio`` (measured / model ADEV over the fitted τ)
        and the coefficients ``coef_<term>`` (``tc_s`` for the Gauss–Markov correlation time).
    curves : DataFrame
        The chosen model's ADEV at every τ of the record (axis, tau_s, adev_model, by term).
    """
    sel = (av.taus >= tau_min) & (av.taus <= tau_max)
    if sel.sum() < 4:
        raise ValueError(f"only {int(sel.sum())} octaves of tau in [{tau_min}, {tau_max}] s")
    taus, edf = av.taus[sel], av.edf[sel]
    rows, curves = [], []
    for j, ax in enumerate(AXES):
        fits = []
        for terms in _models():
            f = fit_avar(taus, av.avar[sel, j], edf, terms, fs)
            n_par = len(terms) + sum(1 for t in terms if TERMS[t].shape_key)
            ratio = np.sqrt(av.avar[sel, j] / f.avar(taus, fs))
            row = {"axis": ax, "terms": "+".join(terms), "deviance": f.deviance, "n_params": n_par,
                   "bic": f.deviance + n_par * math.log(taus.size), "max_ratio": float(np.max(np.abs(np.log(ratio)))),
                   "rms_log_ratio": float(np.sqrt(np.mean(np.log(ratio) ** 2))), "tau_min_s": float(taus.min()),
                   "tau_max_s": float(taus.max()), "n_tau": int(taus.size),
                   **{f"coef_{t}": v for t, v in f.coefficients.items()},
                   "tc_s": f.shape if "gauss_markov" in terms else np.nan}
            row["max_ratio"] = float(np.exp(row["max_ratio"]))
            fits.append((row, f))
        best = min(range(len(fits)), key=lambda i: fits[i][0]["bic"])
        for i, (row, _) in enumerate(fits):
            rows.append({**row, "chosen": i == best})
        f = fits[best][1]
        for i, t in enumerate(av.taus):
            curves.append({"axis": ax, "tau_s": float(t), "adev_measured": float(av.adev[i, j]),
                           "adev_model": float(np.sqrt(f.avar([t], fs)[0])), "fitted": bool(sel[i]),
                           **{f"adev_{k}": float(np.sqrt(c * TERMS[k].basis(np.array([t]), fs,
                                                                           f.shape if TERMS[k].shape_key else None)[0]))
                              for k, c in zip(f.term_ids, f.c)}})
    return pd.DataFrame(rows), pd.DataFrame(curves)


def chosen_models(models: pd.DataFrame) -> list[dict]:
    """The reference model of each axis as ``{term: value}`` (Gauss–Markov: ``(σ, T_c)``), x, y, z."""
    out = []
    for ax in AXES:
        r = models[(models.axis == ax) & models.chosen].iloc[0]
        m = {}
        for t in r.terms.split("+"):
            v = float(r[f"coef_{t}"])
            m[t] = (v, float(r.tc_s)) if TERMS[t].shape_key else v
        out.append(m)
    return out


def session_layout(session) -> tuple[np.ndarray, int]:
    """Trimmed rest windows ``[start, stop)`` of the benchmark session and its length in samples."""
    return session.trimmed_windows(), session.n_samples


def _predicted_scatter(model: dict, starts, durations) -> float:
    """Mean over poses of the variance of the pose-mean errors about their session mean that
    a noise model (all its terms, white included) predicts: ``mean diag(−½ P D P)``."""
    return float(sum(np.diag(centred(pose_difference_variance(term, value, starts, durations))).mean()
                     for term, value in model.items()))


def session_check(acc: np.ndarray, fs: float, session, reference: list[dict], *, n_layer: int, seed: int,
                  n_boot: int, n_resim: int, candidates) -> pd.DataFrame:
    """Observed vs predicted pose-mean scatter on disjoint session-shaped pieces of the record (module docstring).

    Returns one row per (piece, axis), variances in (m/s²)²: ``observed_var``, the mean
    over poses of the squared deviation of the pose means from their session mean;
    ``se_var``, what the calibration's own standard errors imply for it,
    ``(1 − 1/n) mean(se²)`` with ``se`` the static detection's standard error of each
    pose mean (:func:`accelcal.static.detect_static`: the loop's pose noise);
    ``reference_var`` and ``reference_white_var``, the same predicted by the reference
    model and by its white term alone; for the first ``n_layer`` pieces ``layer_var``
    and ``layer_terms`` (stochastic layer on the piece's own rests).
    """
    win, n = session_layout(session)
    starts, durations = win[:, 0] / fs, (win[:, 1] - win[:, 0]) / fs
    n_pieces = len(acc) // n
    rows = []
    for k in range(n_pieces):
        piece = acc[k * n:(k + 1) * n]
        segs = rest_segments(piece, win)
        means = np.array([s.mean(axis=0) for s in segs])
        se2 = np.array([s.var(axis=0, ddof=1) * integrated_autocorr_time(s) / len(s) for s in segs])
        layer = None
        if k < n_layer:
            layer = stochastic_layer(segs, fs, seed=seed + k, n_boot=n_boot, n_resim=n_resim, intervals=win,
                                     candidates=candidates)
        n_p = len(segs)
        for j, ax in enumerate(AXES):
            dev = means[:, j] - means[:, j].mean()
            row = {"piece": k, "axis": ax, "n_poses": n_p, "observed_var": float(dev @ dev / n_p),
                   "se_var": float((1 - 1 / n_p) * se2[:, j].mean()),
                   "reference_var": _predicted_scatter(reference[j], starts, durations),
                   "reference_white_var": _predicted_scatter({"white": reference[j]["white"]}, starts, durations)}
            if layer is not None:
                a = layer.axes[j]
                row["layer_terms"] = "+".join(a.named) or "none"
                row["layer_var"] = _predicted_scatter(a.model_after, starts, durations)
            rows.append(row)
    return pd.DataFrame(rows)


def session_check_summary(check: pd.DataFrame) -> pd.DataFrame:
    """Per axis and pooled: the observed pose-mean scatter with its 95 % interval over pieces
    (t interval of the per-piece values), the excess over the calibration's standard errors
    (``excess_observed`` = sqrt(observed / se), what the loop sees), and predicted / observed
    for the reference model and for the stochastic layer on ≤ 10 s rests."""
    from scipy import stats

    rows = []
    for ax, d in [*check.groupby("axis"), ("all", check)]:
        by_piece = d.groupby("piece")[["observed_var", "se_var", "reference_var", "reference_white_var"]].mean()
        m = len(by_piece)
        obs = by_piece.observed_var
        half = float(stats.t.ppf(0.975, m - 1) * obs.std(ddof=1) / math.sqrt(m)) if m > 1 else float("nan")
        o, se, ref = float(obs.mean()), float(by_piece.se_var.mean()), float(by_piece.reference_var.mean())
        row = {"axis": ax, "pieces": m, "observed_var": o, "observed_ci_low": o - half, "observed_ci_high": o + half,
               "se_var": se, "excess_observed": math.sqrt(o / se), "wander_over_white": math.sqrt(max(o - se, 0) / se),
               "reference_var": ref, "reference_white_var": float(by_piece.reference_white_var.mean()),
               "reference_over_observed": ref / o}
        if "layer_var" in d and d["layer_var"].notna().any():
            lay = d.dropna(subset=["layer_var"])
            obs_l = float(lay.observed_var.mean())
            row.update(layer_pieces=int(lay.piece.nunique()), layer_var=float(lay.layer_var.mean()),
                       layer_over_observed=float(lay.layer_var.mean()) / obs_l,
                       layer_terms=";".join(sorted(set(lay.layer_terms))))
        rows.append(row)
    return pd.DataFrame(rows)


def reference_profile_source(models: pd.DataFrame, fs: float) -> dict:
    """The reference models as the ``fitted['adis16405']`` entry of
    :func:`accelcal_repro.discrepancy.profiles.build_profiles` (rescaled to the session's white noise)."""
    return {"models": chosen_models(models), "fs": fs, "white_match": True,
            "description": "ADIS16405 2.78 h static record, library model chosen by BIC on tau >= 1 s"}


__all__ = ["AXES", "LONG_TAU_TERMS", "chosen_models", "fit_long_tau", "noise_of", "reference_allan",
           "reference_profile_source", "session_check", "session_check_summary", "session_layout"]
