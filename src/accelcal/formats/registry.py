"""The one registry of recording file formats: how each is recognised, read and written.

Everything that chooses or describes a format reads it from here: :func:`accelcal.formats.read`
(``format=`` and detection), the CLI (``--format`` choices and the formats in its help)
and the conformance tests.  Functions are named by ``module:function`` and imported on
first use, so that reading the registry (``accelcal --help``) imports no numerical
library, and a format that needs an optional package costs nothing until it is read.

Detection (``format='auto'``): binary formats are sniffed first, on the path and the
file's first bytes, before anything reads the file as text; then the text is loaded
(gzip undone, decoded) and the text formats are sniffed on its first characters, in the
table's order (the more specific first): the first that recognises the file reads it,
and a text file that none recognises is a table (:data:`FALLBACK`).

Adding a format: a module in this package with ``sniff(path, head) -> bool`` and a
reader returning a :class:`~accelcal.recording.Recording`, and one entry below
(``tests/test_format_conformance.py`` then checks it, with a sample file of it).
A format that needs an optional package names its extra and the modules it installs;
its module imports them inside the reader only, so that sniffing works without them and
reading without them is one line: ``... pip install accelcal[ros]``.
"""

from __future__ import annotations

import importlib.util
import textwrap
from dataclasses import dataclass

from ..errors import MissingExtraError, RecordingError
from ..registry import resolve

#: The reading options (of :func:`accelcal.formats.read`) a reader may take itself.  One it
#: does not take is applied by the dispatcher: ``unit`` converts or checks the values,
#: ``rate`` replaces the time by sample index / rate, ``time_unit``, ``gyro_unit``, ``mag_unit``
#: and ``clock`` are ignored with a note, ``columns`` and the log options are refused.
TABLE_OPTIONS = ("columns", "unit", "time_unit", "rate", "gyro_unit", "mag_unit", "clock")
#: The option of files of named variables (MATLAB, R): which variable is the recording
#: (several, comma-separated: runs of one session).
VARIABLE_OPTIONS = ("variable",)
#: The options of logs, which hold several sensors and two clocks: the IMU topic, the
#: sensor instance, and whose time stamps (``'header'``: the sensor's, ``'log'``: the log's).
LOG_OPTIONS = ("topic", "instance", "time_source")
#: The options of a log's magnetometer: its topic (ROS ``sensor_msgs/MagneticField``) or its instance
#: (PX4 ``sensor_mag`` multi_id, DataFlash ``MAG`` ``I``) when several are logged.
MAG_LOG_OPTIONS = ("mag_topic", "mag_instance")
#: The values of ``time_source``.
TIME_SOURCES = ("header", "log")
#: Whether the recording keeps its time column as written (``time_column=False``: not, which
#: the dispatcher applies to any format; a table's is cut from the file's text, so its reader,
#: told so, lets the text go before the clock fit: 47 MB of a 10⁶-row CSV at the reading's peak).
KEEP_OPTIONS = ("time_column",)
READING_OPTIONS = TABLE_OPTIONS + VARIABLE_OPTIONS + LOG_OPTIONS + MAG_LOG_OPTIONS + KEEP_OPTIONS
#: The command-line option of each reading option, for messages.
OPTION_FLAGS = {"columns": "--columns", "unit": "--unit", "time_unit": "--time-unit", "rate": "--rate",
                "gyro_unit": "--gyro-unit", "mag_unit": "--mag-unit", "topic": "--topic", "instance": "--instance",
                "time_source": "--time-source", "clock": "--clock", "variable": "--variable",
                "mag_topic": "--mag-topic", "mag_instance": "--mag-instance"}
#: Characters of the decoded text that text formats are sniffed on.
TEXT_HEAD_CHARS = 8192
#: Bytes of the file that binary formats are sniffed on.
BINARY_HEAD_BYTES = 65536


