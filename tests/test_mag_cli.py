"""The magnetometer on the command line: `calibrate` with magnetometer columns writes it
aligned and `apply` writes mx, my, mz; a zero column leaves the accelerometer's calibration
with one `warning: magnetometer:` line; `accelcal mag` refuses a planar rotation in one line."""

import json

import numpy as np
import pandas as pd
import pytest

from accelcal.cli import main
from tests.mag_sessions import simulate_session


def _session(path, *, zero_mag=False, planar=False, seed=0):
    """tests/mag_sessions' session as a table with magnetometer columns (mag_y zero with ``zero_mag``)."""
    t, acc, m = simulate_session(seed, planar=planar)
    if zero_mag:
        m[:, 1] = 0.0
    df = pd.DataFrame({"t": t, "ax": acc[:, 0], "ay": acc[:, 1], "az": acc[:, 2],
                       "mag_x_uT": m[:, 0], "mag_y_uT": m[:, 1], "mag_z_uT": m[:, 2]})
    df.to_csv(path, index=False)
    return path


def test_calibrate_writes_the_aligned_magnetometer_and_apply_uses_it(tmp_path, capsys):
    rec = _session(tmp_path / "s.csv")
    out = tmp_path / "cal.json"
    assert main(["calibrate", str(rec), "--out", str(out), "--g", "9.81"]) == 0
    err = capsys.readouterr().err
    assert "magnetometer (ellipsoid_ml" in err and "warning: magnetometer" not in err
    d = json.loads(out.read_text())["magnetometer"]
    assert abs(d["alignment"]["dip_deg"] - 60.0) < 0.3
    assert main(["apply", str(out), str(rec), "--out", str(tmp_path / "o.csv")]) == 0
    o = pd.read_csv(tmp_path / "o.csv")
    m = o[["mx", "my", "mz"]].to_numpy()
    assert np.allclose(np.linalg.norm(m, axis=1), 1.0, atol=0.02)


def test_a_zero_magnetometer_column_warns_and_keeps_the_accelerometer(tmp_path, capsys):
    rec = _session(tmp_path / "z.csv", zero_mag=True)
    out = tmp_path / "cal.json"
    assert main(["calibrate", str(rec), "--out", str(out), "--g", "9.81"]) == 0
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if "warning: magnetometer:" in ln]
    assert len(lines) == 1 and "constant" in lines[0] and "--no-mag" in lines[0]
    assert "magnetometer" not in json.loads(out.read_text())


def test_mag_command_refuses_a_planar_rotation(tmp_path, capsys):
    rec = _session(tmp_path / "p.csv", planar=True)
    out = tmp_path / "m.json"
    assert main(["mag", str(rec), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "one axis only" in err[0] and not out.exists()


def test_location_and_date_give_the_igrf_field_in_ut(tmp_path, capsys):
    """Seoul, 2018-08-30 (the SNU sessions): IGRF-13 gives F = 51.1 µT, I = 54.4 deg (NOAA's
    calculator: 51.1 µT, 54.3 deg); the calibrated field is then in µT."""
    from accelcal.mag.field import model_field

    f = model_field("37.5,127.0", "2018-08-30")
    assert f["strength"] == pytest.approx(51.1, abs=0.3) and f["dip_deg"] == pytest.approx(54.4, abs=0.3)
    rec = _session(tmp_path / "s.csv")
    out = tmp_path / "m.json"
    assert main(["mag", str(rec), "--out", str(out), "--location", "37.5,127.0", "--date", "2018-08-30"]) == 0
    err = capsys.readouterr().err.splitlines()
    assert err[-1] == f"written to {out}", "the output ends with where the calibration was written"
    d = json.loads(out.read_text())["magnetometer"]
    assert d["model"]["strength_unit"] == "uT" and d["model"]["strength"] == pytest.approx(f["strength"])
    assert main(["mag", str(rec), "--out", str(out), "--location", "97,0", "--date", "2018-08-30"]) == 2
    assert "latitude" in capsys.readouterr().err
