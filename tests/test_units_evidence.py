"""A gyro's unit comes from the file, the user or evidence that decides it, else one line: never a silent factor.

The property over every format that carries a gyro x {rad/s, deg/s, counts} x {declared, undeclared}
(tests/units_cells.py): read and calibrated as a user would, each cell gives the right rates or a
one-line refusal.  Then: arbitrary scales of undeclared values (hypothesis), the static record whose
gyro nothing decides (the noise analysis refuses it naming --gyro-unit, nothing written), --gyro-unit
over a log's spec, and a static record given to calibrate, recognised before pose detection.
"""

from __future__ import annotations

import time

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from accelcal import cli
from accelcal.errors import AccelcalError
from accelcal.formats import read
from accelcal.formats.units_evidence import SPEC_GYRO_UNITS, UndecidedUnitError, require_gyro_unit
from accelcal.gyro.calibrate import calibrate_gyro
from accelcal.gyro.unit_evidence import DECIDE_FACTOR, decide
from accelcal.one_orientation import one_orientation
from accelcal.recording import Recording

from . import units_cells as cells


@pytest.fixture(scope="module")
def session():
    return cells.session()


@pytest.fixture(scope="module")
def ferraris():
    return cells.ferraris_session()


@pytest.mark.parametrize("fmt", cells.FORMATS)
def test_every_cell_is_right_or_refused_in_one_line(fmt, session, ferraris):
    s = ferraris if fmt == "imucal-annotated" else session
    for unit in cells.UNITS:
        for declared in (True, False):
            got = cells.outcome(fmt, unit, declared, s)
            assert got.startswith(("right", "refused")), f"{fmt} {unit} {declared}: {got}"
            if declared and unit != "counts" and fmt != "imucal-annotated":  # stated physical units are honoured
                assert got.startswith("right"), f"{fmt} {unit} declared: {got}"
            if not declared and fmt in ("csv", "gyro-file"):  # undeclared: the motions decide
                assert got.startswith("right"), f"{fmt} {unit} undeclared: {got}"
                if unit != "counts":
                    assert "decided by the motions" in got


def test_a_static_records_gyro_is_right_or_refused_unless_its_file_breaks_its_formats_spec():
    """Static records: a unit stated (header, --gyro-unit) or proven (integers: counts) gives the right
    values; none stated: refused naming --gyro-unit.  A log whose spec fixes rad/s but holds deg/s is
    taken at its spec's word: without motions nothing can tell (on a session with motions the evidence
    refuses it, test above)."""
    s = cells.static_session()
    for fmt in cells.FORMATS:
        spec = SPEC_GYRO_UNITS.get(fmt)
        for unit in cells.UNITS:
            for declared in (True, False):
                got = cells.static_outcome(fmt, unit, declared, s)
                if spec is not None and not declared and unit != spec and spec != "counts":
                    continue  # the file breaks its spec: the documented limit (no evidence without motions)
                assert got.startswith(("right", "refused")), f"{fmt} {unit} {declared}: {got}"
                if got.startswith("refused"):
                    assert "--gyro-unit" in got and not declared


def test_a_static_record_of_no_stated_gyro_unit_is_refused_naming_the_option(tmp_path, capsys):
    """The ADIS case: a static deg/s gyro in a table. Before: read as rad/s, exit 0, density 57x too large."""
    rng = np.random.default_rng(3)
    n, fs = 2**12, 100.0
    acc = [0.0, 0.0, -1.0] + 0.003 * rng.standard_normal((n, 3))
    gyro_dps = 0.05 * rng.standard_normal((n, 3)) + [0.1, -0.2, 0.05]
    path = tmp_path / "static.csv"
    np.savetxt(path, np.column_stack([np.arange(n) / fs, gyro_dps, acc]), delimiter=",", fmt="%.8g",
               header="t,Gyro. X,Gyro. Y,Gyro. Z,Accel. X,Accel. Y,Accel. Z", comments="")
    out, yaml = tmp_path / "n.json", tmp_path / "imu.yaml"
    code = cli.main(["noise", str(path), "--out", str(out), "--kalibr", str(yaml)])
    err = capsys.readouterr().err
    assert code == 2 and "--gyro-unit" in err and "57x" in err and len(err.strip().splitlines()) == 1, err
    assert not out.exists() and not yaml.exists()
    with pytest.raises(UndecidedUnitError, match="--gyro-unit"):
        require_gyro_unit(read(path), "a static record")
    rec = read(path, gyro_unit="deg/s")  # stated: the values in rad/s, exactly
    np.testing.assert_allclose(rec.gyro, np.deg2rad(np.loadtxt(path, delimiter=",", skiprows=1)[:, 1:4]))


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(log_scale=st.floats(-4.0, 4.0), integer=st.booleans())
def test_any_scale_of_undeclared_values_is_decided_right_or_refused(session, log_scale, integer):
    """Values in rad/s times any factor k: rad/s (k ~ 1), deg/s (k ~ 57.3), counts (integers, the
    scale estimated), or a refusal; the calibrated rates are right whenever a unit is taken."""
    k = 10.0 ** log_scale
    raw = session["gyro"] * k
    if integer:
        raw = np.round(raw)
    moving = np.linalg.norm(session["rates"], axis=1) > 0.2
    if integer and np.abs(raw[moving]).max() < 20:  # quantised to nothing: not a gyro
        return
    try:
        g = calibrate_gyro(session["t"], raw, session["poses"], session["acc_cal"], raw_unit=None,
                           g_sensitivity=False)
    except AccelcalError as e:  # one line; a float scale of a physical unit is decided, never refused
        assert "\n" not in str(e)
        assert integer or not any(1 / DECIDE_FACTOR <= k / f <= DECIDE_FACTOR for f in (1.0, 180 / np.pi)), str(e)
        assert "--gyro-unit" in str(e) or integer  # integers may be refused for other reasons (a guessed range)
        return
    w = g.model.correct(raw)
    factor = np.median(np.linalg.norm(w[moving], axis=1) / np.linalg.norm(session["rates"][moving], axis=1))
    assert abs(factor - 1.0) < 0.05, (k, integer, g.model.raw_unit, factor)


