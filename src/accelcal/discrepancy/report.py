"""One recording through both layers: the report of ``accelcal discrepancy`` and of the workflow.

:func:`analyse` detects the static poses (as ``accelcal calibrate`` does), runs the
deterministic layer (:func:`accelcal.discrepancy.detect.discrepancy`) on the pose means
and the stochastic layer (:func:`accelcal.discrepancy.stochastic.stochastic_layer`) on
the same rests, and then joins them: what the named noise terms imply for the pose
residuals (:func:`noise_implication`).

The join.  The stochastic layer gives, per pose and axis, the expected variance of the
pose-mean error about the session's common mean under the white-only model and under the
final noise model.  The extra variance of the named terms reaches the scalar residual of
pose i as ``Σ_k w_ik² Δv_ik`` with ``w_i = ∂r_i/∂z_i`` (the same projection that turns
the per-pose standard errors into ``σ_i``).  Adding it to ``σ_i²`` gives the residual
scatter the deterministic layer should expect if the noise model is complete; the χ² of
the final residuals against it says whether the named noise terms account for the
excess the white-noise model leaves.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import stats

from ..errors import AccelcalError
from ..recording import Recording
from ..static import StaticPoses, detect_static_recording
from .detect import DiscrepancyResult, Rules, discrepancy
from .fit import pose_data_from_static


@dataclass(frozen=True)
class StochasticSettings:
    """Settings of the stochastic layer (config ``discrepancy.stochastic``)."""

    seed: int = 20240708
    alpha: float = 0.05
    max_terms: int = 3
    candidates: tuple[str, ...] = ("quantization", "bias_instability", "random_walk", "drift_ramp", "gauss_markov")
    n_boot: int = 199
    n_resim: int = 16

    @classmethod
    def from_config(cls, cfg: dict) -> StochasticSettings:
        return cls(**{k: (tuple(v) if k == "candidates" else v) for k, v in cfg.items()})


#: What ``accelcal discrepancy`` uses (config/config.yaml's ``discrepancy`` section holds the
#: same values; tests/test_discrepancy_cli.py checks that they agree).
DEFAULT_STOCHASTIC = StochasticSettings()


@dataclass(frozen=True)
class Analysis:
    """Both layers on one recording."""

    poses: StaticPoses
    deterministic: DiscrepancyResult
    stochastic: object | None
    stochastic_error: str
    implication: dict
    fs: float

    def to_dict(self) -> dict:
        d = self.deterministic.to_dict()
        d["stochastic"] = self.stochastic.to_dict() if self.stochastic is not None else None
        if self.stochastic is None:
            d["stochastic_error"] = self.stochastic_error
        d["noise_implication"] = self.implication
        d["poses"].update({"t_start": self.poses.t_start.tolist(), "t_end": self.poses.t_end.tolist(),
                           "mean": self.poses.means.tolist(), "mean_std": self.poses.mean_std.tolist(),
                           "n_samples": self.poses.n_samples.tolist()})
        return d


def noise_implication(det: DiscrepancyResult, stoch, alpha: float) -> dict:
    """What the named noise terms mean for the pose residuals of the final deterministic model.

    Returns
    -------
    dict
        ``named_terms`` per axis; ``expected_excess`` = ``sqrt(mean((σ_i² + extra_i)/σ_i²))``
        (1 with white noise only); ``observed_excess`` (of the final deterministic
        model); ``chi2``, ``dof`` and the two-sided ``p_value`` of the final residuals
        against ``σ_i² + extra_i`` (a noise model that predicts far more scatter than the
        residuals show does not explain them either); ``verdict``; ``gap_with_noise_terms``
        = ``sqrt(χ²/n)`` on that yardstick; ``explains_excess`` = p-value ≥ α;
        ``extra_residual_std`` per pose (unit of g).
    """
    if stoch is None:
        return {}
    f = det.final
    w = -(f.J[:, :3] * f.sigma[:, None])  # ∂r/∂z = -∂r/∂b (unweighted)
    v_white = np.column_stack([a.pose_residual_implication["pose_mean_var_white"] for a in stoch.axes])
    v_model = np.column_stack([a.pose_residual_implication["pose_mean_var_model"] for a in stoch.axes])
    if v_white.shape != w.shape:
        raise AccelcalError(f"stochastic layer has {v_white.shape[0]} rests, deterministic layer {w.shape[0]} poses")
    extra = np.sum(w * w * np.clip(v_model - v_white, 0, None), axis=1)
    s2 = f.sigma ** 2 + extra
    chi2 = float(np.sum(f.residuals ** 2 / s2))
    if f.dof > 0:
        upper = float(stats.chi2.sf(chi2, f.dof))
        p = min(1.0, 2 * min(upper, 1 - upper))
        verdict = "consistent" if p >= alpha else ("residuals exceed it" if upper < 0.5 else "it over-predicts")
    else:
        p, verdict = float("nan"), "no degrees of freedom"
    return {
        "named_terms": {a.axis: list(a.named) if a.named else ["none"] for a in stoch.axes},
        "expected_excess": float(np.sqrt(np.mean(s2 / f.sigma ** 2))),
        "observed_excess": float(np.sqrt(f.chi2 / f.dof)) if f.dof > 0 else float("nan"),
        "chi2": chi2, "dof": int(f.dof), "p_value": p,
        "gap_with_noise_terms": float(np.sqrt(chi2 / f.n)),
        "verdict": verdict,
        "explains_excess": bool(np.isfinite(p) and p >= alpha),
        "extra_residual_std": np.sqrt(extra).tolist(),
    }


def analyse(rec: Recording, g: float, *, rules: Rules | None = None,
            stochastic: StochasticSettings | None = DEFAULT_STOCHASTIC, unit: str = "u",
            static_kw: dict | None = None) -> Analysis:
    """Both layers on one recording (``stochastic=None`` skips the stochastic layer).

    Raises
    ------
    AccelcalError
        From the static detection or the deterministic layer (too few poses, no rest...).
        A recording whose rests are too short for the stochastic layer is not an error:
        the report says why that layer is missing.
    """
    from .stochastic import rest_segments, stochastic_layer

    poses = detect_static_recording(rec, **(static_kw or {}))
    det = discrepancy(pose_data_from_static(poses, g), rules or Rules())
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
            impl = noise_implication(det, stoch, (rules or Rules()).alpha)
    else:
        err = "not run"
    return Analysis(poses, det, stoch, err, impl, rec.rate)


__all__ = ["DEFAULT_STOCHASTIC", "Analysis", "StochasticSettings", "analyse", "noise_implication"]
