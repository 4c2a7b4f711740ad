"""Command-line interface: ``accelcal calibrate RECORDING.csv --g G --method M --out RESULT.json``."""

from __future__ import annotations

import argparse
import os
import sys
import threading
import time
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from . import ESTIMATORS, __version__
from .atomic import sha256_file, write_json_atomic
from .errors import AccelcalError
from .results import _finite_json

MODEL_HELP = """\
model (Burkhard et al. 2024, eq. 1):  z = M x + b + e
  z  measured specific force of a static pose (mean of the rest interval)
  x  true specific force, |x| = g at rest
  b  bias;  M lower triangular, row i = (1 + s_i) u_i with scale factors s and
     non-orthogonality angles (theta_xy, theta_zx, theta_zy), see accelcal.model

methods:
  full-lls   closed form (SVD), bias + scale + non-orthogonality, >= 10 poses
  full-als   full-lls with its O(noise^2) bias removed (adjusted least squares)
  full-nlls  iterative (CasADi/IPOPT) from b = 0, M = I, >= 10 poses
  bias-lls   closed form with M = I, >= 4 poses; the bias does not depend on g
  bias-nlls  iterative with M = I, >= 4 poses

input: CSV with a header row and columns
  t         time [s], strictly increasing
  ax,ay,az  acceleration, one consistent unit (m/s^2 or raw counts)
  temp      optional, temperature [degC]
other columns are ignored. The recording must start at rest (the noise level is
learned there, as in IMU-TK) and hold the sensor still in each pose.

units: give --g in the unit the calibrated output should have. For the full
models z may be in raw counts with g in m/s^2: M then carries the sensitivity
(counts per m/s^2) and b is in counts. The bias-only models (M = I) need z and g
in the same unit.
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

"""


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


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="accelcal", description="Accelerometer calibration from static poses.",
                                formatter_class=argparse.RawDescriptionHelpFormatter, epilog=MODEL_HELP)
    p.add_argument("--version", action="version", version=f"accelcal {__version__}")
    sub = p.add_subparsers(dest="command", required=True)
    c = sub.add_parser("calibrate", help="estimate bias, scale factors and non-orthogonality from a recording",
                       description="Detect the static poses of RECORDING.csv and estimate the accelerometer errors.",
                       formatter_class=argparse.RawDescriptionHelpFormatter, epilog=MODEL_HELP)
    c.add_argument("recording", type=Path, help="CSV with columns t, ax, ay, az [, temp]")
    c.add_argument("--g", type=float, required=True, help="local gravity magnitude (e.g. 9.80665)")
    c.add_argument("--method", choices=sorted(ESTIMATORS), default="full-lls", help="estimator (default full-lls)")
    c.add_argument("--out", type=Path, required=True, help="result JSON (written only on success)")
    c.set_defaults(func=_calibrate)
    d = sub.add_parser("discrepancy", help="find where the calibrated model and the recording disagree, name the "
                                           "missing effect and noise term",
                       description="Fit the model of Burkhard et al. (2024) to the static poses of RECORDING.csv, "
                                   "test a library of candidate effects (quadratic, cubic, bias_drift, temperature, "
                                   "temperature_scale) as nested extensions and name the one the residuals ask for "
                                   "(or 'none'); compare the Allan deviation of the rests with a white-noise "
                                   "simulator and name the missing noise term.",
                       formatter_class=argparse.RawDescriptionHelpFormatter, epilog=DISCREPANCY_HELP + MODEL_HELP)
    d.add_argument("recording", type=Path, help="CSV with columns t, ax, ay, az [, temp]")
    d.add_argument("--g", type=float, required=True, help="local gravity magnitude (e.g. 9.80665)")
    d.add_argument("--out", type=Path, required=True, help="report JSON (written only on success)")
    d.add_argument("--figures", type=Path, default=None, metavar="DIR",
                   help="also write discrepancy_residuals and discrepancy_allan (.png, .pdf) to DIR")
    d.set_defaults(func=_discrepancy)
    return p


