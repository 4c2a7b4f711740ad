"""A user's own CSV in the variants people actually have, through ``accelcal calibrate``.

One simulated session (30 hand-placed poses, known bias and M, 100 Hz, m/s²) is written
in the ways loggers, spreadsheets and scripts write it (column names, units in headers,
time units and date-times, delimiters, decimal comma, comments, gzip, BOM, metadata
lines, raw counts, a recording that does not start at rest, a ROS export), plus the
files that must be refused.  :func:`run_variants` runs the CLI on each and records
whether it was read and calibrated correctly (bias within 3 mm/s² of the truth), or
refused, and with which message: the table of the closing note and of
``tests/test_reader_variants.py``.

``python -m accelcal_repro.reader_variants [DIR]`` prints the table (markdown).
"""

from __future__ import annotations

import contextlib
import gzip
import io
import json
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np
import pandas as pd

from accelcal import cli
from accelcal.simulation import random_directions, sample_truth, simulate_recording

G0 = 9.80665
#: Counts per g of the raw-count variant (MPU-6050, ±2 g) and its zero offsets.
COUNTS_PER_G = 16384.0
COUNTS_OFFSET = np.array([120.0, -340.0, 610.0])


@dataclass(frozen=True)
class Variant:
    """One way of writing the session: ``write(path, session) -> path``; ``expect``:
    ``'read'`` or ``'refused'``; ``words``: what the error must say when refused."""

    name: str
    description: str
    write: Callable
    expect: str = "read"
    words: str = ""
    args: tuple = ()
    unit: str = "m/s^2"


def session(seed: int = 11) -> dict:
    """The simulated session: t, acc [m/s²], temp, truth (bias [m/s²], M)."""

    rng = np.random.default_rng(seed)
    tr = {k: v[0] for k, v in sample_truth(rng, 1).items()}
    u = np.vstack([[0, 0, 1.0], random_directions(rng, 29)])
    rec = simulate_recording(rng, u, G0, tr["M"], tr["bias"], noise_std=0.01, temperature=(21.0, 23.0))
    return {"t": rec["t"], "acc": rec["acc"], "temp": rec["temp"], "bias": tr["bias"], "M": tr["M"], "rng": rng}


def _frame(s, names=("t", "ax", "ay", "az"), t=None, acc=None):
    t = s["t"] if t is None else t
    acc = s["acc"] if acc is None else acc
    return pd.DataFrame({names[0]: t, names[1]: acc[:, 0], names[2]: acc[:, 1], names[3]: acc[:, 2]})


def _csv(df, path, **kw):
    df.to_csv(path, index=False, **kw)
    return path


def _text(path, text, encoding="utf-8"):
    Path(path).write_bytes(text.encode(encoding))
    return path


def _semicolon_decimal_comma(path, s):
    df = _frame(s, ("Zeit", "X", "Y", "Z"))
    text = df.to_csv(index=False, sep=";", float_format="%.6f").replace(".", ",")
    return _text(path, text.replace("Zeit;X;Y;Z", "Zeit;acc X;acc Y;acc Z"))


def _whitespace_no_header(path, s):
    lines = [f"{t:.5f} {a:.6f} {b:.6f} {c:.6f}" for t, (a, b, c) in zip(s["t"], s["acc"])]
    return _text(path, "\n".join(lines) + "\n")


def _comments(path, s):
    body = _frame(s).to_csv(index=False)
    return _text(path, "# logger v2.1, sensor ACC-42\n# units: m/s^2\n% exported 2024-05-01\n" + body)


def _gzip(path, s):
    data = _frame(s).to_csv(index=False).encode()
    Path(path).write_bytes(gzip.compress(data, mtime=0))
    return path


def _excel_bom_crlf(path, s):
    text = _frame(s, ("Time", "AccX", "AccY", "AccZ")).to_csv(index=False, lineterminator="\r\n")
    Path(path).write_bytes(b"\xef\xbb\xbf" + text.encode())
    return path


def _extra_columns(path, s):
    df = pd.DataFrame({"time": s["t"], "gyr_x": 0.01, "gyr_y": -0.02, "gyr_z": 0.0, "acc_x": s["acc"][:, 0],
                       "acc_y": s["acc"][:, 1], "acc_z": s["acc"][:, 2], "mag_x": 20.0, "temperature": s["temp"],
                       "status": "ok"})
    return _csv(df, path)


def _counts(s):
    return np.round(COUNTS_OFFSET + s["acc"] / G0 * COUNTS_PER_G)


def _raw_counts(path, s):
    c = _counts(s).astype(np.int64)
    return _csv(pd.DataFrame({"t": s["t"], "ax": c[:, 0], "ay": c[:, 1], "az": c[:, 2]}), path)


def _no_initial_rest(path, s):
    n = 300  # 3 s of handling before the first rest
    rng = np.random.default_rng(5)
    lead = s["acc"][:n] + 2.0 * rng.standard_normal((n, 3))
    acc = np.vstack([lead, s["acc"][n:]])
    return _csv(_frame(s, acc=acc), path)


