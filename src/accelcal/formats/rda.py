"""R data files (the ``rda`` format): ``save()``'s ``.rda``/``.RData`` and ``saveRDS()``'s
``.rds``, read by the ``rdata`` package (the optional ``rdata`` extra).

A numeric matrix is read as a table whose header is its column names (``dimnames``; none:
numbered as a headerless table's), a data frame as a table of its numeric columns
(:mod:`.variables`).  The ``freq`` attribute of an ``imu`` object (SMAC-Group's
``imudata``, e.g. the ADIS16405 record) is the sampling rate, used when the matrix has no
time column.  Files are gzip, bzip2 or xz compressed or not; the sniff undoes the
compression of the file's first bytes and looks for R's serialisation header.
"""

from __future__ import annotations

import bz2
import lzma
import warnings
import zlib
from pathlib import Path

import numpy as np

from ..errors import RecordingError
from .variables import Variable, choose, describe, read_variables, usable

#: The header of ``save()`` (XDR, ASCII, native binary; versions 2 and 3) and of ``saveRDS()``.
RDA_MAGIC = (b"RDX2\n", b"RDX3\n", b"RDA2\n", b"RDA3\n", b"RDB2\n", b"RDB3\n")
RDS_MAGIC = (b"X\n\x00\x00\x00\x02", b"X\n\x00\x00\x00\x03", b"A\n2\n", b"A\n3\n")


def _head(head: bytes) -> bytes:
    """The first bytes of the file, their compression undone (as far as they go)."""
    try:
        if head[:2] == b"\x1f\x8b":
            return zlib.decompressobj(16 + zlib.MAX_WBITS).decompress(head, 64)
        if head[:6] == b"\xfd7zXZ\x00":
            return lzma.LZMADecompressor().decompress(head, 64)
        if head[:3] == b"BZh":
            return bz2.BZ2Decompressor().decompress(head)[:64]
    except (zlib.error, lzma.LZMAError, OSError, EOFError, ValueError):
        return b""
    return head[:64]


def sniff(path, head: bytes) -> bool:
    """R's serialisation header after the compression (module docstring)."""
    h = _head(head)
    return h.startswith(RDA_MAGIC) or h.startswith(RDS_MAGIC)


def read_rda(path, *, variable: str | None = None, columns=None, unit=None, time_unit=None, rate=None,
             gyro_unit=None):
    """Read an R data file's recording (module docstring); ``variable`` chooses it."""
    import rdata

    path = Path(path)
    with open(path, "rb") as fh:
        single = _head(fh.read(65536)).startswith(RDS_MAGIC)
    try:
        parsed = rdata.parser.parse_file(path)
        with warnings.catch_warnings():  # classes without a Python constructor (imudata's "imu") fall back to matrix
            warnings.simplefilter("ignore")
            content = rdata.conversion.convert(parsed)
    except Exception as e:  # a damaged file can fail anywhere inside the parser
        raise RecordingError(f"{path}: not a readable R data file ({type(e).__name__}: {str(e)[:80]}): the file is "
                             "damaged or not from R's save()/saveRDS(); copy or save it again") from None
    if single:
        content = {path.stem: content}
        attrs = {path.stem: _attributes(parsed.object)}
    else:
        attrs = _top_attributes(parsed.object)
    if not isinstance(content, dict):
        raise RecordingError(f"{path}: an R data file without named variables; save the recording with save()")
    found, matrices = {}, {}
    for name, value in content.items():
        v = _variable(str(name), value, attrs.get(str(name), {}))
        if isinstance(v, Variable):
            matrices[str(name)] = v
            found[str(name)] = describe(v.block.shape, "values" if v.names is None else
                                        f"columns {', '.join(v.names)}"[:80])
        else:
            found[str(name)] = v
    chosen = choose(path, found, variable, "R data file")
    return read_variables(path, [matrices[n] for n in chosen], columns=columns, unit=unit, time_unit=time_unit,
                          rate=rate, gyro_unit=gyro_unit)


def _variable(name: str, value, attrs: dict) -> Variable | str:
    """A matrix (numpy or xarray), or a data frame of numeric columns, as a :class:`Variable`."""
    import pandas as pd

    names = None
    if isinstance(value, pd.DataFrame):
        numeric = [c for c in value.columns if pd.api.types.is_numeric_dtype(value[c])
                   and not pd.api.types.is_bool_dtype(value[c])]
        if len(numeric) < 3:
            return f"(data frame of {value.shape[1]} columns, fewer than 3 numeric)"
        a, names = value[numeric].to_numpy(dtype=float), tuple(str(c) for c in numeric)
    elif hasattr(value, "dims") and hasattr(value, "values"):  # an xarray DataArray: a matrix with dimnames
        a = np.asarray(value.values)
        if a.ndim == 2 and value.dims[1] in value.coords:
            names = tuple(str(c) for c in np.asarray(value.coords[value.dims[1]].values))
    else:
        a = np.asarray(value) if isinstance(value, np.ndarray) else None
        if a is None:
            return f"({type(value).__name__})"
    if a.dtype.kind not in "biuf":
        return f"({describe(a.shape, a.dtype.name)})"
    if not usable(a.shape):
        return f"({describe(a.shape, a.dtype.name)})"
    freq = attrs.get("freq")
    rate, rate_from = None, ""
    if freq is not None and np.size(freq) == 1 and np.isfinite(float(np.ravel(freq)[0])) and float(
            np.ravel(freq)[0]) > 0:
        rate, rate_from = float(np.ravel(freq)[0]), f"the freq attribute of {name}"
    return Variable(name, a.astype(float), names, rate, rate_from)


def _pairlist(obj) -> dict:
    """``{tag: RObject}`` of an R pairlist (attributes, or the variables of ``save()``)."""
    out, node = {}, obj
    while node is not None and getattr(node, "tag", None) is not None and isinstance(node.value, (tuple, list)) \
            and len(node.value) == 2:
        tag = node.tag
        while getattr(tag, "value", None) is not None and not isinstance(tag.value, (bytes, str)):
            tag = tag.value  # SYM -> CHAR
        key = tag.value.decode("utf-8", "replace") if isinstance(tag.value, bytes) else str(tag.value)
        out[key] = node.value[0]
        node = node.value[1]
    return out


def _attributes(obj) -> dict:
    """The numeric attributes of an R object (``freq``, ...) as arrays."""
    attrs = {}
    for key, value in _pairlist(getattr(obj, "attributes", None)).items():
        if isinstance(getattr(value, "value", None), np.ndarray) and value.value.dtype.kind in "biuf":
            attrs[key] = value.value
    return attrs


def _top_attributes(obj) -> dict:
    """``{variable: attributes}`` of a ``save()`` file."""
    return {name: _attributes(value) for name, value in _pairlist(obj).items()}


__all__ = ["read_rda", "sniff"]