def _discrepancy(args) -> int:
    from .discrepancy import report
    from .recording import read_recording

    if not np.isfinite(args.g) or args.g <= 0:
        raise AccelcalError(f"--g must be a positive number, got {args.g:g}")
    t0 = time.perf_counter()
    with _step(f"reading {args.recording}"):
        rec = read_recording(args.recording)
    with _step("static detection, deterministic and stochastic layers (the noise bootstrap takes a while)"):
        analysis = report.analyse(rec, args.g, stochastic=report.DEFAULT_STOCHASTIC, unit="data unit")
    figures = []
    if args.figures is not None:
        from .discrepancy.figures import recording_figures

        with _step("drawing figures"):
            figures = recording_figures(analysis, title=args.recording.name)
    out = analysis.to_dict()
    out.update({"accelcal_version": __version__, "recording": str(args.recording),
                "recording_sha256": sha256_file(args.recording), "g": args.g, "elapsed_s": time.perf_counter() - t0})
    if figures:
        from .plotting import save_figure

        for name, fig in figures:
            save_figure(fig, Path(args.figures) / name)
    write_json_atomic(args.out, _finite_json(out))
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
                     f"{ci(nm['random_walk_K_ci'])} (95 % profile likelihood)"
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


def _calibrate(args) -> int:
    from .recording import read_recording
    from .static import detect_static_recording

    t0 = time.perf_counter()
    with _step(f"reading {args.recording}"):
        rec = read_recording(args.recording)
    with _step(f"detecting static intervals in {len(rec.t)} samples"):
        poses = detect_static_recording(rec)
    estimator = ESTIMATORS[args.method]
    if args.method.startswith("bias"):
        _check_same_unit(poses.means, args.g)
    with _step(f"estimating {args.method} from {len(poses.means)} poses"):
        result = estimator(poses.means, args.g)
    out = result.to_dict()
    out.update({
        "method": args.method,
        "accelcal_version": __version__,
        "recording": str(args.recording),
        "recording_sha256": sha256_file(args.recording),
        "poses": {
            "t_start": poses.t_start.tolist(),
            "t_end": poses.t_end.tolist(),
            "mean": poses.means.tolist(),
            "mean_std": poses.mean_std.tolist(),
            "temp": None if poses.temp is None else poses.temp.tolist(),
        },
        "elapsed_s": time.perf_counter() - t0,
    })
    write_json_atomic(args.out, _finite_json(out))
    _summary(result, args.method, args.out)
    return 0


def _check_same_unit(means: np.ndarray, g: float) -> None:
    norm = float(np.median(np.linalg.norm(means, axis=1)))
    if not 0.5 < norm / g < 2.0:
        raise AccelcalError(
            f"pose magnitudes (median {norm:.4g}) are not in the unit of --g {g:g}: "
            "the bias-only models need both in one unit (use a full model for raw counts)"
        )


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


def _summary(r, method: str, out: Path) -> None:
    se = r.standard_errors
    lines = [
        f"{method}: {r.n_poses} poses, residual RMS {r.residual_rms:.3g} (noise estimate {float(se['noise_std']):.3g})",
        "  bias          " + _fmt(r.bias, se["bias"]),
    ]
    if r.model == "full":
        if np.all(np.abs(r.scale_factors) < 0.5):
            lines.append("  scale [ppm]   " + _fmt(r.scale_factors * 1e6, se["scale_factors"] * 1e6))
        else:  # raw counts against g in m/s²: the row norms of M are sensitivities
            lines.append("  gain 1+s      " + _fmt(1 + r.scale_factors, se["scale_factors"]))
        lines.append("  nonorth [deg] " + _fmt(r.nonorthogonality_deg, se["nonorthogonality_deg"]))
    lines.append(f"  written to {out}")
    print("\n".join(lines), file=sys.stderr)


def _fmt(values, errors) -> str:
    return "  ".join(f"{v:+.6g} ± {e:.2g}" for v, e in zip(values, errors))


if __name__ == "__main__":
    sys.exit(main())
