"""Command line: ``accelcal calibrate``, ``accelcal apply``, ``accelcal discrepancy``.

Nothing numerical is imported at module level: ``accelcal --help`` must start at once.
Every failure the user can fix is one ``accelcal: error:`` line on stderr naming the
cause and the option that fixes it, exit status 2, and no output file; warnings about a
result that was written are ``warning:`` lines (a clean fit prints none).
"""

from __future__ import annotations

import argparse
import os
import sys
import threading
import time
from contextlib import contextmanager
from pathlib import Path

from . import __version__
from .effects import EFFECT_IDS, TIME, effect
from .errors import AccelcalError
from .formats.registry import FORMATS, formats_help
from .registry import ESTIMATORS, estimators

STANDARD_GRAVITY = 9.80665

MODEL_HELP = """\
model (Burkhard et al. 2024, eq. 1):  z = M x + b + e
  z  measured specific force of a static pose (mean of the rest interval)
  x  true specific force, |x| = g at rest
  b  bias;  M lower triangular, row i = (1 + s_i) u_i with scale factors s and
     non-orthogonality angles (theta_xy, theta_zx, theta_zy), see accelcal.model

methods:
{methods}

input: a table with time and three acceleration columns, e.g. a CSV with header
  t,ax,ay,az[,temp]; columns are found by their usual names (time, timestamp,
  acc_x, accX, AX, Accel. X, ...) or named with --columns t=...,ax=...,ay=...,az=...;
  comma, semicolon, tab or whitespace separated, decimal comma, # comments, gzip.
  temp      optional temperature column [degC]
{formats}
units: acceleration in m/s^2, g, mg or raw counts (from the header, --unit, or the
  data's magnitude); g and mg are converted to m/s^2. --g is the local gravity in
  m/s^2. For raw counts the full models' M carries the sensitivity (counts per
  m/s^2) and b is in counts; the bias-only models need physical units.
  Time in s, ms, us, ns or ISO 8601 date-times (from the header, --time-unit, or
  the values), or --rate HZ when there is none.
rests: the recording should start at rest (its noise sets the detection threshold,
  as in IMU-TK); if it does not, the quietest 2 s stretch is used, and said so.
  Known rests can be given with --intervals (imucal section list, CSV start,end).
"""

DISCREPANCY_HELP = """\
discrepancy report (JSON):
  effect       effect named in the first round, or 'none'
  effects      every effect named, in order (refit after each)
  outcome      effect, or 'not_identifiable' when nothing was named and a candidate
               could not be tested with these poses, or 'none'
  candidates   per candidate and round: identifiable (absorbed fraction, minimum
               detectable effect), F statistic, p_value (Holm-adjusted: p_adjusted),
               delta_bic, leave-one-pose-out gap, estimate and standard error
  gap_before, gap_after   RMS pose residual in units of its noise, base model and
               base + named effects (noise alone: gap_expected_*)
  stochastic   Allan deviation of the rests vs a white-noise simulator, named noise
               terms, Allan gap before/after; noise_implication: what they mean for
               the pose residuals
  The report is also a calibration: `accelcal apply REPORT.json RECORDING` applies
  its base model with the named effects.

"""

APPLY_HELP = """\
CALIBRATION is the JSON of `accelcal calibrate` or the report of `accelcal
discrepancy` (its base model plus the named effects, e.g. a temperature term).
RECORDING is read with the same readers and options as for calibrate, in the unit
the calibration was made from. The output CSV keeps the time column as it was and
writes the calibrated ax, ay, az in m/s^2 (and temp, if present).
"""


def _methods_help() -> str:
    return "\n".join(f"  {e.cli_name:<10} {e.description}, >= {e.min_poses} poses" for e in estimators("accelerometer"))


def main(argv: list[str] | None = None) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except AccelcalError as exc:
        return _fail(str(exc))
    except OSError as exc:
        return _fail(f"{exc.strerror or exc}: {exc.filename}" if getattr(exc, "filename", None) else str(exc))
    except KeyboardInterrupt:
        return _fail("interrupted", code=130)
    except Exception as exc:  # never a traceback for the user; ACCELCAL_DEBUG=1 shows it
        if os.environ.get("ACCELCAL_DEBUG"):
            raise
        return _fail(f"internal error ({type(exc).__name__}: {exc}); rerun with ACCELCAL_DEBUG=1 and report it", code=3)