@dataclass(frozen=True, kw_only=True)
class Format:
    """One file format of recordings.

    Attributes
    ----------
    name : str
        The ``format=`` / ``--format`` value.
    title : str
        What the format is, one line for the CLI's help.
    reader : str
        ``'module:function'`` of the reader.  Text formats: ``f(path, text=..., **options)``
        with the decoded text (gzip undone; handed over as ``[text]``, which the reader empties,
        to a reader that takes ``time_column``: it may let the text go before it returns);
        binary formats: ``f(path, **options)``.
        ``options`` are those of :attr:`options` the caller gave (never None).
    sniff : str or None
        ``'module:function'`` of ``f(path, head) -> bool``: whether a file is in this
        format.  ``head`` is the first :data:`TEXT_HEAD_CHARS` characters of the decoded
        text for text formats, the first :data:`BINARY_HEAD_BYTES` bytes of the file
        (b'' for a folder) for binary ones.  None: never detected, read only when named.
    options : tuple of str
        The :data:`READING_OPTIONS` the reader takes itself.
    defines_time : bool
        Whether the file times its samples (time stamps or a stated rate).  A format
        that does not takes ``rate`` (the file's rate comes from the user or a default).
    intervals : bool
        Whether the file can say where the sensor rests (blocks, sections, a pose
        column): known static intervals in :attr:`Recording.intervals`.  Only such
        formats return them.
    text : bool
        Text (read through :func:`accelcal.formats.text.load_text`) or binary (a log the
        reader opens itself; it may be a folder).
    strict_reader : str or None
        ``'module:function'`` of ``f(path) -> Recording`` reading the format's exact
        layout, nothing guessed (``read(..., strict=True)``).
    writer : str or None
        ``'module:function'`` of ``f(path, rec)`` writing what :attr:`strict_reader`
        reads back exactly.
    extra : str or None
        The optional extra the reader needs (``pip install accelcal[extra]``).
    requires : tuple of str
        The top-level modules the extra installs, checked before reading.
    """

    name: str
    title: str
    reader: str
    sniff: str | None = None
    options: tuple[str, ...] = ()
    defines_time: bool = True
    intervals: bool = False
    text: bool = True
    strict_reader: str | None = None
    writer: str | None = None
    extra: str | None = None
    requires: tuple[str, ...] = ()

    def __post_init__(self):
        unknown = set(self.options) - set(READING_OPTIONS)
        if unknown:
            raise ValueError(f"format {self.name}: unknown reading option(s) {sorted(unknown)}")
        if not self.defines_time and "rate" not in self.options:
            raise ValueError(f"format {self.name}: a file that does not time its samples needs a reader taking rate")
        if bool(self.extra) != bool(self.requires):
            raise ValueError(f"format {self.name}: an extra and the modules it installs go together")

    def load_reader(self, path=None):
        """The reader, its optional packages checked first (:meth:`check_extra`; ``path``
        names the file in the message)."""
        self.check_extra(path)
        return resolve(self.reader)

    def load_sniff(self):
        """The sniffing function, or None if the format is never detected."""
        return None if self.sniff is None else resolve(self.sniff)

    def load_strict_reader(self):
        """The strict reader, or None."""
        return None if self.strict_reader is None else resolve(self.strict_reader)

    def load_writer(self):
        """The writer, or None."""
        return None if self.writer is None else resolve(self.writer)

    def check_extra(self, path=None) -> None:
        """One-line :class:`~accelcal.errors.MissingExtraError` (a :class:`RecordingError`) if
        a package of :attr:`extra` is not installed."""
        missing = [m for m in self.requires if importlib.util.find_spec(m) is None]
        if missing:
            where = f"{path}: " if path is not None else ""
            raise MissingExtraError(f"{where}reading {self.name} files needs {', '.join(missing)}, "
                                    f"not installed: pip install accelcal[{self.extra}]")