def test_the_decision_takes_the_unit_within_its_factor_and_refuses_between():
    assert decide(0.98, False, "x")[0] == "rad/s"
    assert decide(np.pi / 180 * 1.03, False, "x")[0] == "deg/s"
    assert decide(0.3, True, "x")[0] == "counts"
    with pytest.raises(AccelcalError, match="--gyro-unit"):
        decide(0.3, False, "x")


@pytest.mark.parametrize("fmt", ["ros", "px4", "ardupilot", "imucal"])
def test_gyro_unit_overrides_a_logs_spec_for_a_file_that_does_not_follow_it(fmt, tmp_path, session):
    """deg/s written where the spec says rad/s (or rad/s where imucal's says deg/s): --gyro-unit is the
    user's word over the file's, converted and said."""
    other = "rad/s" if SPEC_GYRO_UNITS[fmt] == "deg/s" else "deg/s"
    path, kwargs = cells.write(fmt, session, other, True, tmp_path)
    rec = read(path, **kwargs)
    np.testing.assert_allclose(rec.gyro, session["gyro"], rtol=1e-5, atol=1e-5)
    assert any(f"overriding the {fmt} format's {SPEC_GYRO_UNITS[fmt]}" in n for n in rec.notes)


def _static_table(path, n: int, rng) -> None:
    acc = [0.1, -0.2, -9.81] + 0.02 * rng.standard_normal((n, 3))
    np.savetxt(path, np.column_stack([np.arange(n) / 100.0, acc]), delimiter=",", fmt="%.6f", header="t,ax,ay,az",
               comments="")


