"""Every registered file format keeps the registry's contract (accelcal.formats.registry).

Parametrised over :data:`accelcal.formats.FORMATS`, with a sample file of each
(tests/format_samples.py): its sniff recognises its own sample and no other; ``auto``
reads it as naming it does; what it declares holds (time, known intervals, the rate, the
options it takes); a writer's file reads back exactly.  The fuzzer
(tests/test_reader_fuzz.py) damages the same samples, format by format.

The toy formats at the end show what adding a format takes: a module with a sniff and a
reader, and one registry entry (here put in by the test), and nothing else: detection,
``--format`` and the help follow, and a missing optional extra is one line.
"""

from __future__ import annotations

import contextlib
import io
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from accelcal import cli
from accelcal.errors import RecordingError
from accelcal.formats import FALLBACK, FORMATS, Format, detect_format, read, write_recording
from accelcal.formats.registry import OPTION_FLAGS, READING_OPTIONS, formats_help

from .format_samples import RATE_HZ, ROWS, SAMPLES, recording

NAMES = list(FORMATS)


@pytest.fixture
def sample(tmp_path):
    """``sample(name)``: the path of a sample file of format ``name``."""
    def write(name, seed=0):
        path = tmp_path / f"{name}.sample"
        path.write_bytes(SAMPLES[name](np.random.default_rng(seed)))
        return path
    return write


def test_every_format_has_a_sample():
    assert set(SAMPLES) == set(FORMATS), "add a sample of each new format to tests/format_samples.py"


@pytest.mark.parametrize("name", NAMES)
def test_sniff_recognises_its_own_sample_and_no_other(name, sample):
    fmt = FORMATS[name]
    sniff = fmt.load_sniff()
    if sniff is None:  # never detected: auto reads such a file as a table
        assert detect_format(sample(name)) == FALLBACK
        return
    for other in NAMES:
        path = sample(other)
        head = path.read_bytes().decode("utf-8", "replace")[:8192] if fmt.text else path.read_bytes()[:65536]
        assert sniff(path, head) == (other == name), f"{name}'s sniff on a {other} sample"
    assert detect_format(sample(name)) == name


@pytest.mark.parametrize("name", NAMES)
def test_auto_reads_a_sample_as_naming_its_format_does(name, sample):
    """The same numbers; a format that is never detected (read as a table) in the same unit."""
    path = sample(name)
    named, auto = read(path, format=name), read(path)
    np.testing.assert_array_equal(auto.acc, named.acc)
    np.testing.assert_array_equal(auto.t, named.t)
    assert auto.n == ROWS and auto.unit == named.unit
    if detect_format(path) == name:
        said = () if name == FALLBACK else (f"format: {name} (detected; pass --format to choose another)",)
        assert auto.notes == said + named.notes


@pytest.mark.parametrize("name", NAMES)
def test_declared_intervals(name, sample):
    rec = read(sample(name), format=name)
    if FORMATS[name].intervals:
        assert rec.intervals is not None and len(rec.intervals) == 3, "every sample has three known rests"
    else:
        assert rec.intervals is None


@pytest.mark.parametrize("name", NAMES)
def test_rate_times_the_samples_by_their_index(name, sample):
    """Every format takes --rate: its reader uses it (a file without time), or its time is replaced."""
    rec = read(sample(name), format=name, rate=50.0)
    np.testing.assert_allclose(rec.t, np.arange(ROWS) / 50.0, rtol=0, atol=1e-12)


@pytest.mark.parametrize("name", NAMES)
def test_where_the_time_came_from_is_said(name, sample):
    """With --rate a note gives it; a file that does not time its samples says what timed them."""
    assert any("50 Hz" in n for n in read(sample(name), format=name, rate=50.0).notes)
    if not FORMATS[name].defines_time:
        assert any("Hz" in n and "no rate" in n for n in read(sample(name), format=name).notes)