def _fail(message: str, code: int = 2) -> int:
    print(f"accelcal: error: {message.splitlines()[0] if message else 'failed'}", file=sys.stderr)
    return code


def _warn(message: str) -> None:
    print(f"warning: {message}", file=sys.stderr)


# --------------------------------------------------------------------------- parser


def _positive(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not v > 0 or v != v or v == float("inf"):
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}")
    return v


def _gravity(text: str) -> float:
    v = _positive(text)
    if not 9.7 <= v <= 9.9:
        raise argparse.ArgumentTypeError(f"{text} is not a gravity magnitude in m/s^2 (9.78-9.83 on the Earth's "
                                         "surface; data in g are converted, pass --unit g)")
    return v


def _reader_options(p) -> None:
    r = p.add_argument_group("reading the recording")
    # the reader checks the name (one error line, as for every input), so no argparse choices
    names = ", ".join(["auto", *FORMATS])
    r.add_argument("--format", default="auto", metavar="FMT", help=f"file format ({names}; default auto)")
    r.add_argument("--columns", metavar="SPEC",
                   help="which column is which: t=NAME,ax=NAME,ay=NAME,az=NAME[,temp=NAME] (names or 1-based numbers)")
    r.add_argument("--unit", metavar="UNIT", help="acceleration unit: m/s2, g, mg or counts (overrides the header)")
    r.add_argument("--time-unit", metavar="UNIT", help="unit of the time column: s, ms, us or ns")
    r.add_argument("--rate", type=_positive, metavar="HZ", help="sampling rate: time from the sample index")
    r.add_argument("--intervals", type=Path, metavar="FILE",
                   help="known static intervals: imucal section list (JSON), JSON [[start, end], ...] in s, "
                        "or CSV with start,end columns (s, or start_index,end_index in samples)")


def _static_options(p) -> None:
    s = p.add_argument_group("static detection (ignored with known intervals)")
    s.add_argument("--init-rest", default="auto", metavar="auto|none|SECONDS",
                   help="noise reference: auto (the initial rest, or the quietest 2 s if the recording does not start "
                        "at rest), none (the quietest 2 s), or the initial rest's length in s (default auto)")
    s.add_argument("--window", type=_positive, metavar="S", help="moving-variance window [s] (default 1)")
    s.add_argument("--threshold", type=_positive, metavar="K",
                   help="static if the window variance is below K x the reference's (default 6)")
    s.add_argument("--min-duration", type=float, metavar="S", help="shortest pose kept [s] (default 1)")
    s.add_argument("--trim", type=float, metavar="S", help="cut from each end of a pose that borders motion [s] "
                                                           "(default 0.25)")


