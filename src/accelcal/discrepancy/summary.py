"""The text the discrepancy results render of themselves: the deterministic layer's
(:meth:`DiscrepancyResult.summary <accelcal.discrepancy.results.DiscrepancyResult.summary>`)
and the whole report's (:meth:`DiscrepancyReport.summary
<accelcal.discrepancy.results.DiscrepancyReport.summary>`), what ``accelcal discrepancy``
prints and the workflow logs.

Built from the result objects, not from their JSON: non-finite numbers print as ``inf``
or ``nan`` (the JSON holds None for both), and an interval end the profile likelihood
leaves open prints as ``inf``.
"""

from __future__ import annotations

from ..jsonsafe import is_finite
from .wander_model import describe_noise_model


def result_lines(det, unit: str | None = None) -> list[str]:
    """The deterministic layer: effects named, gaps, what was not identifiable, outlier poses,
    the noise between poses of the wander null in words, the two readings of the excess,
    and the fits that failed (``unit``: of the data, for the noise term's sizes)."""
    s = det.statistics()
    then = f" (then {', '.join(det.effects[1:])})" if len(det.effects) > 1 else ""
    lines = [f"discrepancy: {s['n_poses']} poses; effect named: {det.effect}{then}",
             f"  gap (RMS residual / noise) {det.gap_before:.3g} -> {det.gap_after:.3g} "
             f"(noise alone: {s['gap_expected_after']:.3g}); excess {s['excess_before']:.3g} -> "
             f"{s['excess_after']:.3g}"]
    if det.not_identifiable:
        lines.append(f"  not identifiable with these poses: {', '.join(det.not_identifiable)}")
    for o in det.outliers:
        lines.append(f"  outlier pose {o.pose} at t = {o.t:.1f} s: shifted {o.shift_sigma:+.3g} sigma "
                     f"(p = {o.p:.3g}); gap {o.gap_before:.3g} -> {o.gap_after:.3g} without it")
    if det.rules.null == "wander":
        lines += _noise_lines(det.noise_model or {}, det.wander_summary or {}, unit)
    by = s.get("excess_explained_by") or []
    lines.append(f"  excess: {s['excess_status']} with the named effects and noise terms"
                 + (f" ({', '.join(by)})" if by else "")
                 + f"; {s['excess_status_white']} against the rests' white noise alone")
    lines += [f"  did not converge: {e}" for e in det.errors]
    return lines


def _noise_lines(nm: dict, wander: dict, unit: str | None) -> list[str]:
    """The noise between poses estimated jointly with the calibration (wander null), in
    words, and the residual excess it predicts."""
    lines = []
    if nm:
        lines.append(f"  noise between poses: {describe_noise_model(nm, unit)}")
    if is_finite(wander.get("excess_predicted")):
        lo, hi = wander["excess_predicted_interval"]
        lines.append(f"  residual excess observed {wander['excess_observed']:.3g}, predicted by the noise model "
                     f"{wander['excess_predicted']:.3g} (95 % interval {lo:.3g}-{hi:.3g})")
    return lines


def report_summary(report, written_to=None) -> str:
    """The lines of :meth:`DiscrepancyReport.summary <accelcal.discrepancy.results.DiscrepancyReport.summary>`."""
    lines = result_lines(report.deterministic, report.unit)
    st = report.stochastic
    if st is not None:
        named = {a.axis: a.named or ("none",) for a in st.axes}
        lines.append("  noise terms named: " + "; ".join(f"{ax}: {', '.join(v)}" for ax, v in named.items()))
        imp = report.implication
        if imp:
            lines.append(f"  residual excess expected from the noise model {imp['expected_excess']:.3g}, "
                         f"observed {imp['observed_excess']:.3g} "
                         f"(explained: {'yes' if imp['explains_excess'] else 'no'})")
    else:
        lines.append(f"  stochastic layer: {report.stochastic_error or 'not run'}")
    if report.gyro is not None:
        lines.append(report.gyro.summary())
    elif report.gyro_error.startswith("gyroscope not tested"):  # a gyro that could not be calibrated
        lines.append(f"gyroscope: {report.gyro_error}")
    if getattr(report, "mag", None) is not None:
        lines.append(report.mag.summary())
    elif getattr(report, "mag_error", "").startswith("magnetometer not tested"):
        lines.append(report.mag_error)
    if written_to is not None:
        lines.append(f"  written to {written_to}")
    return "\n".join(lines)


__all__ = ["report_summary", "result_lines"]
