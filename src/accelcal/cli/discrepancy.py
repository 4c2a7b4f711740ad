"""``accelcal discrepancy``: where the calibrated model and the recording disagree."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from ..atomic import write_json_atomic
from ..effects import EFFECT_IDS
from ..errors import AccelcalError, RecordingError
from ..registry import min_gyro_rests
from .common import (_gravity, _provenance, _rate_hint, _read, _reader_options, _search_static, _static_options,
                     _static_settings, _step)

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
  excess_status          the residual excess under the model the loop used (named
               effects and noise terms); excess_status_white: against the rests'
               white noise alone (values: accelcal.discrepancy.schema.STATUS)
  noise_model  the noise between poses (bias wander or per-placement offset); reading:
               what its numbers mean, in words
  stochastic   Allan deviation of the rests vs a white-noise simulator, named noise
               terms, Allan gap before/after; noise_implication: what they mean for
               the pose residuals
  gyroscope    the gyro's loop (when the recording has a gyro and --no-gyro is not given):
               named effects (g_sensitivity, scale_asymmetry, rate_nonlinearity,
               time_offset, motion_bias, sample_clock; clock_rate is always
               not_identifiable between rests), per round and candidate the test (F,
               p_value, p_adjusted, mde, absorbed share; not_identifiable with why and
               the motions it needs), excess_before/after, estimates, calibration (the
               gyro refitted with the named effects: `apply` corrects with them);
               outcome 'not_tested' with a one-line reason when the gyro cannot be
               calibrated from these rests or they do not measure its noise
  magnetometer the magnetometer's loop (when the recording has one and --no-mag is not
               given), the same keys as gyroscope: named effects (soft_iron, disturbance
               with its window of samples, temperature), per round the tests, the noise
               model (AR order of the residuals); outcome 'not_tested' with a reason
  static       the detection settings (searched as `accelcal calibrate` does)
  The report is also a calibration: `accelcal apply REPORT.json RECORDING` applies
  its base model with the named effects, the gyroscope's too (--no-effects: the models only).

"""

def add_parser(sub, epilog: str) -> None:
    """The ``discrepancy`` subcommand."""
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


def _discrepancy(args) -> int:
    from ..discrepancy import report
    from ..jsonsafe import json_safe

    t0 = time.perf_counter()
    rec = _read(args)
    if rec.unit is None:
        raise AccelcalError("the acceleration unit is unknown: pass --unit")
    static = _static_settings(args, rec)
    with_gyro = rec.gyro is not None and not args.no_gyro  # as calibrate (cli.gyro.wants_gyro)
    with _step("static detection, deterministic and stochastic layers (the noise bootstrap takes a while)"):
        try:
            analysis = report.discrepancy_report(rec, args.g, stochastic=report.DEFAULT_STOCHASTIC, unit=rec.unit,
                                                static_kw=static, search=_search_static(args), gyro=with_gyro,
                                                mag=not getattr(args, "no_mag", False),
                                                min_poses=min_gyro_rests() if with_gyro else 0)
        except RecordingError as e:
            raise RecordingError(f"{e}{_rate_hint(rec)}") from None
    figures = []
    if args.figures is not None:
        from ..discrepancy.figures import recording_figures

        with _step("drawing figures"):
            figures = recording_figures(analysis, title=args.recording.name)
    out = analysis.to_dict()
    out.update({**_provenance(args, t0), "g": args.g, "unit": rec.unit, "notes": list(rec.notes),
                "input": {"unit": rec.unit}})
    if figures:
        from ..plotting import save_figure

        for name, fig in figures:
            save_figure(fig, Path(args.figures) / name)
    write_json_atomic(args.out, json_safe(out))
    print(analysis.summary(written_to=args.out), file=sys.stderr)
    return 0