@pytest.mark.parametrize("name", NAMES)
def test_options_a_reader_does_not_take_are_applied_or_refused(name, sample):
    fmt = FORMATS[name]
    path = sample(name)
    if "columns" not in fmt.options:
        with pytest.raises(RecordingError, match="--columns applies to the csv(, mat or rda)? formats?, not to"):
            read(path, format=name, columns="t=1,ax=2,ay=3,az=4")
    if "time_unit" not in fmt.options:
        assert f"--time-unit ignored: the {name} format defines its time" in read(path, format=name,
                                                                                  time_unit="ms").notes
    for option, value in (("topic", "/imu"), ("instance", 0), ("time_source", "log"), ("variable", "imu")):
        if option not in fmt.options:
            with pytest.raises(RecordingError, match=f"{OPTION_FLAGS[option]} applies to the .* not to {name}"):
                read(path, format=name, **{option: value})
    assert set(fmt.options) <= set(READING_OPTIONS)


@pytest.mark.parametrize("name", [n for n in NAMES if "time_source" in FORMATS[n].options])
def test_a_log_reads_its_gyroscope_and_both_clocks(name, sample):
    """A log format declares the log options: its sample's gyroscope comes along (rad/s), and the
    log's clock times it on request, with the recorded stamps kept as its time column."""
    path = sample(name)
    rec, log = read(path, format=name), read(path, format=name, time_source="log")
    assert rec.gyro is not None and rec.gyro.shape == (ROWS, 3) and rec.gyro_unit == "rad/s"
    assert rec.time_column is not None and log.time_column is not None
    np.testing.assert_allclose(rec.t, np.arange(ROWS) / RATE_HZ, rtol=0, atol=1e-6)
    np.testing.assert_array_equal(log.acc, rec.acc)


@pytest.mark.parametrize("name", [n for n in NAMES if FORMATS[n].writer])
def test_a_writers_file_reads_back_exactly(name, tmp_path):
    rec = recording(np.random.default_rng(3))
    path = tmp_path / "written"
    write_recording(path, rec, format=name)
    back = read(path, strict=True, format=name)
    for field in ("t", "acc", "temp", "intervals"):
        np.testing.assert_array_equal(getattr(back, field), getattr(rec, field))
    assert back.labels == rec.labels
    lenient = read(path, format=name)  # the guessing reader finds the same numbers
    np.testing.assert_array_equal(lenient.acc, rec.acc)
    np.testing.assert_array_equal(lenient.t, rec.t)
    np.testing.assert_array_equal(lenient.intervals, rec.intervals)


def test_strict_reading_takes_the_canonical_csv_and_no_option(sample):
    path = sample("csv")
    assert read(path, strict=True).unit is None  # nothing inferred
    with pytest.raises(RecordingError, match="rate apply to strict=False"):
        read(path, strict=True, rate=100.0)
    with pytest.raises(RecordingError, match="no strict reader; strict=True reads csv"):
        read(sample("imutk"), strict=True, format="imutk")
    with pytest.raises(RecordingError, match="expected header t,ax,ay,az"):
        read(sample("imutk"), strict=True)


def test_writing_a_format_without_writer_is_refused(tmp_path):
    with pytest.raises(RecordingError, match="no writer for the imutk format; formats with one: csv"):
        write_recording(tmp_path / "x", recording(np.random.default_rng(0)), format="imutk")


def test_the_registry_checks_its_entries():
    with pytest.raises(ValueError, match="unknown reading option"):
        Format(name="x", title="x", reader="m:f", options=("speed",))
    with pytest.raises(ValueError, match="needs a reader taking rate"):
        Format(name="x", title="x", reader="m:f", defines_time=False)
    with pytest.raises(ValueError, match="go together"):
        Format(name="x", title="x", reader="m:f", extra="ros")


def test_help_lists_the_formats_without_loading_numpy():
    code = ("import sys, contextlib, io\n"
            "from accelcal import cli\n"
            "with contextlib.redirect_stdout(io.StringIO()) as out:\n"
            "    try:\n"
            "        cli.main(['calibrate', '--help'])\n"
            "    except SystemExit:\n"
            "        pass\n"
            "print(','.join(m for m in ('numpy', 'pandas') if m in sys.modules))\n"
            "print(out.getvalue())")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    loaded, help_text = out.split("\n", 1)
    assert loaded == ""
    assert formats_help() in help_text
    assert _format_choices() == ["auto", *FORMATS]


