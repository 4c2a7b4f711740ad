"""The text a calibration renders of itself (:meth:`Calibration.summary
<accelcal.calibration.base.Calibration.summary>`): what ``accelcal calibrate`` prints and
the workflow logs.

Everything comes from the calibration: its fit, quality and units, and the provenance
``calibrate_recording`` and the CLI record (the static detection's noise reference,
the reader's notes, where g came from), so that a calibration read back from its file
renders the same lines.  Two things only the caller knows are passed in: the length of
the initial rest (the detection's sample range, not kept in the file) and where the file
was written.
"""

from __future__ import annotations

import numpy as np

from ..registry import ESTIMATORS

#: ``provenance["g_source"]`` when g was not given and standard gravity was used.
STANDARD_GRAVITY_SOURCE = "standard gravity (no --g)"
#: Width of the parameter names' column.
_NAME_WIDTH = 26


def format_with_errors(values, errors) -> str:
    """``+v ± e`` for each value, separated by two spaces."""
    return "  ".join(f"{v:+.6g} ± {e:.2g}" for v, e in zip(values, errors))


def calibration_summary(cal, *, init_rest_s: float | None = None, written_to=None) -> str:
    """The lines of :meth:`Calibration.summary <accelcal.calibration.base.Calibration.summary>`."""
    static = cal.provenance.get("static") or {}
    lines = [_headline(cal, static.get("reference"), init_rest_s)]
    lines += [f"  read: {n}" for n in cal.provenance.get("notes") or () if n]
    if static.get("note"):
        lines.append(f"  {static['note']}")
    q = cal.quality
    if q is not None:
        lines += _quality_lines(q)
    lines += _parameter_lines(cal)
    if written_to is not None:
        lines.append(f"  written to {written_to}")
    if q is not None:
        lines += [f"warning: {w}" for w in q.warnings]
    return "\n".join(lines)


def _headline(cal, reference: str | None, init_rest_s: float | None) -> str:
    est = ESTIMATORS.get(cal.CAL_TYPE)
    name = est.cli_name if est else cal.CAL_TYPE
    where = {"initial_rest": "noise reference: initial rest"
                             + ("" if init_rest_s is None else f" (0-{init_rest_s:.1f} s)"),
             "quietest_stretch": "noise reference: the quietest 2 s (no initial rest)",
             "known_intervals": "known static intervals"}.get(reference)
    data = cal.units["data"] if cal.input_unit in (None, cal.unit) else \
        f"{cal.input_unit}, converted to {cal.unit} by the nominal sensitivity"
    g_note = f"g = {cal.g:g} m/s^2"
    if cal.provenance.get("g_source") == STANDARD_GRAVITY_SOURCE:
        g_note += " (standard gravity: pass --g for the local value)"
    poses = f"{cal.n_poses} poses" + (f" ({where})" if where else "")
    return f"{name}: {poses}; data in {data}; {g_note}"


def _quality_lines(q) -> list[str]:
    excess = f"{q.excess:.3g}x the pose noise (chi2/dof {q.chi2 / q.dof:.3g} on {q.dof} dof, p = {q.p_value:.2g})" \
        if q.dof > 0 else "not checkable (no degree of freedom)"
    return [f"  residual RMS {1e3 * q.residual_rms:.3g} mm/s^2 = {excess}; noise alone predicts "
            f"{1e3 * q.predicted_rms:.3g} mm/s^2 per pose",
            f"  poses: {q.distinct_orientations} distinct orientations, sphere coverage {100 * q.coverage:.0f}% "
            f"(within 30 deg)"]


def _parameter_lines(cal) -> list[str]:
    """The parameters with the ± from the pose noise (NaN where the calibration has none)."""
    nan = np.full(3, np.nan)
    se = cal.standard_errors_noise

    def row(name: str, values, errors) -> str:
        return f"  {name}".ljust(_NAME_WIDTH) + format_with_errors(values, errors)

    lines = [row(f"bias [{cal.units['data']}]", cal.bias, se.get("bias", nan))]
    if cal.model == "full":
        s = np.asarray(se.get("scale_factors", nan))
        if cal.unit == "counts":
            lines.append(row("gain [counts/(m/s^2)]", cal.gain, s))
        else:
            lines.append(row("scale [ppm]", cal.scale_factors * 1e6, s * 1e6))
        lines.append(row("nonorth [deg]", cal.nonorthogonality_deg, se.get("nonorthogonality_deg", nan)))
    q = cal.quality
    k = max(1.0, q.excess) if q is not None and np.isfinite(q.excess) else 1.0
    lines.append("  ±: standard errors from the pose noise measured at the rests"
                 + (f", x{k:.3g} for the excess" if k > 1 else ""))
    return lines


__all__ = ["STANDARD_GRAVITY_SOURCE", "calibration_summary", "format_with_errors"]