def test_a_static_record_given_to_calibrate_is_recognised_before_pose_detection(tmp_path, capsys, monkeypatch):
    """One orientation for the whole record: one line pointing to accelcal noise, without walking the
    record through pose detection (the detection here fails the test if called), nothing written."""
    import accelcal.calibration.fitting as fitting

    path = tmp_path / "static.csv"
    _static_table(path, 20_000, np.random.default_rng(4))

    def walked(*a, **k):
        raise AssertionError("pose detection ran on a static record")

    monkeypatch.setattr(fitting, "find_static_poses", walked)
    out = tmp_path / "c.json"
    code = cli.main(["calibrate", str(path), "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and "one orientation" in err and f"accelcal noise {path}" in err, err
    assert len(err.strip().splitlines()) == 1 and not out.exists()


def test_one_orientation_keeps_sessions_that_turn():
    """A session with motions (m/s^2), the same in raw counts with an offset (IMU-TK's Xsens-like
    32768 mid-scale), and a static record in counts."""
    from accelcal.gyro.simulate import simulate_recording

    s = simulate_recording(np.random.default_rng(1), n_motions=4, rest_s=2.0, init_rest_s=3.0)
    assert one_orientation(s["t"], s["acc"], "m/s^2") is None
    assert one_orientation(s["t"], 415.0 * s["acc"] + 32768.0, "counts") is None
    rng = np.random.default_rng(2)
    still = 415.0 * ([0.0, 0.0, 9.81] + 0.01 * rng.standard_normal((6000, 3))) + 32768.0
    assert one_orientation(np.arange(6000) / 100.0, still, "counts") is not None


def test_recognising_a_static_record_costs_a_fraction_of_reading_it(tmp_path):
    """Ratio in one run: calibrate's verdict on a static record against reading it (before: detection
    and its search walked the record, 23x the reading on the 2.78 h ADIS table; now the 1 s means)."""
    from accelcal.calibration import calibrate_recording

    path = tmp_path / "static.csv"
    _static_table(path, 60_000, np.random.default_rng(5))
    t0 = time.perf_counter()
    rec = read(path)
    t_read = time.perf_counter() - t0
    t0 = time.perf_counter()
    with pytest.raises(AccelcalError, match="one orientation"):
        calibrate_recording(rec, 9.81, "full_lls", search=True)
    assert time.perf_counter() - t0 < 0.5 * t_read


def test_a_recording_holds_an_undecided_gyro_as_none():
    rec = Recording(np.arange(20) / 100.0, np.tile([0.0, 0.0, 9.81], (20, 1)), None, "x", unit="m/s^2",
                    gyro=np.zeros((20, 3)))
    assert rec.gyro_unit is None
    with pytest.raises(UndecidedUnitError):
        require_gyro_unit(rec, "a static record")


def test_apply_takes_an_undecided_unit_from_the_calibration_only_for_its_own_recording(session, tmp_path, capsys):
    """calibrate decides deg/s from the motions; apply on the same file uses it; on another file of no
    stated unit it refuses naming --gyro-unit (and writes nothing), and with it applies."""
    path, _ = cells.write("csv", session, "deg/s", False, tmp_path)
    cal, out = tmp_path / "cal.json", tmp_path / "corr.csv"
    assert cli.main(["calibrate", str(path), "--g", str(cells.G), "--out", str(cal)]) == 0
    assert "unit deg/s, decided by the motions" in capsys.readouterr().err
    assert cli.main(["apply", str(cal), str(path), "--out", str(out)]) == 0
    w = np.loadtxt(out, delimiter=",", skiprows=1, usecols=(4, 5, 6))
    moving = np.linalg.norm(session["rates"], axis=1) > 0.2
    assert np.linalg.norm(w[moving] - session["rates"][moving]) < 0.03 * np.linalg.norm(session["rates"][moving])
    other = tmp_path / "other.csv"
    other.write_text(path.read_text().replace("\n0,", "\n0.0,", 1))  # the same session, another file
    capsys.readouterr()
    out.unlink()
    assert cli.main(["apply", str(cal), str(other), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "--gyro-unit" in err and len(err.strip().splitlines()) == 1 and not out.exists()
    assert cli.main(["apply", str(cal), str(other), "--gyro-unit", "deg/s", "--out", str(out)]) == 0
    np.testing.assert_allclose(np.loadtxt(out, delimiter=",", skiprows=1, usecols=(4, 5, 6)), w, atol=1e-9)


@pytest.mark.parametrize("scale, unit", [(1.0, "g"), (9.80665, "m/s^2"), (1000.0, "mg"), (1.6, "counts"),
                                         (4.0, "counts"), (415.0, "counts")])
def test_the_acceleration_unit_is_the_one_whose_g_the_rests_read(scale, unit, session):
    """Rests at 1 g in g, m/s^2 or mg (motions between them do not move the median); any other
    magnitude is raw counts, whose scale the full models estimate: never a physical unit 1.6x off."""
    from accelcal.formats.units_evidence import acceleration_unit_from_rests

    acc = session["acc"] / session["g"] * scale
    if unit == "counts" and scale > 100:
        acc = np.round(acc + 32768.0)
    assert acceleration_unit_from_rests(acc)[0] == unit


def test_turns_about_the_vertical_alone_do_not_decide_the_unit(session):
    """Motions about gravity: any scale carries gravity onto itself, so no unit is taken."""
    from accelcal.gyro.errors import GyroInputError
    from accelcal.gyro.fit import MotionSet
    from accelcal.gyro.unit_evidence import unit_from_motions

    n, k = 1100, 10
    y = np.zeros((n, 3))
    starts = np.arange(k) * 100 + 50
    for a in starts:
        y[a:a + 50, 2] = np.deg2rad(90.0) / 0.5  # 90 deg about z in 0.5 s
    up = np.tile([0.0, 0.0, 1.0], (k + 1, 1))
    ms = MotionSet(y, 0.01, starts - 1, starts + 50, np.arange(k), np.arange(k) + 1, up,
                   np.tile(1e-6 * np.eye(3), (k + 1, 1, 1)), np.full(3, 1e-6), np.zeros((k, 3)))
    with pytest.raises(GyroInputError, match="tilt gravity.*--gyro-unit"):
        unit_from_motions(ms, "magnus4", y)
