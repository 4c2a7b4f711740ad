"""The MATLAB v5 layout check (accelcal.formats.mat_v5): SciPy's reader crashes the
process on some damaged files; the check refuses those and lets real files through."""

from __future__ import annotations

import io
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
import scipy.io
import scipy.sparse

from accelcal.formats.mat_v5 import DamagedMat, check_v5

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"


def _saved(obj: dict, **kw) -> bytes:
    b = io.BytesIO()
    scipy.io.savemat(b, obj, **kw)
    return b.getvalue()


def _variants():
    rng = np.random.default_rng(0)
    every = {"a": rng.normal(size=(50, 4)), "i": np.arange(7, dtype=np.int16), "c": rng.normal(size=3) + 1j,
             "s": "hello", "u": "ünï", "l": np.array([True, False]), "e": np.zeros((0, 3)),
             "cell": np.array([[1.0], "x", np.zeros(3)], dtype=object), "sp": scipy.sparse.random(5, 6, 0.3, random_state=1),
             "st": {"f": np.ones(3), "g": "ab", "h": {"k": 2}}, "big": np.array([1, 2, 300], np.uint32)}
    for compressed in (False, True):
        for oned in ("row", "column"):
            yield _saved(every, do_compression=compressed, oned_as=oned)


def _real_v5_files():
    return [p for p in sorted(DATA.glob("**/*.mat")) if p.read_bytes()[124:128] in (b"\x00\x01IM", b"\x01\x00MI")]


def test_what_scipy_writes_and_the_shared_recordings_pass():
    variants, real = list(_variants()), _real_v5_files()
    for data in variants:
        check_v5(data)  # raises DamagedMat on a layout it refuses
    for path in real:
        check_v5(path.read_bytes())
    assert len(variants) == 4
    assert len(real) == 3 or not DATA.is_dir(), [p.name for p in real]  # the CTU Ferraris session's three files


FLAGS_TAG = bytes.fromhex("0600000008000000")  # an array flags element's tag (little-endian)


def _struct_file() -> tuple[bytes, int]:
    """A file of one struct of two 4-value fields, and where its first field's flags tag starts."""
    data = _saved({"imu": {"t": np.arange(4.0), "x": np.arange(4.0)}})
    return data, data.index(FLAGS_TAG, data.index(FLAGS_TAG) + 1)


def _damaged():
    data, field = _struct_file()
    complex_flag = bytearray(data)
    complex_flag[field + 9] |= 0x08  # a field marked complex with no imaginary part: SciPy reads past it
    unknown = bytearray(data)
    real_part = data.index(b"\x09\x00\x00\x00\x20\x00\x00\x00", field)  # the field's 4 doubles' tag
    unknown[real_part] = 8  # data type 8 names no type: SciPy indexes an empty slot of its type table
    return {"complex flag without an imaginary part": bytes(complex_flag), "unknown data type": bytes(unknown),
            "cut inside an element": data[:-9],
            "negative dimension": data[:field + 24] + b"\xff\xff\xff\xff" + data[field + 28:]}


@pytest.mark.parametrize("case", list(_damaged()))
def test_damaged_layouts_are_refused(case):
    with pytest.raises(DamagedMat):
        check_v5(_damaged()[case])


def test_the_reader_refuses_in_one_line_where_scipy_alone_crashes(tmp_path):
    """Both damaged files kill a process that hands them to SciPy 1.17.1's ``loadmat``
    (segmentation fault, measured); the reader refuses them with a RecordingError instead."""
    paths = []
    for i, case in enumerate(["complex flag without an imaginary part", "unknown data type"]):
        paths.append(tmp_path / f"d{i}.mat")
        paths[-1].write_bytes(_damaged()[case])
    probe = textwrap.dedent("""
        import sys
        from accelcal.errors import RecordingError
        from accelcal.formats import read
        for p in sys.argv[1:]:
            try:
                read(p, format="mat")
            except RecordingError as e:
                print("refused:", str(e).splitlines()[0])
    """)
    out = subprocess.run([sys.executable, "-c", probe, *map(str, paths)], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr[-400:]
    assert out.stdout.count("refused:") == 2 and "not a readable MATLAB v5 file" in out.stdout