def _parser() -> argparse.ArgumentParser:
    epilog = MODEL_HELP.format(methods=_methods_help(), formats=formats_help())
    p = argparse.ArgumentParser(prog="accelcal", description="Accelerometer calibration from static poses.",
                                formatter_class=argparse.RawDescriptionHelpFormatter, epilog=epilog)
    p.add_argument("--version", action="version", version=f"accelcal {__version__}")
    sub = p.add_subparsers(dest="command", required=True)
    c = sub.add_parser("calibrate", help="estimate bias, scale factors and non-orthogonality from a recording",
                       description="Find the static poses of RECORDING, estimate the accelerometer errors and say "
                                   "whether the fit can be trusted (residuals against the noise measured at the rests).",
                       formatter_class=argparse.RawDescriptionHelpFormatter, epilog=epilog)
    c.add_argument("recording", type=Path, help="the recording (see 'input' below)")
    c.add_argument("--g", type=_gravity, default=None,
                   help=f"local gravity magnitude [m/s^2] (default {STANDARD_GRAVITY}, standard gravity)")
    c.add_argument("--method", choices=[e.cli_name for e in estimators("accelerometer")], default="full-lls",
                   help="estimator (default full-lls)")
    c.add_argument("--out", type=Path, required=True, help="calibration JSON (written only on success)")
    c.add_argument("--figures", type=Path, default=None, metavar="DIR",
                   help="also draw calibration_coverage (.png, .pdf): the pose directions on the sphere")
    _reader_options(c)
    n = c.add_argument_group("raw counts to m/s^2 before the fit (the bias-only models need it)")
    n.add_argument("--sensitivity", metavar="S[,S,S][/g|/m/s2]",
                   help="the data sheet's sensitivity, counts per g (default) or per m/s2; then M is the gain "
                        "relative to it and b is in m/s^2")
    n.add_argument("--zero", metavar="C[,C,C]", help="the output at zero specific force [counts] (default 0)")
    _static_options(c)
    c.set_defaults(func=_calibrate)

    a = sub.add_parser("apply", help="apply a calibration to a recording",
                       description="Apply CALIBRATION to RECORDING: calibrated specific force in m/s^2.",
                       formatter_class=argparse.RawDescriptionHelpFormatter, epilog=APPLY_HELP)
    a.add_argument("calibration", type=Path, help="calibration JSON (accelcal calibrate, or a discrepancy report)")
    a.add_argument("recording", type=Path, help="the recording to correct")
    a.add_argument("--out", type=Path, required=True, help="output CSV (written only on success)")
    a.add_argument("--no-effects", action="store_true", help="apply the base model only, not the fitted effects")
    _reader_options(a)
    a.set_defaults(func=_apply)

    d = sub.add_parser("discrepancy", help="find where the calibrated model and the recording disagree, name the "
                                           "missing effect and noise term",
                       description="Fit the model of Burkhard et al. (2024) to the static poses of RECORDING, "
                                   f"test a library of candidate effects ({', '.join(EFFECT_IDS)}) as nested "
                                   "extensions and name the one the residuals ask for "
                                   "(or 'none'); compare the Allan deviation of the rests with a white-noise "
                                   "simulator and name the missing noise term.",
                       formatter_class=argparse.RawDescriptionHelpFormatter, epilog=DISCREPANCY_HELP + epilog)
    d.add_argument("recording", type=Path, help="the recording (see 'input' below)")
    d.add_argument("--g", type=_gravity, required=True, help="local gravity magnitude [m/s^2] (e.g. 9.80665)")
    d.add_argument("--out", type=Path, required=True, help="report JSON (written only on success)")
    d.add_argument("--figures", type=Path, default=None, metavar="DIR",
                   help="also write discrepancy_residuals and discrepancy_allan (.png, .pdf) to DIR")
    _reader_options(d)
    _static_options(d)
    d.set_defaults(func=_discrepancy)
    _noise_parser(sub)
    return p


# --------------------------------------------------------------------------- shared steps


@contextmanager
def _step(what: str, after_s: float = 2.0):
    """Announce ``what`` on stderr only if it is still running after ``after_s`` seconds,
    so that quick runs print nothing but their summary (or their one-line error)."""
    timer = threading.Timer(after_s, lambda: print(f"accelcal: {what} ...", file=sys.stderr, flush=True))
    timer.daemon = True
    timer.start()
    try:
        yield
    finally:
        timer.cancel()


def _read(args):
    from .formats import read

    with _step(f"reading {args.recording}"):
        return read(args.recording, format=args.format, columns=args.columns, unit=args.unit,
                    time_unit=args.time_unit, rate=args.rate, intervals=args.intervals)


def _static_settings(args, rec) -> dict:
    """Keyword arguments of accelcal.static.detect_static from the options."""
    kw = {}
    init = str(args.init_rest).strip().lower()
    if init == "none":
        kw["noise_reference"] = "quietest"
    elif init != "auto":
        try:
            kw["init_duration"] = float(init)
        except ValueError:
            raise AccelcalError(f"--init-rest must be auto, none or a duration in s, got {args.init_rest!r}") from None
        if not kw["init_duration"] > 0:
            raise AccelcalError(f"--init-rest must be a positive duration in s, got {args.init_rest!r}")
        kw["noise_reference"] = "initial"
    for opt, key in (("window", "window"), ("threshold", "threshold_factor"), ("min_duration", "min_duration"),
                     ("trim", "trim")):
        v = getattr(args, opt)
        if v is not None:
            kw[key] = v
    if "threshold_factor" in kw and kw["threshold_factor"] <= 1:
        raise AccelcalError(f"--threshold must exceed 1 (a multiple of the reference variance), got {args.threshold}")
    for key in ("min_duration", "trim"):
        if key in kw and not kw[key] >= 0:
            raise AccelcalError(f"--{key.replace('_', '-')} must be >= 0, got {kw[key]}")
    return kw


