"""The rows and the results of the discrepancy loop: :class:`Candidate`, the outlier family's
:class:`OutlierTest` and :class:`OutlierPose`, :class:`DiscrepancyResult` (the deterministic
layer) with its JSON, and :class:`DiscrepancyReport` (both layers and the sensors' loops on one
recording, what :func:`accelcal.discrepancy.report.discrepancy_report` returns)."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np

from .. import distributions as dist
from ..effects import EFFECTS
from ..static import StaticPoses
from ..summary import Summary
from .fit import Fit, PoseData, evaluate, parameter_names
from .identifiability import Identifiability
from .rules import Rules
from .schema import white_excess_status
from .statistics import gap
from .stochastic import StochasticResult
from .summary import report_summary, result_lines
from .wander_model import describe_noise_model
from .wander_process import process_in

@dataclass(frozen=True)
class Candidate:
    """One candidate in one round: identifiability, nested test, ΔBIC, LOPO, estimate."""

    round: int
    effect: str
    identifiable: bool
    reasons: tuple[str, ...]
    absorbed: float
    absorbed_axis: list
    mde: list
    mde_data: list
    statistic: float = float("nan")
    dof: tuple = (3, 0)
    p_value: float = float("nan")
    p_adjusted: float = float("nan")
    delta_bic: float = float("nan")
    lopo_gap_current: float = float("nan")
    lopo_gap: float = float("nan")
    estimate: list = field(default_factory=lambda: [float("nan")] * 3)
    se: list = field(default_factory=lambda: [float("nan")] * 3)
    se_noise: list = field(default_factory=lambda: [float("nan")] * 3)
    passed_test: bool = False
    passed_bic: bool = False
    passed_lopo: bool = False
    named: bool = False
    test: str = "F-test, common scale (white null)"
    mde_white: list = field(default_factory=lambda: [float("nan")] * 3)
    wander_inflation: float = float("nan")
    confounded_with_wander: bool = False
    wander_alt: dict = field(default_factory=dict)
    ambiguous_with: tuple = ()
    dominated: bool = False
    bartlett: float = float("nan")

    @classmethod
    def from_identifiability(cls, ident: Identifiability, rnd: int) -> Candidate:
        """The row of a candidate in round ``rnd`` before its test: its identifiability only."""
        nan = [float("nan")] * len(ident.mde)
        return cls(round=rnd, effect=ident.effect, identifiable=ident.identifiable, reasons=ident.reasons,
                   absorbed=ident.absorbed, absorbed_axis=ident.absorbed_axis.tolist(), mde=ident.mde.tolist(),
                   mde_data=ident.mde_data.tolist(), dof=(len(ident.mde), ident.dof), estimate=nan, se=nan,
                   se_noise=nan, mde_white=nan)

    @property
    def passed(self) -> bool:
        return self.identifiable and self.passed_test and self.passed_bic and self.passed_lopo

    def to_dict(self) -> dict:
        d = asdict(self)
        d["reasons"] = list(self.reasons)
        d["dof"] = list(self.dof)
        d["ambiguous_with"] = list(self.ambiguous_with)
        d["passed"] = self.passed
        d["parameters"] = list(EFFECTS[self.effect].parameters)
        d["unit"] = EFFECTS[self.effect].unit
        return d


@dataclass(frozen=True)
class OutlierTest:
    """The outlier family of one round (wander null): its most outlying pose and the test.

    ``pose`` is the pose's index in the recording, ``t`` its mid time [s]: the pose of the
    largest studentised residual, ``studentised`` (GLS, at the round's wander); ``p_value``
    the family's p-value against the exact null of that maximum (``draws`` Monte Carlo
    draws, :mod:`accelcal.discrepancy.wander.outliers`), ``p_adjusted`` after Holm over
    the round; ``statistic`` the pose's mean-shift likelihood ratio (the wander
    re-estimated), ``delta_bic`` = ``−LR + 2 ln n``.
    """

    round: int
    pose: int
    t: float
    statistic: float
    studentised: float
    p_value: float
    p_adjusted: float
    delta_bic: float
    passed_test: bool
    named: bool = False
    draws: int = 0

    def to_dict(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class OutlierPose:
    """A pose named an outlier: left out of the fit, its residual predicted by the others.

    ``shift``: its residual under the refit without it (unit of g), ``shift_sigma`` the
    same over the pose's noise; the test's ``statistic``, ``studentised``, ``p`` and
    ``p_adjusted`` (:class:`OutlierTest`); the gaps of the model before and after.
    """

    pose: int
    t: float
    shift: float
    shift_sigma: float
    statistic: float
    studentised: float
    p: float
    p_adjusted: float
    round: int
    gap_before: float
    gap_after: float

    def to_dict(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class DiscrepancyResult:
    """Outcome of the deterministic layer on one pose set.

    ``effect`` is the effect named in round 1 (or ``'none'``); ``outcome`` is the same,
    except ``'not_identifiable'`` when nothing was named and at least one applicable
    candidate was refused in round 1 (the recording cannot rule that effect out).
    """

    effects: tuple[str, ...]
    candidates: tuple[Candidate, ...]
    not_applicable: dict
    base: Fit
    final: Fit
    lopo_base: np.ndarray
    lopo_final: np.ndarray
    data: PoseData
    rules: Rules
    noise_model: dict = field(default_factory=dict)
    outliers: tuple[OutlierPose, ...] = ()
    outlier_tests: tuple[OutlierTest, ...] = ()
    errors: tuple = ()
    final_data: PoseData | None = None
    wander_summary: dict = field(default_factory=dict)

    @property
    def effect(self) -> str:
        return self.effects[0] if self.effects else "none"

    @property
    def not_identifiable(self) -> tuple[str, ...]:
        """Candidates refused in round 1 and, under the wander null, those the last round
        could not rule out against the wander (never one that was named)."""
        return tuple(self.not_identifiable_reasons)

    @property
    def not_identifiable_reasons(self) -> dict:
        out = {c.effect: list(c.reasons) for c in self.candidates if c.round == 1 and not c.identifiable}
        if self.candidates and self.rules.null == "wander":
            for c in self.candidates:
                if c.ambiguous_with and c.effect not in self.effects:
                    out.setdefault(c.effect, list(c.reasons))
            last = max(c.round for c in self.candidates)
            for c in self.candidates:
                if c.round == last and c.effect not in self.effects and c.effect not in out:
                    if not c.identifiable:
                        out[c.effect] = list(c.reasons)
                    elif c.confounded_with_wander:
                        w = self.noise_model
                        out[c.effect] = [f"cannot be told apart from the bias wander (tau {w.get('tau_s', float('nan')):.3g} s): "
                                         f"it makes the minimum detectable effect {c.wander_inflation:.3g} x larger than "
                                         "white noise of the same size would, and the test did not pass"]
        return out

    @property
    def outcome(self) -> str:
        if self.effects:
            return self.effects[0]
        if self.errors:
            return "error"
        return "not_identifiable" if self.not_identifiable else "none"

    @property
    def gap_before(self) -> float:
        return gap(self.base.weighted)

    @property
    def gap_after(self) -> float:
        return gap(self.final.weighted)

    def residual_after_all(self) -> np.ndarray:
        """Residuals of the final model on every pose (outlier poses predicted, not fitted)."""
        if self.final_data is None or len(self.final_data) == len(self.data):
            return self.final.residuals
        r, _, _ = evaluate(self.final.p, self.data, self.final.effects, jacobian=False)
        return np.full(len(self.data), np.nan) if r is None else r

    def summary(self, *, unit: str | None = None, written_to=None) -> Summary:
        """The deterministic layer in a few lines (:func:`~accelcal.discrepancy.summary.result_lines`; ``unit``: the data's)."""
        lines = result_lines(self, unit)
        return Summary(lines + ([f"written to {written_to}"] if written_to is not None else []))

    def statistics(self) -> dict:
        """The gaps and what noise alone predicts, before (base) and after (named effects)."""
        b, f = self.base, self.final
        chi0 = dist.chi2_sf(b.chi2, b.dof)  # NaN without degrees of freedom
        chi1 = dist.chi2_sf(f.chi2, f.dof)
        excess_var = b.chi2 - b.dof
        return {
            "n_poses": b.n,
            "gap_before": self.gap_before,
            "gap_after": self.gap_after,
            "gap_expected_before": float(np.sqrt(max(b.dof, 0) / b.n)),
            "gap_expected_after": float(np.sqrt(max(f.dof, 0) / f.n)),
            "gap_lopo_before": gap(self.lopo_base),
            "gap_lopo_after": gap(self.lopo_final),
            "excess_before": float(np.sqrt(b.chi2 / b.dof)) if b.dof > 0 else float("nan"),
            "excess_after": float(np.sqrt(f.chi2 / f.dof)) if f.dof > 0 else float("nan"),
            "chi2_before": b.chi2, "dof_before": b.dof, "chi2_p_before": float(chi0),
            "chi2_after": f.chi2, "dof_after": f.dof, "chi2_p_after": float(chi1),
            # share of the χ² in excess of its expectation that the named effects remove
            "excess_explained_fraction": float((b.chi2 - f.chi2) / excess_var) if excess_var > 0 else float("nan"),
            **self.excess_readings(chi0, chi1),
        }

    def excess_readings(self, p_before: float, p_after: float) -> dict:
        """``excess_status`` under the model the loop used, and ``excess_status_white``.

        Both start from the base model's residuals against the rests' white noise alone
        (``no excess`` at level α: nothing to explain).  ``excess_status_white`` then asks
        the same of the final residuals: the named effects alone must bring them to the
        rests' noise.  ``excess_status`` asks it of the model the loop used: under the
        wander null the named effects (and outlier poses) *with* the named noise terms
        (white scale, bias wander or per-placement offset: ``excess_explained``, the final
        χ² inside the central 95 % of its predicted distribution); under the white null the
        two are the same.  Values: :data:`accelcal.discrepancy.schema.STATUS`.
        """
        white = white_excess_status(p_before, p_after, self.rules.alpha)
        out = {"excess_status_white": white, "excess_status": white,
               "excess_status_model": "white per-pose noise of the rests"}
        if self.rules.null != "wander":
            return out
        nm = self.noise_model or {}
        if white in ("no excess", "untestable"):
            return out  # nothing to explain, or nothing to test it with: the same under any noise model
        if not nm.get("estimated") or not self.wander_summary or not self.wander_summary.get("dof", 0) > 0:
            return {**out, "excess_status": "untestable",
                    "excess_status_model": "the wander null's noise model was not estimated"}
        term = nm.get("term", "none")
        named = process_in(nm).named
        model = "white per-pose noise of the rests x white scale" + (f" + {term}" if named else "")
        status = "explained" if self.wander_summary.get("excess_explained") else "not explained"
        by = [e for e in self.effects if e != "outlier_pose"]
        if self.outliers:
            by.append(f"{len(self.outliers)} outlier pose(s) left out")
        if named:
            by.append(term)
        ws_lo = (nm.get("white_scale_ci") or [float("nan")])[0]
        if ws_lo is not None and np.isfinite(ws_lo) and ws_lo > 1:
            by.append(f"white scale {nm.get('white_scale', float('nan')):.3g}")
        return {**out, "excess_status": status, "excess_status_model": model,
                "excess_explained_by": by if status == "explained" else []}

    def to_dict(self) -> dict:
        def params(f: Fit):
            names = parameter_names(f.effects)
            se = f.standard_errors(scaled=True)
            sen = f.standard_errors(scaled=False)
            return {nm: {"value": float(v), "se": float(s), "se_noise": float(sn)}
                    for nm, v, s, sn in zip(names, f.p, se, sen)}

        d = {
            "effect": self.effect,
            "effects": list(self.effects),
            "outcome": self.outcome,
            "null": self.rules.null,
            "not_identifiable": list(self.not_identifiable),
            "not_identifiable_reasons": self.not_identifiable_reasons,
            "errors": list(self.errors),
            "noise_model": self.noise_model or _white_noise_model(self),
            "outliers": [o.to_dict() for o in self.outliers],
            "outlier_tests": [o.to_dict() for o in self.outlier_tests],
            **self.wander_summary,
            "not_applicable": dict(self.not_applicable),
            "candidates": [c.to_dict() for c in self.candidates],
            **self.statistics(),
            "rules": {**asdict(self.rules), "candidates": list(self.rules.candidates)},
            "model_before": {"effects": [], "parameters": params(self.base)},
            "model_after": {"effects": list(self.final.effects), "parameters": params(self.final)},
            "poses": {
                "t": self.data.t.tolist(),
                "temp": None if self.data.temp is None else self.data.temp.tolist(),
                "sigma": self.data.sigma.tolist(),
                "residual_before": self.base.residuals.tolist(),
                "residual_after": self.residual_after_all().tolist(),
                "excluded": [o.pose for o in self.outliers],
                "lopo_before": self.lopo_base.tolist(),
                "lopo_after": self.lopo_final.tolist(),
            },
        }
        return d


def _white_noise_model(res: DiscrepancyResult) -> dict:
    f = res.final
    return {"term": "none", "estimated": False, "process": "white per-pose noise times a common scale",
            "scale": float(np.sqrt(f.chi2 / f.dof)) if f.dof > 0 else float("nan"),
            "reason": "null 'white': the tests estimate a common scale of the per-pose noise; no bias wander"}


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


__all__ = ["Candidate", "DiscrepancyReport", "DiscrepancyResult", "OutlierPose", "OutlierTest"]
