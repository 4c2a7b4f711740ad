"""The noise analysis: Allan deviations against allantools, fitted terms against known ones, the static and
resolution checks, the Kalibr and OpenVINS exports, and `accelcal noise` end to end."""

from __future__ import annotations

import contextlib
import io
import json
import math
import subprocess
import sys

import numpy as np
import pytest

from accelcal import cli
from accelcal.calibration import FullLLSCalibration
from accelcal.noise.simulation import simulate_noise
from accelcal.errors import NotStaticError
from accelcal.noise.export import ExportError, avr_convention, kalibr_yaml, openvins_yaml
from accelcal.noise.allan_fit import octave_correlations
from accelcal.noise.planner import plan_lines
from accelcal.noise.report import NoiseAnalysisError, analyse_noise, resolution_warnings
from accelcal.noise.terms import TERMS, ieee_terms
from accelcal.recording import Recording

FS = 100.0
TRUE_ACC = {"white": 2e-3, "bias_instability": 1e-3, "random_walk": 1e-5}
TRUE_GYRO = {"white": 1e-4, "random_walk": 5e-6}


def _record(seed: int, n: int = 2**18, acc_terms=TRUE_ACC, gyro_terms=TRUE_GYRO, gyro=True) -> Recording:
    rng = np.random.default_rng(seed)
    acc = np.array([0.1, -0.2, 9.8]) + simulate_noise(rng, n, FS, acc_terms, size=3)
    w = simulate_noise(rng, n, FS, gyro_terms, size=3) if gyro else None
    return Recording(np.arange(n) / FS, acc, None, f"sim{seed}", unit="m/s^2", gyro=w,
                     gyro_unit="rad/s" if gyro else None)


@pytest.fixture(scope="module")
def report():
    return analyse_noise(_record(11))


# --------------------------------------------------------------------------- Allan deviation


def test_allan_deviations_equal_allantools_at_the_same_taus(report):
    allantools = pytest.importorskip("allantools")
    rec = _record(11)
    for name, x in (("accelerometer", rec.acc), ("gyroscope", rec.gyro)):
        s = report.sensors[name]
        for j in range(3):
            taus, adev, _, _ = allantools.oadev(x[:, j], rate=s.allan.fs, data_type="freq", taus=s.allan.taus)
            assert np.allclose(taus, s.allan.taus, rtol=1e-12)
            assert np.allclose(adev, s.allan.adev[:, j], rtol=1e-9, atol=0)


# --------------------------------------------------------------------------- fitted terms


def test_the_fitted_terms_fall_within_their_intervals_at_about_the_stated_rate():
    """5 records x 3 axes of a record whose N, B are resolved: the 95 % intervals must hold the truth on at
    least 12 of 15 axes per term (P(<= 11 | 0.95) = 0.5 %; measured over 300 axes in tools/bench_noise_coverage.py)."""
    hits = {k: 0 for k in ("white", "bias_instability", "random_walk")}
    for seed in range(5):
        s = analyse_noise(_record(100 + seed, n=2**19, gyro=False), n_boot=300, seed=seed).sensors["accelerometer"]
        for axis in s.terms:
            for k in hits:
                hits[k] += axis[k].lo <= TRUE_ACC[k] <= axis[k].hi
    assert all(h >= 12 for h in hits.values()), hits


def test_white_noise_density_and_its_interval(report):
    for name, truth in (("accelerometer", TRUE_ACC["white"]), ("gyroscope", TRUE_GYRO["white"])):
        for axis in report.sensors[name].terms:
            n = axis["white"]
            assert n.resolved and n.lo < n.value < n.hi and abs(n.value / truth - 1) < 0.02


def test_terms_absent_from_the_data_are_bounded_not_resolved(report):
    absent = [axis[k] for axis in report.sensors["gyroscope"].terms for k in ("quantization", "bias_instability",
                                                                              "drift_ramp")]
    assert not any(e.resolved for e in absent)
    assert sum(e.lo == 0 for e in absent) >= 7  # a true zero inside the 95 % interval (7 of 9 or more)


def test_an_unresolved_random_walk_is_warned_about_with_the_record_it_needs():
    short = analyse_noise(_record(3, n=2**15))
    text = " ".join(short.warnings)
    assert "random_walk is not resolved by this record" in text
    assert any(not a["random_walk"].resolved for a in short.sensors["accelerometer"].terms)


def test_a_record_too_short_for_five_octaves_is_refused():
    with pytest.raises(NoiseAnalysisError, match=r"only \d octaves of tau .* need at least 5"):
        analyse_noise(_record(1, n=12, gyro=False))


