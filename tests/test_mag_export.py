"""The magnetometer exports, read back through each consumer's own equations (implemented here):

PX4 ``Magnetometer::Correct`` (src/lib/sensor_calibration/Magnetometer.hpp l. 86-89, commit 021ee44):
``S · (raw - OFF)`` with S symmetric from SCALE (diagonal) and ODIAG (xy, xz, yz), gauss.
ArduPilot ``AP_Compass_Backend::correct_field`` (libraries/AP_Compass/AP_Compass_Backend.cpp
l. 86-114, commit 2017268): ``M · ((raw + OFS) · SCALE)``, milligauss, SCALE used only within
[1/1.5, 1.5] (``Compass::have_scale_factor``).  Magneto 1.2: ``A⁻¹ (h - b)``.
"""

import numpy as np
import pytest

from accelcal.errors import AccelcalError
from accelcal.mag.export import ardupilot_params, magneto_text, output_scale, px4_params
from accelcal.mag.model import MagModel

A = np.array([[0.0297, 0.0029, -0.0020], [0.0029, 0.0296, -0.0020], [-0.0020, -0.0020, 0.0329]])
B = np.array([-8.1, 7.5, 0.6])
RAW = np.array([[30.0, -12.0, 40.0], [-25.0, 33.0, -10.0], [5.0, 5.0, -45.0]])  # µT


def _values(text, sep):
    return {ln.split(sep)[-3 if sep == "\t" else 0]: float(ln.split(sep)[-2 if sep == "\t" else 1])
            for ln in text.splitlines() if ln and not ln.startswith("#")}


def _sym(d, e):
    return np.array([[d[0], e[0], e[1]], [e[0], d[1], e[2]], [e[1], e[2], d[2]]])


@pytest.mark.parametrize("strength", [None, 48.0])
def test_px4_correct_reproduces_the_model(strength):
    m = MagModel(A, B, raw_unit="uT", **({} if strength is None else {"strength": strength, "strength_unit": "uT"}))
    p = _values(px4_params(m), "\t")
    off = np.array([p[f"CAL_MAG0_{a}OFF"] for a in "XYZ"])
    S = _sym([p[f"CAL_MAG0_{a}SCALE"] for a in "XYZ"], [p[f"CAL_MAG0_{a}ODIAG"] for a in "XYZ"])
    px4 = (RAW * 0.01 - off) @ S.T  # gauss in, gauss out
    expected = (RAW - B) @ A.T * output_scale(m) * 0.01
    assert np.allclose(px4, expected, rtol=1e-7)
    if strength is not None:
        assert np.allclose(np.linalg.norm((RAW * 0.01 - off) @ S.T, axis=1),
                           np.linalg.norm((RAW - B) @ A.T, axis=1) * 0.48, rtol=1e-7)


@pytest.mark.parametrize("strength", [None, 48.0, 200.0])
def test_ardupilot_correct_field_reproduces_the_model(strength):
    m = MagModel(A, B, raw_unit="uT", **({} if strength is None else {"strength": strength, "strength_unit": "uT"}))
    p = _values(ardupilot_params(m), ",")
    ofs = np.array([p[f"COMPASS_OFS_{a}"] for a in "XYZ"])
    M = _sym([p[f"COMPASS_DIA_{a}"] for a in "XYZ"], [p[f"COMPASS_ODI_{a}"] for a in "XYZ"])
    scale = p["COMPASS_SCALE"]
    if not 1 / 1.5 <= scale <= 1.5:  # the autopilot ignores it: the export must not rely on it
        scale = 1.0
    ap = ((RAW * 10.0 + ofs) * scale) @ M.T  # milligauss
    expected = (RAW - B) @ A.T * output_scale(m) * 10.0
    assert np.allclose(ap, expected, rtol=1e-7)


def test_magneto_form_and_refusal_of_counts():
    m = MagModel(A, B, raw_unit="counts")
    lines = magneto_text(m).splitlines()
    b = np.array(lines[2].split(), float)
    Ainv = np.array([ln.split() for ln in lines[4:7]], float)
    assert np.allclose((RAW - b) @ Ainv.T, m.correct(RAW))
    with pytest.raises(AccelcalError, match="physical unit"):
        px4_params(m)


@pytest.mark.parametrize("consumer, rows", [("px4", "px4_rows"), ("ardupilot", "ardupilot_rows")])
def test_accelcal_export_writes_the_compass_beside_the_imu(consumer, rows):
    """`accelcal export --to px4|ardupilot` of a calibration with a magnetometer: the autopilot's file
    holds the compass parameters the tests above check, next to the accelerometer's."""
    from types import SimpleNamespace

    from accelcal.export.registry import sections
    from accelcal.mag import export as mag_export

    m = MagModel(A, B, raw_unit="uT")
    inputs = SimpleNamespace(calibration=SimpleNamespace(mag=SimpleNamespace(model=m)),
                             option=lambda name, default=None: default)
    section = {"px4": mag_export.px4_section, "ardupilot": mag_export.ardupilot_section}[consumer]
    assert section in sections(consumer)  # the registry entry carries it
    params, left_out, notes = section(inputs)
    expected = mag_export.px4_rows(m) if rows == "px4_rows" else mag_export.ardupilot_rows(m)[0]
    assert params == expected and left_out == []
    no_mag = SimpleNamespace(calibration=SimpleNamespace(mag=None), option=inputs.option)
    assert section(no_mag) == ([], [], [])
