"""The calibration applied to a recording, for both outputs of ``accelcal apply`` (a table, a log):
the refusal of data calibrated already, the warning of another unit, the time terms kept to their
own session, the gyroscope in the unit it was calibrated from."""

from __future__ import annotations

from dataclasses import replace

from ..effects import TIME, effect
from ..errors import AccelcalError
from ..units import ANGULAR_RATE_UNITS
from .common import recording_sha256, warn


def check_source(cal, rec, args) -> None:
    """Refuse data calibrated already (unless told); warn when the calibration was made on another unit."""
    if rec.precalibrated and not args.already_calibrated:
        raise AccelcalError(f"{args.recording} was read from {rec.precalibrated}: applying {args.calibration} would "
                            "correct it a second time; read the raw sensor_accel where the log has it (without "
                            "--topic sensor_combined), or pass --already-calibrated if the calibration was fitted to "
                            "these calibrated values")
    made_on = cal.provenance.get("device_id")
    if made_on is not None and rec.device_id is not None and str(made_on) != str(rec.device_id):
        warn(f"{args.calibration} was made on device {made_on}, but {args.recording}'s sensor is device "
             f"{rec.device_id}: a calibration belongs to one unit")


def corrected(cal, rec, args):
    """(calibrated acc, calibrated gyro or None, the effects applied, why the gyro was not corrected)."""
    expected = cal.input_unit or cal.unit
    if expected is not None and rec.unit != ("counts" if expected == "counts" else "m/s^2"):
        raise AccelcalError(f"{args.recording} is read as {rec.unit} but {args.calibration} was made from "
                            f"{expected}: pass --unit {'counts' if expected == 'counts' else 'm/s2 (or g, mg)'}")
    effects = () if args.no_effects else cal.effects
    # a term in time runs on the calibration session's clock: it describes that session only
    drift = [e.id for e in effects if effect(e.id).covariate == TIME]
    if drift and cal.provenance.get("recording_sha256") != recording_sha256(args.recording):
        warn(f"the calibration's {', '.join(drift)} term describes the drift during its own session; it is not "
              "applied to another recording")
        effects = tuple(e for e in effects if e.id not in drift)
    cal = replace(cal, effects=effects)
    x = cal.apply(rec.acc, t=rec.t, temp=rec.temp, unit=rec.unit)
    w, note = _gyro(cal, rec, args)
    return x, w, effects, note


def _gyro(cal, rec, args):
    """The calibrated rate [rad/s] (or None) and a line on why the gyro was not corrected."""
    if cal.gyro is None:
        return None, "" if rec.gyro is None else "gyro not corrected: the calibration has no gyroscope"
    if rec.gyro is None or args.no_gyro:
        return None, "the calibration's gyroscope not applied: the recording has no gyro (--gyro FILE)"
    import numpy as np

    made = cal.gyro.model.raw_unit
    have = rec.gyro_unit
    if have is None:  # not stated: decided only where the calibration's own motions decided it
        if cal.provenance.get("recording_sha256") != recording_sha256(args.recording):
            raise AccelcalError(f"{args.recording}: the gyro's unit is not stated in the file and a recording other "
                                f"than the calibration's own cannot be assumed to share its {made}; pass "
                                f"--gyro-unit rad/s, deg/s or counts")
        have = made
    if (made == "counts") != (have == "counts"):
        raise AccelcalError(f"the recording's gyro is read as {have} but {args.calibration}'s gyroscope was made from "
                            f"{made}: pass --gyro-unit {made}")
    raw = rec.gyro if made == have else np.asarray(rec.gyro) * (ANGULAR_RATE_UNITS[have] / ANGULAR_RATE_UNITS[made])
    named = [e["id"] for e in cal.gyro.effects]
    if named and args.no_effects:  # the model only (a g-sensitivity named stays: it is the model's G)
        cal = replace(cal, gyro=replace(cal.gyro, settings={**cal.gyro.settings, "effects": []}))
        named = []
    w = cal.apply_gyro(raw, rec.acc, t=rec.t, temp=rec.temp, unit=rec.unit)
    return w, f"gyroscope effects applied: {', '.join(named)}" if named else ""
