"""Property-based fuzzing of the readers: any file gives a valid Recording or one
RecordingError line, never another exception; through the CLI, exit 0 or 2 with one line
and no output on failure, never an internal error (exit 4).

The reader property runs over every registered format (``format=`` each name of
:data:`accelcal.formats.FORMATS`, ``auto``, and the strict reading of each format that
has one).  Inputs are generated malformed files: valid files damaged by deletion,
insertion and replacement of characters and lines (tables with odd delimiters, decimal
marks and headers, and the sample file of the format under test,
tests/format_samples.py), comments and blank lines, binary garbage, gzip of any of
these; the sample of a binary format (a log) is damaged byte by byte instead
(truncation, bit flips, spans overwritten, deleted or inserted; tests/test_logs_fuzz.py
does the same to logs of every storage).  The number of examples is ``ACCELCAL_FUZZ_EXAMPLES`` per format (default 250;
a quarter of it through the CLI), so the suite stays fast; the closing note's count
comes from a larger run of the same tests.  Every example run is counted, per format,
and the totals printed (``pytest -s``).
"""

from __future__ import annotations

import contextlib
import gzip
import io
import os
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from accelcal import cli
from accelcal.errors import RecordingError
from accelcal.formats import FORMATS, read
from accelcal.recording import MIN_ROWS

from .format_samples import SAMPLES

N = int(os.environ.get("ACCELCAL_FUZZ_EXAMPLES", "250"))
#: (format, strict) -> {"read": n, "refused": n}; "cli" -> files through `accelcal calibrate`.
COUNT: dict = {"cli": 0}
#: What the reader property runs over: every format, auto, and every strict reading.
READINGS = [("auto", False), *((name, False) for name in FORMATS),
            *((name, True) for name, f in FORMATS.items() if f.strict_reader)]

HEADERS = ["t,ax,ay,az", "time,acc_x,acc_y,acc_z", "timestamp;accX;accY;accZ", "TIME\tAX\tAY\tAZ", "t ax ay az",
           "time [ms],ax [g],ay [g],az [g]", "%time,field.linear_acceleration.x,field.linear_acceleration.y,"
           "field.linear_acceleration.z", "x, y, z", "datetime,ax,ay,az", "", "a,b", "t,ax,ax,az", "pose,t,ax,ay,az",
           "t,gx,gy,gz"]
JUNK = ["nan", "inf", "-inf", "", "1e400", "abc", "1,5", "--", "0x10", "1.2.3", "  ", "\x00", "é", "#", ">>>", ";",
        "\t", "1e-400", "9999999999999999999999", "-0", "+.5", "NaN"]


def _valid_table(draw) -> str:
    n = draw(st.integers(min_value=0, max_value=60))
    sep = draw(st.sampled_from([",", ";", "\t", " ", "|"]))
    header = draw(st.sampled_from(HEADERS))
    rate = draw(st.sampled_from([1.0, 100.0, 400.0, 1000.0]))
    scale = draw(st.sampled_from([1.0, 1 / 9.80665, 1000.0, 16384 / 9.80665]))
    rng = np.random.default_rng(draw(st.integers(0, 2 ** 16)))
    acc = (np.array([0.1, -0.2, 9.8]) + 0.01 * rng.standard_normal((n, 3))) * scale
    t = np.arange(n) / rate
    tfmt = draw(st.sampled_from(["{:.4f}", "{:.0f}", "{:d}"]))
    lines = [header.replace(",", sep) if sep != "," and header.count(",") else header] if header else []
    for i in range(n):
        tv = tfmt.format(int(t[i] * 1000)) if tfmt == "{:d}" else tfmt.format(t[i])
        lines.append(sep.join([tv, *(f"{v:.6g}" for v in acc[i])]))
    return "\n".join(lines) + draw(st.sampled_from(["\n", "", "\r\n", "\n\n\n"]))


