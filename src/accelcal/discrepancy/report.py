"""One recording through both layers: the report of ``accelcal discrepancy`` and of the workflow.

:func:`discrepancy_report` detects the static poses (as ``accelcal calibrate`` does), runs the
deterministic layer (:func:`accelcal.discrepancy.detect.discrepancy`) on the pose means
and the stochastic layer (:func:`accelcal.discrepancy.stochastic.stochastic_layer`) on
the same rests, and then joins them: what the named noise terms imply for the pose
residuals (:func:`noise_implication`).

The join.  Each noise model of the stochastic layer implies, per pose and axis, the
variance of the pose-mean error about the session's common mean
(:func:`accelcal.discrepancy.stochastic.pose_difference_variance`): the white-only
simulator before, the simulator with the named terms after.  Their difference reaches the
scalar residual of pose i as ``Σ_k w_ik² Δv_ik`` with ``w_i = ∂r_i/∂z_i`` (the same
projection that turns the per-pose standard errors into ``σ_i``).  Adding it to ``σ_i²`` gives the residual
scatter the deterministic layer should expect if the noise model is complete; the χ² of
the final residuals against it says whether the named noise terms account for the
excess the white-noise model leaves.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import distributions as dist
from ..errors import AccelcalError
from ..noise.allan import avar_interval, pooled_edf
from ..noise.terms import model_avar
from ..recording import Recording
from ..registry import estimator
from ..static import StaticPoses
from ..static_auto import find_static_poses
from ..summary import Summary
from .detect import discrepancy
from .fit import pose_data_from_static
from .gyro_loop import gyro_layer
from .mag_loop import mag_layer
from .stochastic import StochasticResult
from .stochastic.implication import centred_pose_variance, pose_difference_variance
from .stochastic.layer import DEFAULT_CANDIDATES, rest_segments, stochastic_layer
from .wander_model import describe_noise_model
from .wander_process import process_in
from .summary import report_summary
from .results import DiscrepancyResult
from .rules import Rules


@dataclass(frozen=True)
class StochasticSettings:
    """Settings of the stochastic layer (config ``discrepancy.stochastic``)."""

    seed: int = 20240708
    alpha: float = 0.05
    max_terms: int = 3
    candidates: tuple[str, ...] = DEFAULT_CANDIDATES
    n_boot: int = 199
    n_resim: int = 16

    @classmethod
    def from_config(cls, cfg: dict) -> StochasticSettings:
        return cls(**{k: (tuple(v) if k == "candidates" else v) for k, v in cfg.items()})


#: What ``accelcal discrepancy`` uses (config/config.yaml's ``discrepancy`` section holds the
#: same values; tests/test_discrepancy_cli.py checks that they agree).
DEFAULT_STOCHASTIC = StochasticSettings()


@dataclass(frozen=True)
class DiscrepancyReport:
    """Both layers on one recording: what ``accelcal discrepancy`` reports (:meth:`to_dict`)."""

    poses: StaticPoses
    deterministic: DiscrepancyResult
    stochastic: StochasticResult | None
    stochastic_error: str
    implication: dict
    fs: float
    unit: str | None = None
    static: dict | None = None  #: the detection settings and the search's record (as calibrate's provenance)
    gyro: object = None  #: the gyro loop's GyroLoopResult, or None (``gyro_error`` says why)
    gyro_error: str = "not run"
    mag: object = None  #: the magnetometer loop's MagLoopResult, or None (``mag_error`` says why)
    mag_error: str = "not run"

    def to_dict(self) -> dict:
        d = self.deterministic.to_dict()
        d["noise_model"]["reading"] = describe_noise_model(d["noise_model"], self.unit)
        d["stochastic"] = self.stochastic.to_dict() if self.stochastic is not None else None
        if self.stochastic is None:
            d["stochastic_error"] = self.stochastic_error
        d["noise_implication"] = self.implication
        if self.static is not None:
            d["static"] = self.static
        # one report for the whole IMU: the accelerometer's keys at the top (as before), each sensor below
        d["gyroscope"] = self.gyro.to_dict() if self.gyro is not None else {"outcome": "not_tested",
                                                                            "reason": self.gyro_error}
        d["magnetometer"] = self.mag.to_dict() if self.mag is not None else {"outcome": "not_tested",
                                                                             "reason": self.mag_error}
        d["poses"].update({"t_start": self.poses.t_start.tolist(), "t_end": self.poses.t_end.tolist(),
                           "mean": self.poses.means.tolist(), "mean_std": self.poses.mean_std.tolist(),
                           "n_samples": self.poses.n_samples.tolist()})
        return d

    def summary(self, *, written_to=None) -> Summary:
        """Both layers in a few lines: what ``accelcal discrepancy`` prints.

        The deterministic layer's lines (:meth:`DiscrepancyResult.summary
        <accelcal.discrepancy.results.DiscrepancyResult.summary>`), the noise terms
        named from the rests and what they imply for the pose residuals.

        Parameters
        ----------
        written_to : path, optional
            Where the report was written (a line says so).

        Returns
        -------
        Summary
            Lines without a final newline (a ``str``; also as a dict and HTML).
        """
        return Summary(report_summary(self, written_to))


def _pose_mean_variance(model: dict, starts, durations) -> np.ndarray:
    """Expected variance of each pose-mean error about the session's common mean under a
    noise model ``{term: value}`` (:func:`accelcal.discrepancy.stochastic.pose_difference_variance`)."""
    return sum(centred_pose_variance(pose_difference_variance(k, v, starts, durations)) for k, v in model.items())


def _extra_variance(stoch, w: np.ndarray, starts, durations) -> tuple[np.ndarray, np.ndarray]:
    """Additional variance of each pose's residual (gradient rows ``w``) under the rests' named
    terms over their white-only fit: extrapolated over the session, and short-term (each pose
    mean carrying only the extra Allan variance at its own duration, no wander between poses:
    the named terms not extrapolated beyond the rests' τ range, ~10 s)."""
    dv = np.zeros_like(w)
    dshort = np.zeros_like(w)
    for k, a in enumerate(stoch.axes):
        before = {t: v["value"] for t, v in a.fit_before.items()}
        dv[:, k] = _pose_mean_variance(a.model_after, starts, durations) - _pose_mean_variance(before, starts, durations)
        dshort[:, k] = model_avar(a.model_after, durations, stoch.fs) - model_avar(before, durations, stoch.fs)
    return np.sum(w * w * np.clip(dv, 0, None), axis=1), np.sum(w * w * np.clip(dshort, 0, None), axis=1)


def _two_sided(upper: float | None, alpha: float) -> tuple[float, str]:
    """Two-sided p-value from the upper tail ``upper`` of the observed χ² and its verdict
    (``None``: no degrees of freedom)."""
    if upper is None:
        return float("nan"), "no degrees of freedom"
    p = min(1.0, 2 * min(upper, 1 - upper))
    return p, "consistent" if p >= alpha else ("residuals exceed it" if upper < 0.5 else "it over-predicts")


def rests_implication(det: DiscrepancyResult, stoch, starts, durations, alpha: float) -> dict:
    """What the noise terms named from the rests mean for the pose residuals of the final model
    (the terms extrapolated from the rests' τ range to the whole session).

    The simulator's noise model before is the white-only fit of each axis, after it is the
    fit with the named terms; ``extra_i = Σ_k w_ik² (v_after,ik - v_before,ik)`` is the
    additional variance of pose i's residual (``v`` the centred pose-mean variances of the
    model, ``w_i = ∂r_i/∂z_i``).  Comparing after with the white-only *fit*, not with the
    white term inside the final fit, avoids counting short-τ noise twice when the final
    fit moves it from ``white`` into another term.

    Parameters
    ----------
    det : DiscrepancyResult
    stoch : StochasticResult
        Its rests must be the poses of ``det`` (same order).
    starts, durations : array_like
        Start and duration [s] of each pose.
    alpha : float

    Returns
    -------
    dict
        ``named_terms`` per axis; ``expected_excess`` = ``sqrt(mean((σ_i² + extra_i)/σ_i²))``
        (1 without named terms); ``observed_excess`` (of the final deterministic model);
        ``expected_excess_short_term``: the same with each pose mean carrying only the
        extra Allan variance at its own duration (no wander between poses: the named
        terms not extrapolated beyond the rests' τ range);
        ``chi2``, ``dof`` and the two-sided ``p_value`` of the final residuals against
        ``σ_i² + extra_i`` (a noise model that predicts far more scatter than the
        residuals show does not explain them either); ``verdict``; ``gap_with_noise_terms``
        = ``sqrt(χ²/n)`` on that yardstick; ``explains_excess`` = p-value ≥ α;
        ``extra_residual_std`` per pose (unit of g).
    """
    if stoch is None:
        return {}
    f = det.final
    if det.final_data is not None and len(det.final_data) != len(starts):  # outlier poses left the fit
        keep = det.final_data.pose_index
        starts, durations = np.asarray(starts)[keep], np.asarray(durations)[keep]
    w = -(f.J[:, :3] * f.sigma[:, None])  # ∂r/∂z = -∂r/∂b (unweighted)
    if len(starts) != w.shape[0] or len(stoch.axes) != 3:
        raise AccelcalError(f"stochastic layer and deterministic layer disagree on the poses ({len(starts)} "
                            f"rests, {w.shape[0]} poses, {len(stoch.axes)} axes)")
    extra, extra_short = _extra_variance(stoch, w, starts, durations)
    s2 = f.sigma ** 2 + extra
    chi2 = float(np.sum(f.residuals ** 2 / s2))
    p, verdict = _two_sided(float(dist.chi2_sf(chi2, f.dof)) if f.dof > 0 else None, alpha)
    return {
        "named_terms": {a.axis: list(a.named) if a.named else ["none"] for a in stoch.axes},
        "expected_excess": float(np.sqrt(np.mean(s2 / f.sigma ** 2))),
        "expected_excess_short_term": float(np.sqrt(np.mean(1 + extra_short / f.sigma ** 2))),
        "observed_excess": float(np.sqrt(f.chi2 / f.dof)) if f.dof > 0 else float("nan"),
        "chi2": chi2, "dof": int(f.dof), "p_value": p,
        "gap_with_noise_terms": float(np.sqrt(chi2 / f.n)),
        "verdict": verdict,
        "explains_excess": bool(np.isfinite(p) and p >= alpha),
        "extra_residual_std": np.sqrt(extra).tolist(),
    }


def noise_implication(det: DiscrepancyResult, stoch, starts, durations, alpha: float) -> dict:
    """Does the named noise model predict the pose residuals' excess over white noise?

    Under the wander null the named noise model is the rests' white per-pose noise plus the
    bias wander estimated jointly with the calibration (``det.noise_model``): the weighted
    χ² of the final least-squares residuals is then distributed as ``Σ μ_k χ²₁``
    (:func:`accelcal.discrepancy.wander.excess_distribution`); the verdict is
    ``consistent`` when the observed χ² lies in its central ``1 − α`` interval (two-sided
    p ≥ α, gamma approximation with the exact mean and variance).  That check uses the
    same residuals the wander was fitted to, so it says that a wander of this family *can*
    account for the excess; ``allan_check`` is the independent one: what the wander implies
    for the Allan deviation of the rests, compared with the measured one where the wander
    should be visible.  ``rests_only`` keeps the reading of the terms named from the rests
    alone (:func:`rests_implication`).  Under the white null, the rests-only reading is
    the implication (as before the wander null existed).

    Returns
    -------
    dict
        ``named_terms``, ``expected_excess``, ``expected_excess_interval``,
        ``expected_excess_short_term``, ``observed_excess``, ``chi2``, ``dof``, ``p_value``,
        ``gap_with_noise_terms``, ``verdict``, ``explains_excess``, ``extra_residual_std``,
        ``model``, ``allan_check``, ``rests_only``.
    """
    rests = rests_implication(det, stoch, starts, durations, alpha) if stoch is not None else {}
    nm = det.noise_model or {}
    if det.rules.null != "wander" or not nm.get("estimated") or not det.wander_summary:
        return rests
    c = det.wander_summary
    f = det.final
    dof = int(c["dof"])
    chi2 = float(np.sum(f.weighted ** 2))
    mean, var = c["chi2_mean"], c["chi2_var"]
    upper = float(dist.gamma_sf(chi2, mean ** 2 / var, scale=var / mean)) if dof > 0 and var > 0 else None
    p, verdict = _two_sided(upper, alpha)
    term = nm.get("term", "none")
    named = {a: [term] for a in "xyz"}
    out = {
        "model": "white per-pose noise (rests) + bias wander (REML, jointly with the calibration)",
        "named_terms": named,
        "expected_excess": c["excess_predicted"],
        "expected_excess_interval": c["excess_predicted_interval"],
        "expected_excess_short_term": rests.get("expected_excess_short_term", float("nan")),
        "observed_excess": c["excess_observed"],
        "chi2": chi2, "dof": dof, "p_value": p,
        "gap_with_noise_terms": c["gap_wander_after"],
        "verdict": verdict,
        "explains_excess": bool(np.isfinite(p) and p >= alpha),
        # beyond the rests' pose noise: the white scale's share and the wander's (or offset's)
        "extra_residual_std": np.sqrt(np.clip(np.square(c["noise_residual_std"])
                                              - np.square(det.data.sigma), 0.0, None)).tolist(),
        "white_scale": nm.get("white_scale"),
        "allan_check": allan_check(nm, stoch) if stoch is not None else {"verdict": "no rests analysed"},
        "rests_only": rests,
    }
    return out


def allan_check(noise_model: dict, stoch, level: float = 0.95, min_share: float = 0.1) -> dict:
    """What the jointly estimated wander implies for the Allan deviation of the rests.

    At averaging times ``τ_A`` much shorter than its correlation time the wander adds
    ``K² τ_A / 3`` to the Allan variance (its short-lag random-walk part, ``K² = 2 s²/τ``;
    the exact Gauss–Markov Allan variance is used).  Per axis, the prediction white (the
    rests' white-only fit) + wander, with the band of the wander's 95 % interval of ``K``,
    is compared with the measured Allan deviation and its ``level`` interval (χ² with the
    Satterthwaite mix of the white- and random-walk-FM edf), at the ``τ_A`` where the
    wander is at least ``min_share`` of the predicted Allan variance (where both layers see
    the same time scales), Bonferroni over those ``τ_A``.  The check is one-sided: the
    wander is *contradicted* on an axis when the rests show less Allan variance than white +
    the lower end of the band at some compared ``τ_A`` (``rests show less``); the rests
    showing more is not a contradiction (short-term noise such as a vibration the rests
    carry in their own standard errors), it is reported as ``more_at``.  ``consistent``
    otherwise; ``not visible in the rests`` when the wander is below ``min_share`` at every
    ``τ_A`` the rests reach.
    """
    found = process_in(noise_model).rest_allan(noise_model)
    if isinstance(found, dict):  # nothing the rests can show
        return found
    K, K_ci, avar = found
    fs = stoch.fs

    def wander_avar(taus, k):
        return avar(taus, k, fs)

    band = (K_ci[0] if np.isfinite(K_ci[0]) else 0.0, K_ci[1] if np.isfinite(K_ci[1]) else np.inf)
    axes = {a.axis: _axis_allan_check(a, stoch, wander_avar, K, band, level, min_share) for a in stoch.axes}
    verdicts = [c["verdict"] for c in axes.values()]
    verdict = verdicts[0] if len(set(verdicts)) == 1 else "; ".join(f"{ax}: {c['verdict']}" for ax, c in axes.items())
    return {"axes": axes, "min_share": min_share, "level": level, "verdict": verdict}


def _axis_allan_check(a, stoch, wander_avar, K: float, band: tuple, level: float, min_share: float) -> dict:
    """:func:`allan_check` on one axis: the measured Allan variance against white + wander
    (``wander_avar(taus, K)``, its band from the ends of ``K``'s interval) where the wander
    is at least ``min_share`` of the prediction."""
    taus = np.asarray(a.taus, float)
    white = a.fit_before["white"]["value"] ** 2 / taus
    wv = wander_avar(taus, K)
    lo_w, hi_w = (wander_avar(taus, k) for k in band)
    share = wv / (white + wv)
    seen = share >= min_share
    m = np.round(taus * stoch.fs).astype(int)
    nu_w, nu_r = pooled_edf(stoch.segment_lengths, m, 0), pooled_edf(stoch.segment_lengths, m, -2)
    nu = (white + wv) ** 2 / (white ** 2 / np.maximum(nu_w, 1e-9) + wv ** 2 / np.maximum(nu_r, 1e-9))
    k = max(int(seen.sum()), 1)
    meas = np.asarray(a.adev_measured, float) ** 2
    lo, hi = avar_interval(meas[:, None], nu[:, None], 1 - (1 - level) / k)
    lo, hi = lo[:, 0], hi[:, 0]
    pred_lo, pred_hi = white + lo_w, white + hi_w
    less = seen & (pred_lo > hi)
    more = seen & (pred_hi < lo)
    if not seen.any():
        v = "not visible in the rests"
    elif less.any():
        v = "rests show less"
    else:
        v = "consistent"
    return {
        "verdict": v, "taus": taus.tolist(), "adev_measured": np.sqrt(meas).tolist(),
        "adev_interval": np.sqrt(np.column_stack([lo, hi])).tolist(),
        "adev_white": np.sqrt(white).tolist(), "adev_predicted": np.sqrt(white + wv).tolist(),
        "adev_predicted_band": np.sqrt(np.column_stack([pred_lo, pred_hi])).tolist(),
        "wander_share": share.tolist(), "compared": seen.tolist(),
        "less_at": taus[less].tolist(), "more_at": taus[more].tolist(),
    }


def discrepancy_report(rec: Recording, g: float, *, rules: Rules | None = None,
                       stochastic: StochasticSettings | None = DEFAULT_STOCHASTIC, unit: str = "u",
                       static_kw: dict | None = None, search: bool = False,
                       min_poses: int = 0, gyro: bool = True, mag: bool = True) -> DiscrepancyReport:
    """The discrepancy report of a recording: static poses, both layers and their join.

    Finds the static poses as ``accelcal calibrate`` does (one code path,
    :func:`accelcal.static_auto.find_static_poses`: the settings ``static_kw``, and with
    ``search`` the candidates' best when they give fewer poses than the full model needs,
    or ``min_poses`` if more), runs the deterministic layer on their means and the
    stochastic layer on the same rests (``stochastic=None`` skips it), and joins them
    (:func:`noise_implication`); the gyro's loop (``gyro``) and the magnetometer's
    (``mag``, :func:`accelcal.discrepancy.mag_loop.mag_layer`) when the recording has them.

    Raises
    ------
    AccelcalError
        From the static detection or the deterministic layer (too few poses, no rest...).
        A recording whose rests are too short for the stochastic layer is not an error:
        the report says why that layer is missing.
    """
    need = max(estimator("full_lls").min_poses, min_poses) if search else 0
    poses, searched = find_static_poses(rec, g, static_kw, need)
    static = {**(static_kw or {}), "known_intervals": rec.intervals is not None}
    if searched is not None:
        static.update({**searched["settings"], "search": searched})
    det = discrepancy(pose_data_from_static(poses, g, rec.acc, rec.rate), rules or Rules())
    stoch, err, impl = None, "", {}
    if stochastic is not None:
        try:
            stoch = stochastic_layer(rest_segments(rec.acc, poses.intervals), rec.rate, seed=stochastic.seed,
                                     alpha=stochastic.alpha, max_terms=stochastic.max_terms,
                                     candidates=stochastic.candidates, intervals=poses.intervals,
                                     n_boot=stochastic.n_boot, n_resim=stochastic.n_resim, unit=unit)
        except AccelcalError as e:
            err = str(e).splitlines()[0]
        else:
            iv = poses.intervals
            impl = noise_implication(det, stoch, iv[:, 0] / rec.rate, (iv[:, 1] - iv[:, 0]) / rec.rate,
                                     (rules or Rules()).alpha)
    else:
        err = "not run"
    gyro_result, gyro_err = (gyro_layer(rec, g, poses, alpha=(rules or Rules()).alpha) if gyro and rec.gyro is not None
                             else (None, "no gyro in the recording" if rec.gyro is None else "gyro left out (--no-gyro)"))
    mag_result, mag_err = (mag_layer(rec, poses, alpha=(rules or Rules()).alpha) if mag and rec.mag is not None
                           else (None, "no magnetometer in the recording" if rec.mag is None else
                                 "magnetometer left out (--no-mag)"))
    return DiscrepancyReport(poses, det, stoch, err, impl, rec.rate, unit, static, gyro_result, gyro_err or "",
                             mag_result, mag_err or "")


__all__ = ["DEFAULT_STOCHASTIC", "DiscrepancyReport", "StochasticSettings", "allan_check", "discrepancy_report",
           "noise_implication", "rests_implication"]
