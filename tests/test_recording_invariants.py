"""The invariants of a recording are checked in one place, for every reader (issue 33).

At least ``MIN_ROWS`` samples, finite time, specific force and rate, time strictly
increasing: :func:`accelcal.recording.checked_recording` checks them on every reader's
output (``formats.read``), and the reader's :class:`~accelcal.recording.Origin` lets the
one-line refusal name the place (the line, the message of a topic) and the fix.

Two tests keep it so: every registered format's sample, broken in each of the three ways
(tests/format_samples.py ``DAMAGES``), is refused by that check and names the place; and
no module of ``accelcal/formats`` carries a row, finite or time check of its own, except
the ones listed here with why they are the format's own.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import numpy as np
import pytest

from accelcal import recording
from accelcal.errors import RecordingError
from accelcal.formats import FORMATS, read

from .format_samples import DAMAGES, SAMPLES

FORMATS_DIR = Path(recording.__file__).parent / "formats"

#: (format, damage) -> why a check of the format's own structure refuses it first.
FORMATS_OWN = {
    ("block-log", "one_row"): "each block is one pose and needs MIN_ROWS rows of its own (block_log._block_rate)",
    ("px4", "one_row"): "an instance of fewer than MIN_ROWS samples is no candidate: which sensor_accel is read",
    ("mat", "one_row"): "a variable of fewer than MIN_ROWS rows is no candidate: which variable is the recording",
    ("rda", "one_row"): "a variable of fewer than MIN_ROWS rows is no candidate: which variable is the recording",
}
#: Formats whose files carry no time (it is the row index over a rate): time cannot go back.
UNTIMED = {"block-log", "mpu6050"}

#: Where sample ``BROKEN`` (nan) or ``BROKEN + 1`` (backwards) of each sample file is, as the message must say.
PLACES = {
    "block-log": ("line 14", None), "mpu6050": ("line 13", None), "imucal": ("line 9", "line 10"),
    "imucal-annotated": ("line 9", "line 10"), "csv": ("line 9", "line 10"), "imutk": ("line 8", "line 9"),
    "ros": ("message 7", "message 8"), "px4": ("message 7", "message 8"), "ardupilot": ("message 7", "message 8"),
    "mat": ("row 8", "row 9"), "rda": ("row 8", "row 9"),
}
CASES = [(name, damage, False) for name in FORMATS for damage in DAMAGES
         if (name, damage) not in FORMATS_OWN and not (damage == "backwards" and name in UNTIMED)]
CASES += [(name, damage, True) for name, f in FORMATS.items() if f.strict_reader for damage in DAMAGES]


def _raised_in(e: pytest.ExceptionInfo) -> str:
    """The function the error was raised in."""
    tb = e.tb
    while tb.tb_next is not None:
        tb = tb.tb_next
    return f"{Path(tb.tb_frame.f_code.co_filename).name}:{tb.tb_frame.f_code.co_name}"


def test_every_format_has_a_place_to_name():
    assert set(PLACES) == set(FORMATS), "say where the broken sample of a new format's file is"


@pytest.mark.parametrize("name, damage, strict", CASES, ids=[f"{n}-{d}" + "-strict" * s for n, d, s in CASES])
def test_a_broken_file_is_refused_by_the_shared_check_naming_the_place(name, damage, strict, tmp_path):
    path = tmp_path / f"{damage}.sample"
    path.write_bytes(SAMPLES[name](np.random.default_rng(1), damage))
    with pytest.raises(RecordingError) as e:
        read(path, format=name, strict=strict)
    msg = str(e.value)
    assert _raised_in(e) in ("recording.py:checked_recording", "recording.py:_check_increasing"), msg
    assert msg.startswith(f"{path}: ") and "\n" not in msg
    if damage == "one_row":
        assert re.search(r": only 1 (data rows|messages|rows); need at least 10 \(.+\)$", msg), msg
    elif damage == "nan":
        assert f"non-finite value nan at {PLACES[name][0]} " in msg and msg.endswith("remove or repair it"), msg
    else:
        assert re.search(rf" (repeats|goes back) at {PLACES[name][1]} \(", msg), msg
        assert "--rate" in msg or "stamps are not in order" in msg, msg


@pytest.mark.parametrize("name, damage", sorted(FORMATS_OWN))
def test_what_the_formats_own_checks_refuse_is_one_line(name, damage, tmp_path):
    """The exceptions above: refused in one line by the format's own structure, not let through."""
    path = tmp_path / f"{damage}.sample"
    path.write_bytes(SAMPLES[name](np.random.default_rng(1), damage))
    with pytest.raises(RecordingError, match=r"at least 10|at least 2 samples") as e:
        read(path, format=name)
    assert "\n" not in str(e.value) and not _raised_in(e).startswith("recording.py:check")