#: The formats, by name, in the order they are sniffed and listed.
FORMATS: dict[str, Format] = {f.name: f for f in (
    Format(name="block-log", title="serial-monitor log of poses in blocks (FastAhrs FXOS8700); each block is a "
                                   "known rest",
           reader="accelcal.formats.block_log:read_block_log", sniff="accelcal.formats.block_log:sniff",
           intervals=True),
    Format(name="mpu6050", title="tomisuarez2/ImuCalibration's MPU-6050 logger (Fs,100 lines, then ax,ay,az,gx,gy,gz)",
           reader="accelcal.formats.mpu6050:read_mpu6050_csv", sniff="accelcal.formats.mpu6050:sniff"),
    Format(name="imucal", title="imucal session (n_samples, gyr_*, acc_*); no rate in the file: --rate HZ, default "
                                "imucal's example's 102.4 Hz",
           reader="accelcal.formats.imucal:read_imucal_session", sniff="accelcal.formats.imucal:sniff",
           options=("rate",), defines_time=False),
    Format(name="imucal-annotated", title="imucal annotated session (a part column); its static parts are known "
                                          "rests; rate as imucal",
           reader="accelcal.formats.imucal_annotated:read_annotated_session",
           sniff="accelcal.formats.imucal_annotated:sniff", options=("rate",), defines_time=False, intervals=True),
    Format(name="csv", title="any delimited table (see 'input' above)",
           reader="accelcal.formats.table:read_table", options=TABLE_OPTIONS + KEEP_OPTIONS, intervals=True,
           strict_reader="accelcal.formats.canonical:read_canonical",
           writer="accelcal.formats.canonical:write_canonical"),
    Format(name="imutk", title="IMU-TK ASCII (t x y z, e.g. xsens_acc.mat), which csv reads too",
           reader="accelcal.formats.imutk:read_imutk_ascii", options=("clock",)),
    Format(name="ros", title="ROS 1 bag, ROS 2 bag (its folder, metadata.yaml, .db3 or .mcap) or bare .mcap file: "
                             "a sensor_msgs/Imu topic, accelerometer and gyroscope",
           reader="accelcal.formats.ros:read", sniff="accelcal.formats.ros:sniff",
           options=("topic", "time_source", "mag_topic"),
           text=False, extra="ros", requires=("rosbags",)),
    Format(name="px4", title="PX4 ULog: the raw sensor_accel/sensor_gyro when logged, else sensor_combined (already "
                             "calibrated by the autopilot)",
           reader="accelcal.formats.px4:read", sniff="accelcal.formats.px4:sniff",
           options=LOG_OPTIONS + ("mag_instance",), text=False,
           extra="px4", requires=("pyulog",)),
    Format(name="ardupilot", title="ArduPilot DataFlash .bin log: its IMU messages (after ArduPilot's calibration)",
           reader="accelcal.formats.ardupilot:read", sniff="accelcal.formats.ardupilot:sniff",
           options=LOG_OPTIONS + ("mag_instance",), text=False, extra="ardupilot", requires=("pymavlink",)),
    Format(name="mat", title="MATLAB .mat (v5; v7.3 with the mat73 extra, h5py): a numeric matrix, its columns numbered "
                             "as a headerless table's (--columns), or a struct of vectors; --variable NAME chooses "
                             "(NAME,NAME,...: runs of one session)",
           reader="accelcal.formats.mat:read_mat", sniff="accelcal.formats.mat:sniff",
           options=TABLE_OPTIONS + VARIABLE_OPTIONS, text=False),
    Format(name="rda", title="R data (.rda/.RData of save(), .rds of saveRDS()): a numeric matrix by its dimnames "
                             "or a data frame; an imu object's freq times it; --variable NAME chooses",
           reader="accelcal.formats.rda:read_rda", sniff="accelcal.formats.rda:sniff",
           options=TABLE_OPTIONS + VARIABLE_OPTIONS, text=False, extra="rdata", requires=("rdata",)),
)}

#: The format of a text file that no format's sniff recognises.
FALLBACK = "csv"


def format_named(name: str) -> Format:
    """The format called ``name``; one-line :class:`RecordingError` listing the known ones."""
    try:
        return FORMATS[name]
    except (KeyError, TypeError):
        raise RecordingError(f"unknown format {name!r}; known: {', '.join(['auto', *FORMATS])}") from None


def formats_help(width: int = 80) -> str:
    """The formats as help text: a heading, then name, title, and whether auto detects it."""

    sniffed = [f.name for f in FORMATS.values() if f.sniff is not None]
    heading = (f"formats (--format FMT; auto: the first of {', '.join(sniffed)} that recognises the file from "
               f"its first lines, else {FALLBACK}):")
    lines = textwrap.wrap(heading, width, subsequent_indent="  ", break_on_hyphens=False)
    column = max(len(n) for n in FORMATS) + 4
    for f in FORMATS.values():
        text = f.title
        if f.sniff is None and f.name != FALLBACK:
            text += "; read as such only when named"
        if f.extra:
            text += f"; needs pip install accelcal[{f.extra}]"
        lines += textwrap.wrap(text, width, initial_indent=f"  {f.name}".ljust(column), subsequent_indent=" " * column,
                               break_on_hyphens=False)
    return "\n".join(lines)


__all__ = ["BINARY_HEAD_BYTES", "FALLBACK", "FORMATS", "Format", "KEEP_OPTIONS", "LOG_OPTIONS", "MAG_LOG_OPTIONS", "OPTION_FLAGS",
           "READING_OPTIONS",
           "TABLE_OPTIONS", "VARIABLE_OPTIONS", "TEXT_HEAD_CHARS", "TIME_SOURCES", "format_named", "formats_help"]