def test_octave_correlations_reproduce_their_table():
    rng = np.random.default_rng(5)
    for term in ("white", "random_walk"):
        measured = octave_correlations(rng, term, n=2**14, reps=300)
        assert np.allclose(measured[:3], TERMS[term].octave_correlation[:3], atol=0.1), (term, measured)


def test_a_misfitting_model_gets_a_model_error_and_a_warning():
    rng = np.random.default_rng(8)
    n = 2**18
    t = np.arange(n) / FS
    acc = np.array([0, 0, 9.8]) + 2e-3 * math.sqrt(FS) * rng.standard_normal((n, 3))
    acc += 0.02 * np.sin(2 * np.pi * 0.5 * t)[:, None]  # a 0.5 Hz disturbance the five terms lack
    r = analyse_noise(Recording(t, acc, None, "sine", unit="m/s^2"))
    assert min(r.sensors["accelerometer"].model_error) > 0.1
    assert any("follow the Allan deviation only to about" in w for w in r.warnings)
    assert max(analyse_noise(_record(2, gyro=False)).sensors["accelerometer"].model_error) < 0.1


# --------------------------------------------------------------------------- static checks


def test_a_recording_that_moves_is_refused_or_analysed_on_request():
    rec = _record(4, n=2**16)
    acc = rec.acc.copy()
    acc[30000:] = acc[30000:] @ np.array([[1, 0, 0], [0, np.cos(0.2), -np.sin(0.2)], [0, np.sin(0.2), np.cos(0.2)]])
    moved = Recording(rec.t, acc, None, "moved", unit="m/s^2", gyro=rec.gyro, gyro_unit="rad/s")
    with pytest.raises(NotStaticError, match=r"not a static recording: the accelerometer's direction changed by 11"):
        analyse_noise(moved)
    r = analyse_noise(moved, allow_motion=True)
    assert any(w.startswith("not static") for w in r.warnings)


def test_a_rotation_about_gravity_is_caught_by_the_gyro():
    rec = _record(5, n=2**16)
    gyro = rec.gyro.copy()
    gyro[20000:20300, 2] += 0.5
    with pytest.raises(NotStaticError, match="the gyro's 1 s mean rate departs"):
        analyse_noise(Recording(rec.t, rec.acc, None, "yaw", unit="m/s^2", gyro=gyro, gyro_unit="rad/s"))


def test_gaps_and_taps_are_warnings():
    rec = _record(6, n=2**16, gyro=False)
    t = rec.t.copy()
    t[40000:] += 0.5
    acc = rec.acc.copy()
    acc[1000:1100] += 0.5 * np.random.default_rng(0).standard_normal((100, 3))
    w = " ".join(analyse_noise(Recording(t, acc, None, "g", unit="m/s^2")).warnings)
    assert "1 gaps in the time stamps (about 50 samples missing" in w and "noisier than the median block" in w


# --------------------------------------------------------------------------- exports


def _yaml(text: str) -> dict:
    yaml = pytest.importorskip("yaml")
    return yaml.safe_load(text.replace("%YAML:1.0", ""))


def test_kalibr_yaml_holds_the_worst_axis_with_units_and_inflation(report):
    k = _yaml(kalibr_yaml(report, rostopic="/imu", inflate=10))
    acc = report.sensors["accelerometer"]
    worst = max(a["white"].value for a in acc.terms)
    assert k["accelerometer_noise_density"] == pytest.approx(10 * worst, rel=1e-6)
    assert k["rostopic"] == "/imu" and k["update_rate"] == pytest.approx(FS)
    text = kalibr_yaml(report)
    assert "accelerometer_random_walk:" in text and "[ m/s^3/sqrt(Hz) ]" in text and "[ rad/s^2/sqrt(Hz) ]" in text
    with pytest.raises(ExportError, match="inflation factor"):
        kalibr_yaml(report, inflate=0.5)


def test_an_unresolved_random_walk_is_exported_as_its_upper_bound():
    r = analyse_noise(_record(3, n=2**15))
    gyro = r.sensors["gyroscope"]
    k = _yaml(kalibr_yaml(r))
    bounds = [a["random_walk"].hi if not a["random_walk"].resolved else a["random_walk"].value for a in gyro.terms]
    assert k["gyroscope_random_walk"] == pytest.approx(max(bounds), rel=1e-6)
    assert "upper bound" in kalibr_yaml(r)