def _sample(draw, fmt: str) -> tuple[str, bytes]:
    """The format and sample file of ``fmt`` (of any format for ``auto``)."""
    name = draw(st.sampled_from(sorted(SAMPLES))) if fmt == "auto" else fmt
    return name, SAMPLES[name](np.random.default_rng(draw(st.integers(0, 2 ** 16))))


def _damaged_bytes(draw, data: bytes) -> bytes:
    """A binary file (a log) damaged: truncated, bits flipped, spans overwritten, deleted or inserted."""
    b = bytearray(data)
    for _ in range(draw(st.integers(0, 4))):
        op = draw(st.sampled_from(["truncate", "flip", "overwrite", "delete", "insert"]))
        at = draw(st.integers(0, max(len(b) - 1, 0)))
        if op == "truncate":
            del b[at:]
        elif op == "flip" and b:
            b[at] ^= 1 << draw(st.integers(0, 7))
        elif op == "delete":
            del b[at:at + draw(st.integers(1, 64))]
        else:
            junk = draw(st.binary(min_size=1, max_size=32))
            b[at:at + len(junk) * (op == "overwrite")] = junk
    return bytes(b)


@st.composite
def damaged_files(draw, fmt: str | None = None) -> bytes:
    """A damaged file; with ``fmt``, half of them start from that format's sample."""
    kinds = ["table", "table", "table", "bytes", "lines"] + (["sample"] * 5 if fmt else [])
    kind = draw(st.sampled_from(kinds))
    sampled = _sample(draw, fmt) if kind == "sample" else None
    if kind == "bytes":
        data = draw(st.binary(max_size=400))
    elif kind == "lines":
        data = "\n".join(draw(st.lists(st.text(max_size=40), max_size=30))).encode("utf-8", "surrogatepass")
    elif sampled is not None and not FORMATS[sampled[0]].text:
        data = _damaged_bytes(draw, sampled[1])
    else:
        text = _valid_table(draw) if sampled is None else sampled[1].decode("utf-8")
        for _ in range(draw(st.integers(0, 6))):
            op = draw(st.sampled_from(["delete", "insert", "replace", "cut", "dupline", "comment", "blank"]))
            lines = text.split("\n")
            i = draw(st.integers(0, max(len(lines) - 1, 0)))
            if op == "delete" and text:
                j = draw(st.integers(0, len(text) - 1))
                text = text[:j] + text[j + draw(st.integers(1, 5)):]
            elif op == "insert":
                j = draw(st.integers(0, len(text)))
                text = text[:j] + draw(st.sampled_from(JUNK)) + text[j:]
            elif op == "replace" and lines:
                fields = lines[i].split(",")
                fields[draw(st.integers(0, len(fields) - 1))] = draw(st.sampled_from(JUNK))
                lines[i] = ",".join(fields)
                text = "\n".join(lines)
            elif op == "cut":
                text = text[: draw(st.integers(0, len(text)))]
            elif op == "dupline" and lines:
                lines.insert(i, lines[i])
                text = "\n".join(lines)
            elif op == "comment":
                lines.insert(i, draw(st.sampled_from(["# note", "% x", "// y", "--- monitor"])))
                text = "\n".join(lines)
            elif op == "blank":
                lines.insert(i, "")
                text = "\n".join(lines)
        data = text.encode("utf-8", "surrogatepass")
    if draw(st.booleans()) and draw(st.integers(0, 5)) == 0:
        data = gzip.compress(data, mtime=0)
        if draw(st.booleans()):
            data = data[: len(data) // 2]  # a damaged gzip
    return data


def _check_recording(rec, fmt: str, strict: bool) -> None:
    assert rec.n >= MIN_ROWS and np.all(np.isfinite(rec.t)) and np.all(np.diff(rec.t) > 0)
    if rec.acc is None:  # a gyro-only recording: its gyro, no acceleration unit
        assert not strict and rec.unit is None and rec.gyro is not None
    else:
        assert rec.acc.ndim == 2 and rec.acc.shape == (rec.n, 3) and np.all(np.isfinite(rec.acc))
        assert rec.unit in ((None, "m/s^2", "counts") if strict else ("m/s^2", "counts"))
    assert rec.gyro is None or (rec.gyro.shape == (rec.n, 3) and np.all(np.isfinite(rec.gyro)))
    assert rec.temp is None or (rec.temp.shape == (rec.n,) and np.all(np.isfinite(rec.temp)))
    if fmt != "auto" and not FORMATS[fmt].intervals:
        assert rec.intervals is None, f"{fmt} does not declare known intervals"


@pytest.mark.parametrize("fmt, strict", READINGS, ids=[f + ("-strict" if s else "") for f, s in READINGS])
@settings(max_examples=N, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(data=st.data())
def test_reader_returns_a_recording_or_one_line(fmt, strict, data):
    count = COUNT.setdefault((fmt, strict), {"read": 0, "refused": 0})
    with tempfile.TemporaryDirectory() as tmp:
        p = Path(tmp) / "rec.csv"
        p.write_bytes(data.draw(damaged_files(fmt)))
        try:
            rec = read(p, format=fmt, strict=strict)
        except RecordingError as e:
            msg = str(e)
            assert msg and "\n" not in msg and "Traceback" not in msg
            count["refused"] += 1
        else:
            _check_recording(rec, fmt, strict)
            count["read"] += 1


@settings(max_examples=max(N // 4, 20), deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(damaged_files("auto"))
def test_cli_exits_0_or_2_in_one_line(data):
    COUNT["cli"] += 1
    with tempfile.TemporaryDirectory() as tmp:
        p, out = Path(tmp) / "rec.csv", Path(tmp) / "out.json"
        p.write_bytes(data)
        err = io.StringIO()
        with contextlib.redirect_stderr(err):
            code = cli.main(["calibrate", str(p), "--out", str(out)])
        text = err.getvalue()
        assert code in (0, 2), text
        if code == 2:
            # a read that outlasts 2 s (a loaded machine) announces itself first: not an error line
            lines = [ln for ln in text.strip().splitlines() if not (ln.startswith("accelcal: ") and ln.endswith(" ..."))]
            assert len(lines) == 1 and lines[0].startswith("accelcal: error: "), text
            assert not out.exists()


def test_report_count(request):
    """How many inputs were tried, per format (`pytest -s` prints it): every format and
    strictness of the parametrisation, some read and some refused.  Needs the two properties
    in the same session (they run first in this file)."""
    rows = [(f + (" (strict)" if s else ""), c) for (f, s), c in ((k, v) for k, v in COUNT.items() if k != "cli")]
    total = sum(c["read"] + c["refused"] for _, c in rows)
    print(f"\nfuzz: {total} files through the readers, {COUNT['cli']} through `accelcal calibrate`; per format:")
    for name, c in rows:
        print(f"  {name:<24} {c['read'] + c['refused']:>6} files: {c['read']:>5} read, {c['refused']:>5} refused")
    if not total:
        pytest.skip("the properties did not run in this session")
    selected = {(item.callspec.params["fmt"], item.callspec.params["strict"]) for item in request.session.items
                if item.originalname == "test_reader_returns_a_recording_or_one_line"}
    tried = {k for k in COUNT if k != "cli"}
    assert tried == selected, f"formats never tried: {selected - tried}"
    assert all(c["read"] + c["refused"] > 0 for _, c in rows)
    for name, c in rows:  # 20-54 of 250 read in each format (measured)
        assert c["read"] + c["refused"] < 100 or (c["read"] > 0 and c["refused"] > 0), (name, c)
    # both outcomes: damage that every reader refuses would exercise nothing past the sniffing
    assert sum(c["read"] for _, c in rows) > 0 and sum(c["refused"] for _, c in rows) > 0, rows


pytestmark = pytest.mark.filterwarnings("ignore::UserWarning")