def _nominal(args, rec):
    """The --sensitivity/--zero conversion of raw counts to m/s^2, or None."""
    if args.sensitivity is None:
        if args.zero is not None:
            raise AccelcalError("--zero needs --sensitivity (counts per g or per m/s2)")
        return None
    if rec.unit != "counts":
        raise AccelcalError(f"--sensitivity converts raw counts, but the data are read as {rec.unit} "
                            "(pass --unit counts if they are counts)")
    import numpy as np

    from .nominal import NominalConversion
    from .units import G0

    def triple(text, what):
        try:
            v = np.array([float(x) for x in text.split(",")])
        except ValueError:
            raise AccelcalError(f"{what} must be one or three numbers separated by commas, got {text!r}") from None
        if v.size not in (1, 3) or not np.all(np.isfinite(v)):
            raise AccelcalError(f"{what} must be one or three numbers separated by commas, got {text!r}")
        return np.broadcast_to(v, (3,)).astype(float)

    text, per = args.sensitivity, "g"
    if "/" in text:
        text, per = text.split("/", 1)
    per = per.strip().lower().replace("²", "2").replace("^", "")
    if per not in ("g", "m/s2"):
        raise AccelcalError(f"--sensitivity: counts per g or per m/s2, got per {per!r}")
    sens = triple(text, "--sensitivity")
    if not np.all(sens > 0):
        raise AccelcalError("--sensitivity must be positive")
    cpu = sens / G0 if per == "g" else sens
    zero = np.zeros(3) if args.zero is None else triple(args.zero, "--zero")
    return NominalConversion(zero, cpu, None, f"--sensitivity {args.sensitivity}" +
                             (f" --zero {args.zero}" if args.zero else ""))


def _rate_hint(rec) -> str:
    rate = rec.rate
    if 1.0 <= rate <= 20000.0:
        return ""
    return (f" (the sampling rate is {rate:.4g} Hz from the time column: if its unit is not what was assumed, "
            "pass --time-unit s|ms|us|ns)")


def _provenance(args, t0: float) -> dict:
    from .atomic import sha256_file

    return {"accelcal_version": __version__, "recording": str(args.recording),
            "recording_sha256": sha256_file(args.recording), "elapsed_s": time.perf_counter() - t0}


# --------------------------------------------------------------------------- calibrate


def _calibrate(args) -> int:
    from .calibration import calibrate_recording
    from .errors import RecordingError

    t0 = time.perf_counter()
    rec = _read(args)
    g = STANDARD_GRAVITY if args.g is None else args.g
    static = _static_settings(args, rec)
    method = args.method
    with _step(f"detecting static poses and estimating {method} from {rec.n} samples"):
        try:
            cal, poses = calibrate_recording(rec, g, method, static=static, conversion=_nominal(args, rec))
        except RecordingError as e:
            raise RecordingError(f"{e}{_rate_hint(rec)}") from None
    prov = {**_provenance(args, t0), "g_source": "--g" if args.g is not None else "standard gravity (no --g)"}
    cal = _with_provenance(cal, prov)
    figures = []
    if args.figures is not None:
        from .calibration_figures import coverage_figure

        with _step("drawing figures"):
            figures = [("calibration_coverage", coverage_figure(cal, title=args.recording.name))]
    cal.save(args.out)
    if figures:
        from .plotting import save_figure

        for name, fig in figures:
            save_figure(fig, Path(args.figures) / name)
    _summary(cal, poses, rec, args)
    for w in cal.quality.warnings:
        _warn(w)
    return 0