def test_openvins_chain_carries_the_calibration_as_ta(report):
    M = np.array([[1.01, 0, 0], [0.002, 0.99, 0], [-0.001, 0.003, 1.005]])
    cal = FullLLSCalibration(bias=np.array([0.01, -0.02, 0.03]), M=M, g=9.80665, unit="m/s^2")
    text, warnings = openvins_yaml(report, calibration=cal, inflate=10)
    y = _yaml(text)["imu0"]
    assert np.allclose(y["Ta"], M) and np.allclose(y["Tw"], np.eye(3)) and np.allclose(y["Tg"], 0)
    assert np.allclose(y["R_IMUtoACC"], np.eye(3)) and y["model"] == "kalibr" and warnings == []
    assert "accelerometer bias b_a" in text and "0.01, -0.02, 0.03" in text
    assert "the calibration has no gyroscope: Tw = I" in text
    assert np.allclose(_yaml(openvins_yaml(report)[0])["imu0"]["Ta"], np.eye(3))
    counts = FullLLSCalibration(bias=np.zeros(3), M=400 * np.eye(3), g=9.80665, unit="counts")
    with pytest.raises(ExportError, match="in m/s\\^2; this calibration is of counts"):
        openvins_yaml(report, calibration=counts)


def test_exports_need_physical_units_and_openvins_needs_the_gyro():
    rec = _record(7, n=2**15, gyro=False)
    r = analyse_noise(Recording(rec.t, rec.acc, None, "c", unit="counts"))
    with pytest.raises(ExportError, match="accelerometer is in counts"):
        kalibr_yaml(r)
    with pytest.raises(ExportError, match="OpenVINS needs the noise of both sensors"):
        openvins_yaml(analyse_noise(rec))


def test_the_allan_variance_ros_convention_on_white_noise():
    x = 2e-3 * math.sqrt(FS) * np.random.default_rng(1).standard_normal(2**18)
    from accelcal.noise.allan import allan_variance

    a = allan_variance(x, FS)
    avr = avr_convention(a.taus, a.adev[:, 0])
    assert avr["noise_density"] == pytest.approx(2e-3, rel=0.01)
    # its +1/2 line through white noise reads a "random walk" that is not there: the convention's bias
    assert avr["random_walk"] > 1e-5


def test_the_json_report_is_plain_and_finite(report):
    d = json.loads(json.dumps(report.to_dict(), allow_nan=False))
    assert d["format"] == "accelcal-noise" and set(d["sensors"]) == {"accelerometer", "gyroscope"}
    x = d["sensors"]["accelerometer"]["axes"]["x"]
    assert set(x["terms"]) == set(ieee_terms()) and x["noise_density"]["unit"] == "m/s^2/sqrt(Hz)"
    assert x["random_walk"]["unit"] == "m/s^3/sqrt(Hz)"


# --------------------------------------------------------------------------- the command


def _run(*argv) -> tuple[int, str]:
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        code = cli.main([str(a) for a in argv])
    return code, err.getvalue()


def test_accelcal_noise_on_a_gyro_alone(tmp_path):
    """A recording without accelerometer: the gyro's noise alone (the static check by the gyro's
    rate; it was an internal error, exit 4, before)."""
    rng = np.random.default_rng(3)
    n = 6000
    gyro = 1e-3 * rng.standard_normal((n, 3)) + [0.01, -0.02, 0.005]
    path = tmp_path / "gyro.csv"
    np.savetxt(path, np.column_stack([np.arange(n) / 100.0, gyro]), delimiter=",", header="t,gx,gy,gz", comments="")
    code, err = _run("noise", path, "--gyro-unit", "rad/s", "--out", tmp_path / "noise.json")
    assert code == 0, err
    out = json.loads((tmp_path / "noise.json").read_text())
    assert list(out["sensors"]) == ["gyroscope"]


def test_accelcal_noise_on_a_bag_writes_every_output(tmp_path):
    pytest.importorskip("rosbags")
    pytest.importorskip("matplotlib")
    from .ros_synthetic import write_imu_bag

    rec = _record(9, n=2**15)
    bag = write_imu_bag(tmp_path / "static.mcap", 1.7e9 + rec.t, rec.acc, rec.gyro, kind="mcap", topic="/imu0")
    outs = [tmp_path / n for n in ("n.json", "imu.yaml", "chain.yaml", "fig.png")]
    code, err = _run("noise", bag, "--out", outs[0], "--kalibr", outs[1], "--openvins", outs[2], "--figure", outs[3],
                     "--inflate", "10")
    assert code == 0, err
    assert all(p.is_file() for p in outs) and (tmp_path / "fig.pdf").is_file()
    assert "rostopic: /imu0" in outs[1].read_text()
    assert json.loads(outs[0].read_text())["n_samples"] == 2**15
    assert "noise: 32768 samples, 0.091 h at 100 Hz" in err


