"""The gyro's unit decided by the session's own evidence, when neither the file nor the user states it.

A multi-position session: between two rests the sensor turns, and gravity seen at the
first rest must be carried onto gravity seen at the next by the integrated rotation.  The
scalar scale ``c`` [rad/s per raw unit] that does this best over the motions
(:func:`accelcal.gyro.fit.initial_scale`, IMU-TK's unweighted misfit) is the evidence: it
lies within a real gyro's scale error (a few %) of the unit's factor to rad/s, and the
two candidates differ by 57.3, so at most one of them is within :data:`DECIDE_FACTOR` of
it.  A Ferraris session: the plain sum of each marked rotation over its stated angle gives
``c`` the same way.

Where ``c`` fits neither rad/s nor deg/s, integer values are raw counts (their scale is
then estimated from ``c``); anything else is refused in one line naming ``--gyro-unit``:
never a number off by a unit.
"""

from __future__ import annotations

import numpy as np

from .errors import GyroInputError
from .fit import initial_scale
from .model import RAW_UNITS

#: The physical units the evidence chooses between.
CANDIDATES = ("rad/s", "deg/s")
#: ``c`` within this factor of a unit's factor to rad/s decides that unit (the candidates are 57.3 apart;
#: a real gyro's scale error is a few %).
DECIDE_FACTOR = 1.5
#: Motions tilting gravity by more than MIN_TILT_DEG that the decision needs.
MIN_TILTING, MIN_TILT_DEG = 3, 20.0


def decide(c: float, integer_values: bool, what: str) -> tuple[str, str]:
    """``(unit, how)`` from the evidence ``c`` [rad/s per raw unit] (module docstring).

    ``what`` names the evidence for the message (``'the motions between rests'``).
    """
    fits = [u for u in CANDIDATES if 1.0 / DECIDE_FACTOR <= c / RAW_UNITS[u] <= DECIDE_FACTOR]
    if fits:
        u = fits[0]
        other = next(o for o in CANDIDATES if o != u)
        apart = max(RAW_UNITS[u], RAW_UNITS[other]) / min(RAW_UNITS[u], RAW_UNITS[other])
        return u, (f"unit {u}, decided by {what}: they fit {c:.4g} rad/s per raw unit, {c / RAW_UNITS[u]:.3f} x "
                   f"{u}'s factor ({other} would be {apart:.3g} x off)")
    if integer_values:
        return "counts", f"scalar search (raw counts: integer values, which {what} scale by {c:.4g} rad/s per count)"
    raise GyroInputError(f"the gyro's unit is not stated and {what} do not decide it: they fit {c:.4g} rad/s per "
                         f"raw unit, which is neither rad/s (1) nor deg/s ({RAW_UNITS['deg/s']:.4g}); pass "
                         "--gyro-unit rad/s, deg/s or counts (with --gyro-sensitivity if known)")


def is_integer_valued(gyro) -> bool:
    g = np.asarray(gyro, float)
    return bool(g.size) and bool(np.all(g == np.round(g)))


def unit_from_motions(ms, integrator: str, gyro) -> tuple[str, float, str]:
    """``(unit, nominal [rad/s per raw unit], how)`` of a multi-position session's motions ``ms``.

    Only motions that tilt gravity carry evidence (a turn about the vertical leaves it in
    place for any scale): fewer than :data:`MIN_TILTING` of them, and the unit is refused.
    """
    tilt = np.rad2deg(np.arccos(np.clip(np.sum(ms.u[ms.rest_before] * ms.u[ms.rest_after], axis=1), -1, 1)))
    if int(np.sum(tilt > MIN_TILT_DEG)) < MIN_TILTING:
        raise GyroInputError(f"the gyro's unit is not stated and only {int(np.sum(tilt > MIN_TILT_DEG))} of "
                             f"{len(tilt)} motions tilt gravity by more than {MIN_TILT_DEG:g} deg ({MIN_TILTING} "
                             "needed to decide it); pass --gyro-unit rad/s, deg/s or counts")
    c = float(initial_scale(ms, integrator))
    unit, how = decide(c, is_integer_valued(gyro), "the motions between rests")
    nominal = c if unit == "counts" else RAW_UNITS[unit]
    return unit, nominal, how


def unit_from_rotations(segments, h: float, angles_deg, gyro) -> tuple[str, str]:
    """``(unit, how)`` of a Ferraris session: its rotations' summed rate against their stated angles."""
    turns = np.array([h * np.linalg.norm(np.asarray(s, float).sum(axis=0)) for s in segments])
    angles = np.deg2rad(np.abs(np.broadcast_to(np.asarray(angles_deg, float), (len(turns),))))
    ok = turns > 0
    if not ok.any():
        raise GyroInputError("the marked rotations show no rotation in the gyro: wrong gyro columns or sections "
                             "(--intervals), or pass --gyro-unit")
    c = float(np.median(angles[ok] / turns[ok]))
    unit, how = decide(c, False, "the rotations of known angle")
    return unit, how


__all__ = ["CANDIDATES", "DECIDE_FACTOR", "MIN_TILTING", "MIN_TILT_DEG", "decide", "is_integer_valued",
           "unit_from_motions", "unit_from_rotations"]