def _with_provenance(cal, extra: dict):
    from dataclasses import replace

    return replace(cal, provenance={**cal.provenance, **extra})


def _summary(cal, poses, rec, args) -> None:
    import numpy as np

    q = cal.quality
    est = ESTIMATORS[cal.CAL_TYPE]
    where = {"initial_rest": f"noise reference: initial rest (0-{rec.t[poses.init_rest[1] - 1] - rec.t[0]:.1f} s)",
             "quietest_stretch": "noise reference: the quietest 2 s (no initial rest)",
             "known_intervals": "known static intervals"}[poses.reference]
    g_note = f"g = {cal.g:g} m/s^2" + ("" if args.g is not None else " (standard gravity: pass --g for the local value)")
    data = cal.unit if cal.input_unit in (None, cal.unit) else \
        f"{cal.input_unit}, converted to {cal.unit} by the nominal sensitivity"
    lines = [f"{est.cli_name}: {cal.n_poses} poses ({where}); data in {data}; {g_note}"]
    lines += [f"  read: {n}" for n in rec.notes if n]
    if poses.reference_note:
        lines.append(f"  {poses.reference_note}")
    excess = f"{q.excess:.3g}x the pose noise (chi2/dof {q.chi2 / q.dof:.3g} on {q.dof} dof, p = {q.p_value:.2g})" \
        if q.dof > 0 else "not checkable (no degree of freedom)"
    lines.append(f"  residual RMS {1e3 * q.residual_rms:.3g} mm/s^2 = {excess}; noise alone predicts "
                 f"{1e3 * q.predicted_rms:.3g} mm/s^2 per pose")
    lines.append(f"  poses: {q.distinct_orientations} distinct orientations, sphere coverage {100 * q.coverage:.0f}% "
                 f"(within 30 deg)")
    se = cal.standard_errors_noise
    z = cal.unit
    lines.append(f"  bias [{z}]".ljust(26) + _fmt(cal.bias, se["bias"]))
    if cal.model == "full":
        if cal.unit == "counts":
            lines.append("  gain [counts/(m/s^2)]".ljust(26) + _fmt(cal.gain, se["scale_factors"]))
        else:
            lines.append("  scale [ppm]".ljust(26) + _fmt(cal.scale_factors * 1e6, se["scale_factors"] * 1e6))
        lines.append("  nonorth [deg]".ljust(26) + _fmt(cal.nonorthogonality_deg, se["nonorthogonality_deg"]))
    k = max(1.0, q.excess) if np.isfinite(q.excess) else 1.0
    lines.append(f"  ±: standard errors from the pose noise measured at the rests"
                 + (f", x{k:.3g} for the excess" if k > 1 else ""))
    lines.append(f"  written to {args.out}")
    print("\n".join(lines), file=sys.stderr)


def _fmt(values, errors) -> str:
    return "  ".join(f"{v:+.6g} ± {e:.2g}" for v, e in zip(values, errors))


# --------------------------------------------------------------------------- apply


def _apply(args) -> int:
    from dataclasses import replace

    from .atomic import sha256_file
    from .calibration import load_calibration

    cal = load_calibration(args.calibration)
    rec = _read(args)
    expected = cal.input_unit or cal.unit
    if expected is not None and rec.unit != ("counts" if expected == "counts" else "m/s^2"):
        raise AccelcalError(f"{args.recording} is read as {rec.unit} but {args.calibration} was made from "
                            f"{expected}: pass --unit {'counts' if expected == 'counts' else 'm/s2 (or g, mg)'}")
    effects = () if args.no_effects else cal.effects
    # a term in time runs on the calibration session's clock: it describes that session only
    drift = [e.id for e in effects if effect(e.id).covariate == TIME]
    if drift and cal.provenance.get("recording_sha256") != sha256_file(args.recording):
        _warn(f"the calibration's {', '.join(drift)} term describes the drift during its own session; it is not "
              "applied to another recording")
        effects = tuple(e for e in effects if e.id not in drift)
    cal = replace(cal, effects=effects)
    x = cal.apply(rec.acc, t=rec.t, temp=rec.temp, unit=rec.unit)
    _write_corrected(args.out, rec, x)
    names = ", ".join(e.id for e in effects) or "none"
    print(f"apply: {rec.n} samples of {args.recording} calibrated with {args.calibration} ({cal.CAL_TYPE}; "
          f"effects applied: {names}); ax, ay, az in m/s^2 written to {args.out}", file=sys.stderr)
    return 0