def _format_choices() -> list[str]:
    """The names the help of ``--format`` lists."""
    calibrate = next(a for a in cli._parser()._actions if a.dest == "command").choices["calibrate"]
    text = next(a for a in calibrate._actions if a.dest == "format").help
    return text[text.index("(") + 1:text.index(";")].split(", ")


# --------------------------------------------------------------------------- toy formats


def toy_sniff(path, head: str) -> bool:
    return head.startswith("TOY")


def toy_read(path, text: str) -> object:
    """``TOY`` then one ``x y z`` line per sample at 10 Hz, in g."""
    from accelcal.recording import Recording

    acc = np.array([[float(v) for v in line.split()] for line in text.splitlines()[1:]])
    return Recording(np.arange(len(acc)) / 10.0, acc, None, str(path), notes=("toy: 10 Hz",))


def toy_log_sniff(path, head: bytes) -> bool:
    return path.is_dir() and (path / "toy.meta").is_file()


def toy_log_read(path):
    import accelcal_no_such_package  # noqa: F401  (the extra; never installed)


TOY = Format(name="toy", title="a toy text format, one x y z line per sample", reader=f"{__name__}:toy_read",
             sniff=f"{__name__}:toy_sniff")
TOY_LOG = Format(name="toy-log", title="a toy log folder", reader=f"{__name__}:toy_log_read",
                 sniff=f"{__name__}:toy_log_sniff", text=False, extra="toylog", requires=("accelcal_no_such_package",))


@pytest.fixture
def toys(monkeypatch):
    """The two toy formats registered: one entry each in the table, as a new format's."""
    monkeypatch.setitem(FORMATS, "toy", TOY)
    monkeypatch.setitem(FORMATS, "toy-log", TOY_LOG)


def _cli(*args) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = cli.main([str(a) for a in args])
        except SystemExit as e:
            code = e.code
    return code, out.getvalue(), err.getvalue()


def test_a_toy_format_is_detected_named_and_listed(toys, tmp_path, sample):
    path = tmp_path / "toy.txt"
    rows = np.round(9.80665 * np.tile([[0, 0, 1.0]], (20, 1)), 4)
    path.write_text("TOY\n" + "\n".join(" ".join(map(str, r)) for r in rows) + "\n")
    assert detect_format(path) == "toy"
    rec = read(path)
    assert rec.notes[:2] == ("format: toy (detected; pass --format to choose another)", "toy: 10 Hz")
    assert rec.unit == "m/s^2"  # no unit in the file: inferred from the magnitude, as for every format
    assert read(path, format="toy", rate=20.0).t[1] == pytest.approx(0.05)  # --rate replaces its time
    assert detect_format(sample("mpu6050")) == "mpu6050"  # the others are still recognised
    code, out, _ = _cli("calibrate", "--help")
    assert code == 0 and _format_choices()[-2:] == ["toy", "toy-log"]
    assert " toy a toy text format, one x y z line per sample " in " ".join(out.split())
    assert "a toy log folder; needs pip install accelcal[toylog]" in " ".join(out.split())


def test_a_missing_extra_is_one_line_and_exit_2(toys, tmp_path):
    log = tmp_path / "flight"
    log.mkdir()
    (log / "toy.meta").write_text("")
    assert detect_format(log) == "toy-log"  # a binary format is sniffed on the path, before any text is read
    out = tmp_path / "cal.json"
    for args in ((), ("--format", "toy-log")):
        code, _, err = _cli("calibrate", log, "--out", out, *args)
        assert code == 2 and err.splitlines() == [
            f"accelcal: error: {log}: reading toy-log files needs accelcal_no_such_package, not installed: "
            "pip install accelcal[toylog]"]
        assert not out.exists()


def test_an_unknown_format_is_refused_in_one_line(tmp_path):
    known = ", ".join(["auto", *FORMATS])
    with pytest.raises(RecordingError, match=f"unknown format 'xyz'; known: {known}$"):
        read(Path(tmp_path / "x.csv"), format="xyz")
    code, _, err = _cli("calibrate", tmp_path / "x.csv", "--out", tmp_path / "o.json", "--format", "xyz")
    assert code == 2 and err.splitlines() == [f"accelcal: error: unknown format 'xyz'; known: {known}"]