def _ros(path, s):
    stamp = (1714557600_000_000_000 + np.round(s["t"] * 1e9)).astype(np.int64)
    df = pd.DataFrame({"%time": stamp, "field.header.seq": np.arange(len(stamp)), "field.header.stamp": stamp,
                       "field.header.frame_id": "imu_link", "field.angular_velocity.x": 0.0,
                       "field.linear_acceleration.x": s["acc"][:, 0], "field.linear_acceleration.y": s["acc"][:, 1],
                       "field.linear_acceleration.z": s["acc"][:, 2]})
    return _csv(df, path)


def _metadata_lines(path, s):
    body = _frame(s, ("t", "ax", "ay", "az")).to_csv(index=False)
    return _text(path, "Device,ACC-42\nSerial,00731\nSample rate,100\n" + body)


def _missing_column(path, s):
    return _csv(_frame(s).drop(columns=["az"]), path)


def _two_candidates(path, s):
    df = _frame(s, ("t", "acc_x", "acc_y", "acc_z"))
    df["accel_x"] = df["acc_x"]
    return _csv(df, path)


def _repeated_ms(path, s):
    # 100 Hz samples stamped by a clock that ticks every 20 ms: every other stamp repeats
    t = np.floor(s["t"] * 1000 / 20) * 20
    return _csv(_frame(s, ("timestamp_ms", "ax", "ay", "az"), t=t.astype(np.int64)), path)


def _nan(path, s):
    acc = s["acc"].copy()
    acc[1234, 1] = np.nan
    return _csv(_frame(s, acc=acc), path)


def _truncated(path, s):
    text = _frame(s).to_csv(index=False)
    return _text(path, text[: len(text) - 20])


def _xlsx(path, s):
    Path(path).write_bytes(b"PK\x03\x04" + b"\x14\x00\x06\x00" + bytes(200))
    return path


def _never_rests(path, s):
    t = s["t"]
    ang = 0.5 * t
    acc = G0 * np.column_stack([np.cos(ang), np.sin(ang) * np.cos(0.3 * t), np.sin(ang) * np.sin(0.3 * t)])
    acc += 0.01 * np.random.default_rng(3).standard_normal(acc.shape)
    return _csv(_frame(s, acc=acc), path)


def _two_columns(path, s):
    return _csv(pd.DataFrame({"time": s["t"], "accel": s["acc"][:, 2]}), path)


VARIANTS: tuple[Variant, ...] = (
    Variant("canonical", "t,ax,ay,az in s and m/s^2", lambda p, s: _csv(_frame(s), p)),
    Variant("imucal_names", "time, acc_x, acc_y, acc_z", lambda p, s: _csv(_frame(s, ("time", "acc_x", "acc_y",
                                                                                      "acc_z")), p)),
    Variant("camel_case", "timestamp, accX, accY, accZ", lambda p, s: _csv(_frame(s, ("timestamp", "accX", "accY",
                                                                                      "accZ")), p)),
    Variant("upper_case", "TIME, AX, AY, AZ", lambda p, s: _csv(_frame(s, ("TIME", "AX", "AY", "AZ")), p)),
    Variant("units_in_header", "time [s], acc_x [m/s^2], ...", lambda p, s: _csv(_frame(
        s, ("time [s]", "acc_x [m/s^2]", "acc_y [m/s^2]", "acc_z [m/s^2]")), p)),
    Variant("g_in_header", "t, ax_g, ay_g, az_g (data in g)", lambda p, s: _csv(_frame(
        s, ("t", "ax_g", "ay_g", "az_g"), acc=s["acc"] / G0), p)),
    Variant("g_no_unit", "t, ax, ay, az in g, no unit written", lambda p, s: _csv(_frame(s, acc=s["acc"] / G0), p)),
    Variant("mg_in_header", "time, Accel X (mg), ...", lambda p, s: _csv(_frame(
        s, ("time", "Accel X (mg)", "Accel Y (mg)", "Accel Z (mg)"), acc=s["acc"] / G0 * 1000), p)),
    Variant("ms_timestamps", "timestamp in integer ms (Arduino millis())", lambda p, s: _csv(_frame(
        s, ("timestamp", "ax", "ay", "az"), t=np.round(s["t"] * 1000).astype(np.int64) + 123456), p)),
    Variant("us_timestamps", "time in integer µs (micros())", lambda p, s: _csv(_frame(
        s, ("time", "ax", "ay", "az"), t=np.round(s["t"] * 1e6).astype(np.int64) + 5_000_000), p)),
    Variant("ns_epoch", "Unix epoch time stamps in ns", lambda p, s: _csv(_frame(
        s, ("timestamp", "ax", "ay", "az"), t=(1714557600_000_000_000 + np.round(s["t"] * 1e9)).astype(np.int64)), p)),
    Variant("iso_datetime", "ISO 8601 date-times", lambda p, s: _csv(_frame(
        s, ("datetime", "ax", "ay", "az"),
        t=(pd.Timestamp("2024-05-01T10:00:00") + pd.to_timedelta(np.round(s["t"] * 1e3), unit="ms")).strftime(
            "%Y-%m-%dT%H:%M:%S.%f")), p)),
    Variant("semicolon_decimal_comma", "Zeit;acc X;acc Y;acc Z with 9,81 (German Excel)", _semicolon_decimal_comma),
    Variant("tab_separated", "tab-separated t ax ay az", lambda p, s: _csv(_frame(s), p, sep="\t")),
    Variant("whitespace_no_header", "IMU-TK style: t x y z, spaces, no header", _whitespace_no_header),
    Variant("comment_lines", "# and % comment lines above the header", _comments),
    Variant("gzip", "the canonical CSV gzip-compressed (.csv.gz)", _gzip),
    Variant("excel_bom_crlf", "Time, AccX... with a UTF-8 BOM and CRLF", _excel_bom_crlf),
    Variant("extra_columns", "gyro (constant: --no-gyro), magnetometer, temperature and a text column around acc_*",
            _extra_columns, args=("--no-gyro",)),
    Variant("constant_gyro", "gyro columns that never move", _extra_columns, "refused", "--no-gyro"),
    Variant("raw_counts", "int16 counts (16384/g, offsets), t in s", _raw_counts, unit="counts"),
    Variant("no_initial_rest", "first 3 s handled (shaking) before the first rest", _no_initial_rest),
    Variant("ros_rostopic_csv", "rostopic echo -p sensor_msgs/Imu (%time in ns)", _ros),
    Variant("metadata_lines", "Device/Serial/Sample rate lines above the header", _metadata_lines),
    Variant("missing_column", "az column absent", _missing_column, "refused", "no column for az"),
    Variant("two_candidates", "acc_x and accel_x both present", _two_candidates, "refused", "--columns ax="),
    Variant("two_columns", "time and one acceleration column", _two_columns, "refused", "three acceleration columns"),
    Variant("coarse_timestamps", "100 Hz data stamped by a 20 ms clock", _repeated_ms, "refused", "--rate"),
    Variant("nan_value", "a NaN (written empty) in ay", _nan, "refused", "empty field at line"),
    Variant("truncated", "file cut in the middle of the last line", _truncated, "refused", "line"),
    Variant("xlsx", "an Excel workbook renamed .csv", _xlsx, "refused", "Excel"),
    Variant("empty", "an empty file", lambda p, s: _text(p, ""), "refused", "empty file"),
    Variant("never_rests", "the sensor turns all the time", _never_rests, "refused", "never"),
    Variant("bias_only_on_counts", "raw counts with --method bias-lls", _raw_counts, "refused", "raw counts",
            args=("--method", "bias-lls")),
)