def _write_corrected(path: Path, rec, x) -> None:
    import pandas as pd

    from .atomic import atomic_output

    time_name, time_values = rec.time_column if rec.time_column is not None else ("t", rec.t)
    data = {time_name: time_values, "ax": x[:, 0], "ay": x[:, 1], "az": x[:, 2]}
    if rec.temp is not None:
        data["temp"] = rec.temp
    with atomic_output(path) as tmp, open(tmp, "w", newline="") as f:
        pd.DataFrame(data).to_csv(f, index=False)


# --------------------------------------------------------------------------- discrepancy


def _discrepancy(args) -> int:
    from .atomic import write_json_atomic
    from .discrepancy import report
    from .errors import RecordingError
    from .jsonsafe import json_safe

    t0 = time.perf_counter()
    rec = _read(args)
    if rec.unit is None:
        raise AccelcalError("the acceleration unit is unknown: pass --unit")
    static = _static_settings(args, rec)
    with _step("static detection, deterministic and stochastic layers (the noise bootstrap takes a while)"):
        try:
            analysis = report.discrepancy_report(rec, args.g, stochastic=report.DEFAULT_STOCHASTIC, unit=rec.unit,
                                                static_kw=static)
        except RecordingError as e:
            raise RecordingError(f"{e}{_rate_hint(rec)}") from None
    figures = []
    if args.figures is not None:
        from .discrepancy.figures import recording_figures

        with _step("drawing figures"):
            figures = recording_figures(analysis, title=args.recording.name)
    out = analysis.to_dict()
    out.update({**_provenance(args, t0), "g": args.g, "unit": rec.unit, "notes": list(rec.notes),
                "input": {"unit": rec.unit}})
    if figures:
        from .plotting import save_figure

        for name, fig in figures:
            save_figure(fig, Path(args.figures) / name)
    write_json_atomic(args.out, json_safe(out))
    _discrepancy_summary(out, args.out)
    return 0


def _discrepancy_summary(out: dict, path: Path) -> None:
    det = out
    lines = [f"discrepancy: {det['n_poses']} poses; effect named: {det['effect']}"
             + (f" (then {', '.join(det['effects'][1:])})" if len(det["effects"]) > 1 else ""),
             f"  gap (RMS residual / noise) {det['gap_before']:.3g} -> {det['gap_after']:.3g} "
             f"(noise alone: {det['gap_expected_after']:.3g}); excess {det['excess_before']:.3g} -> "
             f"{det['excess_after']:.3g}"]
    if det["not_identifiable"]:
        lines.append(f"  not identifiable with these poses: {', '.join(det['not_identifiable'])}")
    for o in det.get("outliers", []):
        lines.append(f"  outlier pose {o['pose']} at t = {o['t']:.1f} s: shifted {o['shift_sigma']:+.3g} sigma "
                     f"(p = {o['p']:.3g}); gap {o['gap_before']:.3g} -> {o['gap_after']:.3g} without it")
    nm = det.get("noise_model") or {}
    if nm.get("term") == "bias_wander":
        def v(x):  # the JSON holds None for inf (a random walk has no finite size)
            return "inf" if x is None else f"{x:.3g}"

        def ci(x):
            return "[" + ", ".join(map(v, x)) + "]"

        lines.append(f"  bias wander ({nm['process']}): size {v(nm['size'])} {ci(nm['size_ci'])}, "
                     f"tau {v(nm['tau_s'])} s {ci(nm['tau_ci'])}, random-walk K {v(nm['random_walk_K'])} "
                     f"{ci(nm['random_walk_K_ci'])}"
                     + (f", correlation between the axes {v(nm['axis_correlation'])} {ci(nm['axis_correlation_ci'])}"
                        if nm.get("axis_correlation") is not None else "") + " (95 % profile likelihood)"
                     + ("" if nm.get("time_correlation_established") else
                        "; its time correlation is not established (tau may be below the poses: extra white noise)"))
    elif nm.get("estimated") is False and det.get("null") == "colored":
        lines.append(f"  bias wander not estimated: {nm.get('reason', '')}")
    elif nm.get("term") == "none" and det.get("null") == "colored":
        lines.append("  bias wander: none detected (REML estimate 0)")
    if det.get("excess_predicted") is not None and det.get("null") == "colored":
        lo, hi = det["excess_predicted_interval"]
        lines.append(f"  residual excess observed {det['excess_observed']:.3g}, predicted by white + wander "
                     f"{det['excess_predicted']:.3g} (95 % interval {lo:.3g}-{hi:.3g})")
    for e in det.get("errors", []):
        lines.append(f"  did not converge: {e}")
    st = out.get("stochastic")
    if st:
        named = {ax: a["named"] for ax, a in st["axes"].items()}
        lines.append("  noise terms named: " + "; ".join(f"{ax}: {', '.join(v)}" for ax, v in named.items()))
        imp = out.get("noise_implication") or {}
        if imp:
            lines.append(f"  residual excess expected from the noise model {imp['expected_excess']:.3g}, "
                         f"observed {imp['observed_excess']:.3g} (explained: {'yes' if imp['explains_excess'] else 'no'})")
    else:
        lines.append(f"  stochastic layer: {out.get('stochastic_error', 'not run')}")
    lines.append(f"  written to {path}")
    print("\n".join(lines), file=sys.stderr)