def test_a_side_file_is_checked_as_a_recording_of_its_own(tmp_path):
    """A gyro of its own file (--gyro): its lines are named, not the accelerometer's."""
    acc, gyro = tmp_path / "acc.csv", tmp_path / "gyro.csv"
    rows = [f"{k / 100:.2f},0.1,0.2,9.8" for k in range(30)]
    acc.write_text("t,ax,ay,az\n" + "\n".join(rows) + "\n")
    g = [f"{k / 100:.2f},0.01,0.02,0.03" for k in range(30)]
    g[4] = "0.04,0.01,inf,0.03"
    gyro.write_text("t,gx,gy,gz\n" + "\n".join(g) + "\n")
    with pytest.raises(RecordingError) as e:
        read(acc, gyro=gyro)
    assert str(e.value) == (f"{gyro}: angular rate (column 'gy'): non-finite value inf at line 6 (1 such line(s)); "
                            "remove or repair it")


# --------------------------------------------------------------------------- no check of a reader's own

#: Names of checks that were per-reader copies of the shared one; none may come back.
COPIES = ("check_rows", "check_finite", "check_time", "_check_increasing")
#: Words of a refusal of a row count, a non-finite value or time order.
REFUSAL = re.compile(r"need at least|at least \{MIN_ROWS\}|non-finite|not a finite|strictly increasing|not in order"
                     r"|goes back|repeats at")
#: (module, words of its refusal) -> why the check is the format's own and stays.
OWN_CHECKS = {
    ("block_log.py", "need at least"): "each block (a pose) needs MIN_ROWS rows: the file's structure",
    ("px4.py", "at least {MIN_ROWS}"): "a topic instance of fewer samples is no candidate (which instance is read)",
    ("px4.py", "non-finite"): "sensor_gyro is a topic of its own resampled to sensor_accel's times: only here "
                              "can its messages be named",
    ("px4.py", "not in order"): "the same: sensor_gyro's stamps, which the resampling needs in order",
    ("parsing.py", "non-finite"): "a table's magnetometer columns (parse_numbers(finite=True)): a Recording's nan "
                                  "field is a log's 'no sample here' (mag_logs), so a table's nan is refused as read",
    ("variables.py", "at least {MIN_ROWS}"): "a variable of fewer rows is no candidate (which variable is the "
                                             "recording)",
}


def _refusals(path: Path) -> list[str]:
    """The words of :data:`REFUSAL` in each ``raise`` statement of the module at ``path``."""
    text = path.read_text()
    found = []
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, ast.Raise) and node.exc is not None:
            found += REFUSAL.findall(ast.get_source_segment(text, node) or "")
    return found


def _called_or_defined(path: Path) -> set[str]:
    names = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Call):
            f = node.func
            names.add(f.id if isinstance(f, ast.Name) else f.attr if isinstance(f, ast.Attribute) else "")
        elif isinstance(node, ast.FunctionDef):
            names.add(node.name)
    return names


def test_no_reader_checks_rows_finiteness_or_time_of_its_own():
    modules = sorted(p for p in FORMATS_DIR.glob("*.py") if p.name != "_parse_kernels.py")
    copies = {p.name: sorted(_called_or_defined(p) & set(COPIES)) for p in modules}
    assert not any(copies.values()), f"a reader's copy of the shared check: {copies}"
    found = {(p.name, words) for p in modules for words in _refusals(p)}
    assert found <= set(OWN_CHECKS), (f"a row, finite or time refusal of a reader's own: {found - set(OWN_CHECKS)}; "
                                      "give the reader an Origin and leave it to recording.checked_recording")
    assert set(OWN_CHECKS) <= found, f"listed but gone (drop them from OWN_CHECKS): {set(OWN_CHECKS) - found}"


#: Where the shared check is called besides formats.read, and why there.
CALLERS = {
    "variables.py": "each run of a file of variables, while its rows still name their variable",
    "gyro_file.py": "a gyro file of its own (--gyro): its lines, not the accelerometer's",
    "ros.py": "read_topic, the route of `accelcal apply` to a bag (and a recovered bag's part, named damaged)",
    "imucal_annotated.py": "before its parts become known intervals (a Recording refuses a 1-sample rest)",
}


def test_the_shared_check_runs_where_a_files_samples_are_read():
    """formats.read (both routes), and where samples reach a recording another way (:data:`CALLERS`)."""
    callers = {p.name for p in FORMATS_DIR.glob("*.py") if "checked_recording" in _called_or_defined(p)}
    assert callers == {"dispatch.py", *CALLERS}
    dispatch = (FORMATS_DIR / "dispatch.py").read_text()
    assert dispatch.count("return checked_recording(") == 2


def test_the_route_of_apply_to_a_bag_checks_it_too(tmp_path):
    """``accelcal apply`` reads a bag with ros.read_topic (for the bag's order), not formats.read."""
    from accelcal.formats import ros

    path = tmp_path / "nan.bag"
    path.write_bytes(SAMPLES["ros"](np.random.default_rng(1), "nan"))
    with pytest.raises(RecordingError, match=r"topic /imu: specific force \(linear_acceleration.x\): non-finite value "
                                             r"nan at message 7 "):
        ros.read_topic(path)