def run_variant(v: Variant, s: dict, folder: Path) -> dict:
    """Write variant ``v`` of session ``s`` into ``folder`` and run ``accelcal calibrate`` on it (in-process)."""

    suffix = ".csv.gz" if v.name == "gzip" else ".csv"
    path = v.write(folder / f"{v.name}{suffix}", s)
    out = folder / f"{v.name}.json"
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        code = cli.main(["calibrate", str(path), "--g", str(G0), "--out", str(out), *v.args])
    text = err.getvalue()
    row = {"variant": v.name, "description": v.description, "expect": v.expect, "exit": code,
           "outcome": "read" if code == 0 else "refused", "written": out.exists()}
    if code == 0:
        js = json.loads(out.read_text())
        bias = np.asarray(js["bias"])
        truth = s["bias"] if v.unit == "m/s^2" else COUNTS_OFFSET + s["bias"] / G0 * COUNTS_PER_G
        scale = 1.0 if v.unit == "m/s^2" else COUNTS_PER_G / G0
        row.update(n_poses=js["n_poses"], unit=js["unit"], bias_error_mm_s2=float(np.max(np.abs(bias - truth))) / scale
                   * 1e3, notes="; ".join(js.get("notes", [])),
                   warnings=" | ".join(ln for ln in text.splitlines() if ln.startswith("warning:")),
                   message="")
    else:
        lines = text.strip().splitlines()
        row.update(message=lines[0] if lines else "", one_line=len(lines) == 1, traceback="Traceback" in text)
    return row


def run_variants(folder, seed: int = 11) -> pd.DataFrame:
    """Every variant of :data:`VARIANTS` through the CLI: one row each."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    s = session(seed)
    return pd.DataFrame([run_variant(v, s, folder) for v in VARIANTS])


def main(argv=None) -> int:

    argv = sys.argv[1:] if argv is None else argv
    with tempfile.TemporaryDirectory() as tmp:
        df = run_variants(argv[0] if argv else tmp)
    print("| variant | file | outcome | poses | bias error [mm/s²] | message / notes |")
    print("|---|---|---|---|---|---|")
    for r in df.itertuples():
        if r.outcome == "read":
            msg = (r.warnings + " " if r.warnings else "") + r.notes
            print(f"| {r.variant} | {r.description} | read | {r.n_poses} | {r.bias_error_mm_s2:.2f} | {msg} |")
        else:
            print(f"| {r.variant} | {r.description} | refused (exit {r.exit}) | | | {r.message} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