# --------------------------------------------------------------------------- noise

NOISE_HELP = """\
RECORDING: a static recording, the sensor at rest in one orientation for its whole
length (hours resolve the bias terms): a ROS 1/2 bag or MCAP file (sensor_msgs/Imu:
accelerometer and gyroscope), a PX4 ULog, an ArduPilot DataFlash log, or a table
(accelerometer only). Outputs (JSON, YAML, figure) are written only on success.
The exported values are continuous-time, the worst axis, with every axis and the
interval in a comment: noise density N [m/s^2/sqrt(Hz), rad/s/sqrt(Hz)] and random
walk K [m/s^3/sqrt(Hz), rad/s^2/sqrt(Hz)] of the IEEE fit of the Allan deviation.
"""


def _noise_parser(sub) -> None:
    n = sub.add_parser("noise", help="noise densities and random walks of a static recording (Kalibr, OpenVINS)",
                       description="Allan deviation and IEEE noise terms (quantization, white noise, bias "
                                   "instability, random walk, ramp) of a static recording, with intervals; exports "
                                   "for Kalibr and OpenVINS.",
                       formatter_class=argparse.RawDescriptionHelpFormatter, epilog=NOISE_HELP)
    n.add_argument("recording", type=Path, help="the static recording (log or table)")
    n.add_argument("--out", type=Path, required=True, help="noise report JSON")
    n.add_argument("--kalibr", type=Path, metavar="YAML", help="also write Kalibr's imu.yaml")
    n.add_argument("--openvins", type=Path, metavar="YAML", help="also write OpenVINS's kalibr_imu_chain.yaml")
    n.add_argument("--calibration", type=Path, metavar="JSON",
                   help="accelcal calibration whose M becomes OpenVINS's Ta (default: identity)")
    n.add_argument("--inflate", type=_positive, default=1.0, metavar="F",
                   help="multiply the exported densities and random walks by F (OpenVINS advises 10-20)")
    n.add_argument("--figure", type=Path, metavar="PNG", help="also draw the Allan deviations (.png and .pdf)")
    n.add_argument("--level", type=float, default=0.95, help="confidence level of the intervals (default 0.95)")
    n.add_argument("--seed", type=int, default=0, help="seed of the bootstrap (default 0)")
    g = n.add_argument_group("reading a log")
    g.add_argument("--topic", help="the IMU topic (ROS), sensor_accel or sensor_combined (PX4), IMU message "
                                   "(DataFlash); default: the only one")
    g.add_argument("--instance", type=int, help="the sensor instance (PX4 multi_id, DataFlash I)")
    g.add_argument("--time-source", choices=("header", "log"), default="header",
                   help="the sensor's stamps (default) or the log's record times")
    n.set_defaults(func=_noise)


