"""MATLAB ``.mat`` files (the ``mat`` format): a numeric variable as the recording.

Version 5 files (MATLAB's default up to ``-v7``, and SciPy's ``savemat``) are read by
:func:`scipy.io.loadmat`.  A numeric matrix is read as a table without header (its
columns numbered: :mod:`.variables`); a struct whose fields are vectors and n x 3
triads of one length is read as a table whose header is the field names (a triad
``acc`` gives ``acc_x, acc_y, acc_z``); column vectors of one length saved side by side
(MATLAB's import of a spreadsheet: ``t, AccX, AccY, AccZ``) are the variable
:data:`VECTORS`, a table headed by their names.  Version 7.3 files (``save(FILE, '-v7.3')``,
MATLAB's only form above 2 GB) are HDF5, read through h5py (the ``mat73`` extra) into the
same variables: each dataset's ``MATLAB_class`` attribute says what it is (numeric,
``char``, ``logical``, ``cell``; a group is a ``struct``), and its dimensions are MATLAB's
reversed (HDF5 is row-major, MATLAB column-major), so each array is transposed back.  IMU-TK's ``.mat`` files are ASCII tables despite the
name: the sniff goes by the MAT-file header, so they stay tables.
"""

from __future__ import annotations

import io

import numpy as np

from ..errors import RecordingError
from .mat_v5 import check_v5
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
    content = _load_v73(path) if VERSIONS.get(head[124:128]) == 7.3 else _load_v5(path)
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


def _load_v5(path) -> dict:
    import scipy.io  # ~0.3 s: only when a .mat is read

    with open(path, "rb") as fh:
        data = fh.read()
    try:
        check_v5(data)  # SciPy's parser can crash the process on a damaged layout (mat_v5's docstring)
        return scipy.io.loadmat(io.BytesIO(data), squeeze_me=False, chars_as_strings=True)
    except Exception as e:  # a damaged file can fail anywhere inside the parser
        raise RecordingError(f"{path}: not a readable MATLAB v5 file ({type(e).__name__}: {str(e)[:80]}): the file "
                             "is damaged or not a .mat; copy or save it again") from None


def _load_v73(path) -> dict:
    """``{name: array}`` of a v7.3 (HDF5) file, shaped and typed as :func:`scipy.io.loadmat` gives a v5 file's."""
    try:
        import h5py  # the mat73 extra
    except ImportError:
        raise RecordingError(f"{path}: a MATLAB v7.3 (HDF5) file needs h5py: pip install 'accelcal[mat73]', or save "
                             "it as version 7 in MATLAB, save(FILE, VARS, '-v7'), and read that") from None
    try:
        with h5py.File(path, "r") as f:
            return {name: _h5_value(f[name], h5py) for name in f if not name.startswith("#")}
    except Exception as e:  # h5py raises OSError, KeyError, ValueError... on a damaged file
        raise RecordingError(f"{path}: not a readable MATLAB v7.3 file ({type(e).__name__}: {str(e)[:80]}): the file "
                             "is damaged or not a .mat; copy or save it again") from None


def _h5_value(obj, h5py) -> np.ndarray:
    """One v7.3 variable (or struct field) as :func:`scipy.io.loadmat` would give it."""
    cls = obj.attrs.get("MATLAB_class", b"")
    cls = cls.decode() if isinstance(cls, bytes) else str(cls)
    if isinstance(obj, h5py.Group):
        fields = [k for k in obj if isinstance(obj[k], h5py.Dataset)]
        out = np.empty((1, 1), dtype=[(k, object) for k in fields] or [("empty", object)])
        for k in fields:
            out[0, 0][k] = _h5_value(obj[k], h5py)
        return out
    if obj.attrs.get("MATLAB_empty", 0):
        return np.zeros((0, 0))
    if cls == "char":
        return np.array(["".join(map(chr, np.asarray(obj[()]).T.reshape(-1)))])
    if cls in ("cell", "function_handle") or obj.dtype.kind in "OV":  # references, complex pairs: described only
        return np.empty(obj.shape[::-1], dtype=complex if obj.dtype.names == ("real", "imag") else object)
    a = np.asarray(obj[()]).T  # MATLAB's dimensions, reversed by HDF5
    return a.astype(bool) if cls == "logical" else a


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
