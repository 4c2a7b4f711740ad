"""Every export consumer of the registry (:data:`accelcal.export.registry.CONSUMERS`) behaves alike:
it writes the files its entry names, refuses in one line what it cannot write (a missing
gyroscope or noise report, an implausible calibration), says what its model leaves out,
refuses exactly the lossy exports under ``exact``, and takes sections added by other parts.

Its consumer's own equations are checked per consumer in ``tests/test_export_equations.py``.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from accelcal.export import CONSUMERS
from accelcal.export.api import ExportError, ExportInputs, export, output_paths, write_files
from accelcal.export import registry

from .export_fixtures import full_calibration, gyro_quality, noise_report

NAMES = list(CONSUMERS)
#: The consumers whose model holds every term of a calibration without fitted effects.
EXACT = {"kalibr", "openvins", "imucal"}


def _inputs(cal=None, noise="default", **options):
    cal = full_calibration() if cal is None else cal
    return ExportInputs(cal, noise_report() if noise == "default" else noise, {"source": "cal.json", **options})


@pytest.mark.parametrize("name", NAMES)
def test_every_consumer_writes_the_files_its_entry_names(name, tmp_path):
    c = CONSUMERS[name]
    assert c.source and c.title and callable(c.load_writer())
    r = export(name, _inputs())
    assert set(r.files) == set(c.files)
    assert all(text.strip() and text.endswith("\n") for text in r.files.values())
    files = output_paths(name, tmp_path / "out", r)
    write_files(files)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(f"out{s}" for s in c.files)
    assert all(x.line().startswith("left out: ") and x.cost for x in r.left_out)


@pytest.mark.parametrize("name", NAMES)
def test_what_a_consumer_needs_is_named_in_one_line(name):
    c = CONSUMERS[name]
    no_gyro = full_calibration(gyro=False)
    if "gyro" in c.needs:
        with pytest.raises(ExportError, match=r"needs the gyroscope .*calibrate a recording with gyro") as e:
            export(name, _inputs(no_gyro))
        assert "\n" not in str(e.value)
    else:
        r = export(name, _inputs(no_gyro))
        assert all("gyroscope" not in x.term for x in r.left_out)
    if "noise" in c.needs:
        with pytest.raises(ExportError, match=r"needs the noise .*--noise NOISE.json .*accelcal noise") as e:
            export(name, _inputs(noise=None))
        assert "\n" not in str(e.value)
    else:
        export(name, _inputs(noise=None))


def _implausible():
    cal = full_calibration()
    scale = cal.M.copy()
    scale[1, 1] = 1.3
    flipped = cal.M.copy()
    flipped[2, 2] = -1.0
    gyro = replace(cal.gyro, model=replace(cal.gyro.model, bias=np.array([0.0, 40.0, 0.0])))
    return {"scale 1.3": (replace(cal, M=scale), "scale is y 1.3"),
            "offset 200 m/s^2": (replace(cal, bias=np.array([0.0, 0.0, 200.0])),
                                 "offset is z 200 m/s^2, beyond the sensor's range of 16 g"),
            "axis flipped": (replace(cal, M=flipped), "not positive definite"),
            "gyro offset 40 rad/s": (replace(cal, gyro=gyro), "gyroscope's offset is y 2292 deg/s")}


@pytest.mark.parametrize("case", list(_implausible()))
@pytest.mark.parametrize("name", NAMES)
def test_implausible_calibrations_are_refused_in_one_line(name, case):
    cal, words = _implausible()[case]
    with pytest.raises(ExportError, match="implausible calibration") as e:
        export(name, _inputs(cal))
    assert words in str(e.value) and "\n" not in str(e.value)


def test_the_sensor_range_sets_the_offset_limit():
    cal = replace(full_calibration(), bias=np.array([0.0, 0.0, 60.0]))  # 6.1 g: beyond a 4 g part, within 16 g
    export("px4", _inputs(cal))
    with pytest.raises(ExportError, match="range of 4 g"):
        export("px4", _inputs(cal, acc_range_g=4.0))


@pytest.mark.parametrize("name", NAMES)
def test_exact_refuses_exactly_the_exports_that_leave_a_term_out(name):
    r = export(name, _inputs())
    assert bool(r.left_out) == (name not in EXACT)
    if name in EXACT:
        export(name, _inputs(), exact=True)
    else:
        with pytest.raises(ExportError, match=r"^--exact: .* cannot hold .*export without --exact"):
            export(name, _inputs(), exact=True)


def test_noise_values_must_be_positive_and_in_si_units():
    bad = noise_report()
    bad["sensors"]["gyroscope"]["axes"]["y"]["noise_density"]["value"] = 0.0
    with pytest.raises(ExportError, match="not a positive number on every axis"):
        export("orbslam3", _inputs(noise=bad))
    counts = noise_report()
    counts["sensors"]["accelerometer"]["unit"] = "counts"
    with pytest.raises(ExportError, match="accelerometer is in counts; VINS needs m/s\\^2"):
        export("vins", _inputs(noise=counts))


def _compass_section(inputs):
    return [("CAL_MAG0_XOFF", 0.25)], [], ["compass from a test section"]


def test_a_section_added_by_another_part_lands_in_the_parameter_file(monkeypatch):
    monkeypatch.setattr(registry, "_ADDED", {})
    registry.add_section("px4", "tests.test_export_conformance:_compass_section")
    registry.add_section("px4", "tests.test_export_conformance:_compass_section")  # once only
    r = export("px4", _inputs())
    assert r.files[""].count("CAL_MAG0_XOFF\t0.25\t9") == 1 and "compass from a test section" in r.notes
    assert "CAL_MAG0" not in export("ardupilot", _inputs()).files[""]
    with pytest.raises(KeyError):
        registry.add_section("nobody", "x:y")


def test_strict_sees_the_quality_warnings_of_both_sensors():
    from accelcal.export.api import trust_problems

    cal = full_calibration()
    assert trust_problems(cal) == []
    bad = replace(cal, gyro=replace(cal.gyro, quality=gyro_quality(["the gyro's residuals exceed the noise"])))
    assert trust_problems(bad) == ["gyroscope: the gyro's residuals exceed the noise"]


def test_the_docs_page_lists_every_consumer_and_its_source():
    text = (Path(__file__).resolve().parents[1] / "docs" / "export.md").read_text()
    for c in CONSUMERS.values():
        assert f"`{c.name}`" in text, c.name


def test_px4_writes_the_device_ids_the_ulog_reader_noted():
    cal = full_calibration()
    notes = ["PX4 ULog, sensor_accel instance 0 (device id 3014666): 1000 samples at 200 Hz",
             "sensor_gyro instance 0 (device id 3014658), rad/s, sampled with the accelerometer"]
    text = export("px4", _inputs(replace(cal, provenance={"notes": notes}))).files[""]
    assert "1\t1\tCAL_ACC0_ID\t3014666\t6" in text and "1\t1\tCAL_GYRO0_ID\t3014658\t6" in text
    combined = replace(cal, provenance={"notes": ["PX4 ULog, sensor_combined: 900 samples at 200 Hz; already ..."]})
    assert any("compose with the vehicle's present ones" in n for n in export("px4", _inputs(combined)).notes)
    r = export("px4", _inputs(cal, device_id=77, instance=2))
    assert "CAL_ACC2_ID\t77\t6" in r.files[""] and "CAL_GYRO2_ID" not in r.files[""]


@pytest.mark.parametrize("name", NAMES)
def test_a_fitted_effect_is_named_as_left_out_by_every_consumer(name):
    from accelcal.calibration.base import EffectTerm

    cal = replace(full_calibration(), effects=(EffectTerm("temperature", np.array([1e-3, -2e-3, 5e-4]), 25.0),))
    r = export(name, _inputs(cal))
    assert any(x.term == "the fitted effect temperature" for x in r.left_out)
    with pytest.raises(ExportError, match="--exact"):
        export(name, _inputs(cal), exact=True)
