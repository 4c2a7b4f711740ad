"""Adding a file format: a sniff, a reader and one registry entry.

The format: a first line ``# xyz-log <rate> Hz``, then one ``x y z`` line per sample in g.
Once registered, ``accelcal.formats.read`` and ``accelcal calibrate`` recognise such a
file by its first line (or take ``--format xyz-log``), and the command-line help lists
it.  In the package the sniff and the reader are one module of ``accelcal/formats/``,
the entry one item of ``FORMATS`` in ``accelcal/formats/registry.py``, and a sample file
of the format one function in ``tests/format_samples.py`` (docs/extending.md).

Run: ``python examples/custom_format.py``.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import numpy as np

from accelcal import cli
from accelcal.errors import RecordingError
from accelcal.formats import FORMATS, Format, detect_format, read
from accelcal.recording import Origin, Recording
from accelcal.simulation import random_directions, simulate_recording
from accelcal.units import G0

MAGIC = "# xyz-log"


def sniff(path: Path, head: str) -> bool:
    """Whether the file starts with the format's first line (``head``: its first characters)."""
    return head.startswith(MAGIC)


def read_xyz_log(path, text: str) -> Recording:
    """The samples of an xyz-log file (``text``: its decoded content), in m/s².

    Row count, finite values and increasing time are not checked here: ``read`` checks them
    for every reader, and the :class:`Origin` (each sample's line) lets its message name the line."""
    lines = text.splitlines()
    rows = [(no, line) for no, line in enumerate(lines[1:], start=2) if line.strip()]
    try:
        rate = float(lines[0].removeprefix(MAGIC).split()[0])
        acc = np.array([[float(v) for v in line.split()] for _, line in rows]) * G0
    except (ValueError, IndexError):
        raise RecordingError(f"{path}: not an xyz-log file (first line '{MAGIC} <rate> Hz', then x y z in g)") \
            from None
    if acc.ndim != 2 or acc.shape[1] != 3 or not rate > 0:
        raise RecordingError(f"{path}: an xyz-log file has three values per line and a positive rate")
    return Recording(np.arange(len(acc)) / rate, acc, None, str(path), unit="m/s^2",
                     notes=(f"xyz-log: {rate:g} Hz, values in g",), origin=Origin("line", numbers=[no for no, _ in rows]))


ENTRY = Format(name="xyz-log", title="xyz-log: '# xyz-log RATE Hz', then x y z per line in g",
               reader=f"{__name__}:read_xyz_log", sniff=f"{__name__}:sniff")


def main(folder: Path) -> int:
    FORMATS[ENTRY.name] = ENTRY
    rng = np.random.default_rng(8)
    rec = simulate_recording(rng, np.vstack([[0, 0, 1.0], random_directions(rng, 19)]), G0, np.eye(3),
                             np.array([0.02, -0.01, 0.03]), noise_std=0.01)
    path = folder / "session.txt"
    with open(path, "w") as f:
        f.write(f"{MAGIC} 100 Hz\n")
        np.savetxt(f, rec["acc"] / G0, fmt="%.7f")

    print(f"detected as {detect_format(path)}; {read(path).n} samples")
    code = cli.main(["calibrate", str(path), "--out", str(folder / "cal.json")])  # the summary names the format
    return code if detect_format(path) == "xyz-log" else 1


if __name__ == "__main__":
    with tempfile.TemporaryDirectory() as tmp:
        sys.exit(main(Path(tmp)))