def _noise(args) -> int:
    from .formats_logs import detect_log, read_log
    from .noise_report import analyse_noise

    t0 = time.perf_counter()
    if not args.recording.exists():
        raise AccelcalError(f"{args.recording}: no such file or folder")
    if not 0 < args.level < 1:
        raise AccelcalError(f"--level must be between 0 and 1, got {args.level}")
    with _step(f"reading {args.recording}"):
        if detect_log(args.recording):
            rec = read_log(args.recording, topic=args.topic, time_source=args.time_source, instance=args.instance)
        else:
            from .formats import read

            rec = read(args.recording)
    cal = None
    if args.calibration is not None:
        from .calibration import load_calibration

        cal = load_calibration(args.calibration)
    with _step("Allan deviations and the noise fit"):
        report = analyse_noise(rec, level=args.level, seed=args.seed)
    texts, warnings = _noise_exports(args, rec, report, cal)
    figure = None
    if args.figure is not None:
        from .noise_figure import noise_figure

        with _step("drawing the figure"):
            figure = noise_figure(report, title=f"{args.recording.name}: {report.duration_s / 3600:.3g} h at "
                                                f"{report.fs:.4g} Hz")
    _noise_write(args, report, texts, figure, t0)
    _noise_summary(args, report, warnings)
    return 0


def _noise_exports(args, rec, report, cal) -> tuple[dict, list]:
    import re

    from .noise_export import kalibr_yaml, openvins_yaml

    found = next((m.group(1) for n in rec.notes if (m := re.search(r"topic (/\S+) \(sensor_msgs/Imu", n))), None)
    topic = args.topic or found or "/imu0"
    texts, warnings = {}, []
    if args.kalibr is not None:
        texts[args.kalibr] = kalibr_yaml(report, rostopic=topic, inflate=args.inflate)
    if args.openvins is not None:
        texts[args.openvins], warnings = openvins_yaml(report, rostopic=topic, inflate=args.inflate, calibration=cal)
    elif cal is not None:
        warnings.append("--calibration is used by --openvins only; nothing was exported from it")
    if texts and found is None:
        warnings.append(f"rostopic in the YAML is {topic} (the recording is not a ROS log): set it to your topic")
    return texts, warnings


def _noise_write(args, report, texts: dict, figure, t0: float) -> None:
    from .atomic import atomic_output, write_json_atomic

    out = report.to_dict()
    out["provenance"] = _provenance(args, t0) if args.recording.is_file() else \
        {"accelcal_version": __version__, "recording": str(args.recording), "elapsed_s": time.perf_counter() - t0}
    write_json_atomic(args.out, out)
    for path, text in texts.items():
        with atomic_output(path) as tmp:
            Path(tmp).write_text(text)
    if figure is not None:
        from .plotting import save_figure

        save_figure(figure, args.figure)


def _noise_summary(args, report, warnings: list) -> None:
    from .noise_export import exported_values

    lines = [f"noise: {report.n} samples, {report.duration_s / 3600:.3g} h at {report.fs:.4g} Hz"]
    lines += [f"  read: {n}" for n in report.notes if n]
    for s in report.sensors.values():
        ex = [exported_values(s, j) for j in range(3)]
        lines.append(f"  {s.sensor}: noise density " + ", ".join(f"{e['noise_density']['value']:.3g}" for e in ex)
                     + f" {s.unit}/sqrt(Hz); random walk " + ", ".join(
                         f"{'<' if e['random_walk']['upper_bound'] else ''}{e['random_walk']['value']:.3g}" for e in ex)
                     + f" {ex[0]['random_walk']['unit']} (x, y, z)")
    lines.append(f"  written to {args.out}" + "".join(f", {p}" for p in (args.kalibr, args.openvins, args.figure)
                                                         if p is not None))
    print("\n".join(lines), file=sys.stderr)
    for w in (*report.warnings, *warnings):
        _warn(w)


if __name__ == "__main__":
    sys.exit(main())