def test_accelcal_noise_refuses_a_moving_recording_in_one_line_and_writes_nothing(tmp_path):
    pytest.importorskip("rosbags")
    from .ros_synthetic import write_imu_bag

    rec = _record(10, n=2**14)
    gyro = rec.gyro.copy()
    gyro[5000:6000, 0] = 1.0
    bag = write_imu_bag(tmp_path / "moving.bag", 1.7e9 + rec.t, rec.acc, gyro, kind="ros1")
    out, y = tmp_path / "n.json", tmp_path / "imu.yaml"
    code, err = _run("noise", bag, "--out", out, "--kalibr", y)
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert err.startswith("accelcal: error: ") and "not a static recording" in err
    assert not out.exists() and not y.exists()
    code, err = _run("noise", tmp_path / "missing.bag", "--out", out)
    assert code == 2 and "no such file" in err


def test_a_calibration_with_a_gyroscope_reaches_both_files(report):
    from accelcal.noise.export import calibrated_kalibr_yaml

    from .export_fixtures import full_calibration

    cal = full_calibration()
    text, warnings = openvins_yaml(report, calibration=cal)
    y = _yaml(text)["imu0"]
    assert not np.allclose(y["Tw"], np.eye(3)) and not np.allclose(y["Tg"], 0) and warnings == []
    assert "not calibrated" not in text and "no gyroscope" not in text
    k = _yaml(calibrated_kalibr_yaml(report, cal)[0])
    assert k["model"] == "scale-misalignment" and np.allclose(k["gyroscopes"]["M"], y["Tw"])


def test_accelcal_noise_pays_for_neither_the_gyro_package_nor_the_tables_text(tmp_path):
    """`accelcal noise` writes no gyro model and no time column: the package accelcal.gyro cost it
    0.12 s of CPU to import (of ~2.4 s on the 10⁶-row ADIS CSV), and the time column as written
    kept the table's whole text alive (45 MB of the 287 MB pandas + allantools peak it is held to)."""
    rng = np.random.default_rng(4)
    n = 6000
    gyro = 1e-3 * rng.standard_normal((n, 3)) + [0.01, -0.02, 0.005]
    path = tmp_path / "gyro.csv"
    np.savetxt(path, np.column_stack([np.arange(n) / 100.0, gyro]), delimiter=",", header="t,gx,gy,gz", comments="")
    code = ("import sys\nfrom accelcal import cli\nimport accelcal.noise.report as report\nseen = []\n"
            "analyse = report.analyse_noise\n"
            "def spy(rec, **kw):\n    seen.append(rec.time_column)\n    return analyse(rec, **kw)\n"
            "report.analyse_noise = spy\n"
            "cli.main(sys.argv[1:])\n"
            "print(sorted(m for m in sys.modules if m.startswith('accelcal.gyro')), seen)\n")
    out = subprocess.run([sys.executable, "-c", code, "noise", str(path), "--gyro-unit", "rad/s", "--out",
                          str(tmp_path / "noise.json")], capture_output=True, text=True, timeout=120)
    assert (tmp_path / "noise.json").is_file(), out.stderr
    assert out.stdout.strip().splitlines()[-1] == "[] [None]", out.stdout


def test_the_report_reads_each_terms_roles_from_its_entry(report, monkeypatch):
    """The warnings, the planner and the JSON's units follow the entry's fields (no list of ids elsewhere):
    the ramp, given a planner name and the unresolved warning, is planned and warned about; a unit on the
    entry is the JSON's."""
    s = report.sensors["accelerometer"]
    assert not any("drift_ramp" in w for w in resolution_warnings(s, report.duration_s))
    ramp = TERMS["drift_ramp"]
    monkeypatch.setattr(ramp, "planned_as", "ramp")
    monkeypatch.setattr(ramp, "warn_unresolved", True)
    monkeypatch.setattr(ramp, "unit", "{u} per second")
    assert any(w.startswith("accelerometer x, y, z: drift_ramp is not resolved") and "exports" not in w
               for w in resolution_warnings(s, report.duration_s))
    assert "; ramp " in plan_lines(s, report.duration_s, 0.25, 0.95)[0]
    assert report.to_dict()["sensors"]["accelerometer"]["axes"]["x"]["terms"]["drift_ramp"]["unit"] == "m/s^2 per second"
