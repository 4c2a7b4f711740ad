"""MATLAB ``.mat`` files (the ``mat`` format): a numeric variable as the recording.

Version 5 files (MATLAB's default up to ``-v7``, and SciPy's ``savemat``) are read by
:func:`scipy.io.loadmat`.  A numeric matrix is read as a table without header (its
columns numbered: :mod:`.variables`); a struct whose fields are vectors and n x 3
triads of one length is read as a table whose header is the field names (a triad
``acc`` gives ``acc_x, acc_y, acc_z``); column vectors of one length saved side by side
(MATLAB's import of a spreadsheet: ``t, AccX, AccY, AccZ``) are the variable
:data:`VECTORS`, a table headed by their names.  Version 7.3 files are HDF5, which
needs h5py (not in accelcal's environment): they are refused in one line saying how to
save a version 5 file instead.  IMU-TK's ``.mat`` files are ASCII tables despite the
name: the sniff goes by the MAT-file header, so they stay tables.
"""

from __future__ import annotations

import numpy as np

from ..errors import RecordingError
from .variables import Variable, choose, describe, read_variables, usable

#: The start of a MAT-file's 116-byte text header; the version and endian marks at bytes 124-127.
HEADER = b"MATLAB "
VERSIONS = {b"\x00\x01IM": 5, b"\x01\x00MI": 5, b"\x00\x02IM": 7.3, b"\x02\x00MI": 7.3}
#: The name of the table made of a file's column vectors of one length.
VECTORS = "vectors"


def sniff(path, head: bytes) -> bool:
    """A MAT-file header (v5 or v7.3)."""
    return head.startswith(HEADER) and head[124:128] in VERSIONS


def read_mat(path, *, variable: str | None = None, columns=None, unit=None, time_unit=None, rate=None,
             gyro_unit=None):
    """Read a ``.mat`` file's recording (module docstring); ``variable`` chooses it
    (several, comma-separated: runs of one session)."""
    with open(path, "rb") as fh:
        head = fh.read(128)
    if VERSIONS.get(head[124:128]) == 7.3:
        raise RecordingError(f"{path}: a MATLAB v7.3 (HDF5) file, which needs h5py (not installed with accelcal): "
                             "save it as version 7 in MATLAB, save(FILE, VARS, '-v7'), and read that")
    import scipy.io

    try:
        content = scipy.io.loadmat(path, squeeze_me=False, chars_as_strings=True)
    except Exception as e:  # a damaged file can fail anywhere inside the parser
        raise RecordingError(f"{path}: not a readable MATLAB v5 file ({type(e).__name__}: {str(e)[:80]}): the file "
                             "is damaged or not a .mat; copy or save it again") from None
    found, matrices = {}, {}
    for name, value in content.items():
        if name.startswith("__"):
            continue
        v = _variable(name, value)
        if isinstance(v, Variable):
            matrices[name] = v
            found[name] = describe(v.block.shape, "values" if v.names is None else f"columns {', '.join(v.names)}"[:80])
        else:
            found[name] = v
    table = _vectors({k: v for k, v in content.items() if not k.startswith("__") and k not in matrices})
    if table is not None and VECTORS not in found:
        matrices[VECTORS] = table
        found[VECTORS] = describe(table.block.shape, f"columns {', '.join(table.names)}"[:80])
    chosen = choose(path, found, variable, "MATLAB file")
    return read_variables(path, [matrices[n] for n in chosen], columns=columns, unit=unit, time_unit=time_unit,
                          rate=rate, gyro_unit=gyro_unit)


def _variable(name: str, value) -> Variable | str:
    """The variable as a :class:`Variable`, or ``'(why not)'``."""
    a = np.asarray(value)
    if a.dtype.names is not None:
        return _struct(name, a)
    if a.dtype.kind not in "biuf":
        return f"({describe(a.shape, _kind(a))})"
    if not usable(a.shape):
        return f"({describe(a.shape, a.dtype.name)})"
    return Variable(name, a.astype(float))


def _columns(items) -> dict[str, np.ndarray]:
    """``{column name: values}`` of named numeric vectors (n x 1, 1 x n) and triads (n x 3)."""
    cols = {}
    for name, value in items:
        v = np.asarray(value)
        if v.dtype.kind not in "biuf" or v.ndim != 2 or v.size == 0:
            continue
        if 1 in v.shape:
            cols[name] = v.reshape(-1).astype(float)
        elif v.shape[1] == 3 and v.shape[0] > 3:
            cols.update({f"{name}_{a}": v[:, j].astype(float) for j, a in enumerate("xyz")})
    return cols


def _struct(name: str, a: np.ndarray) -> Variable | str:
    """A 1x1 struct of numeric vectors and triads of one length: a table with the field names as header."""
    if a.size != 1:
        return f"({describe(a.shape, 'struct array')})"
    rec = a.reshape(-1)[0]
    cols = _columns((field, rec[field]) for field in a.dtype.names)
    lengths = {len(v) for v in cols.values()}
    if len(cols) < 3 or len(lengths) != 1 or not usable((lengths.pop(), len(cols))):
        return f"(struct of {len(a.dtype.names)} fields, not 3 or more numeric columns of one length)"
    return Variable(name, np.column_stack(list(cols.values())), tuple(cols))


def _vectors(content: dict) -> Variable | None:
    """The file's column vectors of the most common length, side by side, if 3 or more."""
    cols = {k: v for k, v in _columns((k, v) for k, v in content.items()
                                       if np.asarray(v).dtype.names is None and 1 in np.shape(v)).items()}
    if not cols:
        return None
    lengths = [len(v) for v in cols.values()]
    n = max(set(lengths), key=lengths.count)
    same = {k: v for k, v in cols.items() if len(v) == n}
    if len(same) < 3 or not usable((n, len(same))):
        return None
    return Variable(VECTORS, np.column_stack(list(same.values())), tuple(same))


def _kind(a: np.ndarray) -> str:
    return {"U": "char", "S": "char", "O": "cell", "c": "complex", "?": "logical"}.get(a.dtype.kind, a.dtype.name)


__all__ = ["read_mat", "sniff"]
