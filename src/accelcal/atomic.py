"""Atomic file output: a file is either whole or not there at all.

Every writer of a result (tables, figures, JSON, the report, downloads) writes through
:func:`atomic_output`: the data goes to a hidden temporary file beside the target, which
is renamed onto the target only when the writer finished without an exception.  A rename
within one folder is atomic on POSIX, so readers (and Snakemake) see the old file or the
new one, never half of one.

A writer killed by SIGKILL runs no clean-up and leaves its temporary file behind; the
next write of the same target removes it (:func:`remove_stale_temporaries`).
"""

from __future__ import annotations

import glob
import hashlib
import json
import os
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path


def remove_stale_temporaries(path: str | os.PathLike, suffix: str = ".tmp") -> None:
    """Delete the temporary files ``.<name>.<random><suffix>`` of the target ``path``.

    They are what :func:`atomic_output` leaves when its writer is killed mid-write
    (SIGKILL skips every clean-up).  Temporary files of other targets in the same folder
    are left alone.

    Parameters
    ----------
    path : str or os.PathLike
        The target whose leftover temporary files are removed.
    suffix : str, default ".tmp"
        Suffix of the temporary files, as given to :func:`atomic_output`.
    """
    path = Path(path)
    prefix = f".{path.name}."
    # Snakemake runs one job per output at a time, so a temporary file of this target
    # cannot belong to a live writer: it is a killed writer's leftover.
    for stale in path.parent.glob(f"{glob.escape(prefix)}*{glob.escape(suffix)}"):
        # mkstemp's random part has no dot; with one, the file is the temporary of another
        # target whose name starts with this one's (``table.csv.gz`` beside ``table.csv``),
        # whose writer may be running now
        if "." not in stale.name[len(prefix):len(stale.name) - len(suffix)]:
            stale.unlink(missing_ok=True)


def _umask() -> int:
    # os.umask is the only portable way to read the mask, and it sets it at the same time
    mask = os.umask(0)
    os.umask(mask)
    return mask


@contextmanager
def atomic_output(path: str | os.PathLike, suffix: str = ".tmp") -> Iterator[Path]:
    """Write ``path`` whole or not at all: yield a temporary path to write, then rename it.

    Creates the parent folder, removes a killed writer's leftover temporary files of the
    same target (:func:`remove_stale_temporaries`) and yields the path of a new, empty,
    closed temporary file ``.<name>.<random><suffix>`` in the target's folder.  When the
    ``with`` block ends normally, the file gets the permissions of a normally created file
    (``0o666`` minus the umask: :func:`tempfile.mkstemp` makes it private, and outputs are
    for reading) and is renamed onto ``path``.  When the block raises (any exception,
    including KeyboardInterrupt), the temporary file is deleted, ``path`` is left as it
    was, and the exception propagates.

    Parameters
    ----------
    path : str or os.PathLike
        The file to write.
    suffix : str, default ".tmp"
        Suffix of the temporary file (e.g. ``".part"`` for downloads).

    Yields
    ------
    pathlib.Path
        The temporary file to write (open it yourself, by name).

    Examples
    --------
    >>> with atomic_output("out/table.csv") as tmp:  # doctest: +SKIP
    ...     df.to_csv(tmp, index=False)
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    remove_stale_temporaries(path, suffix)
    fd, name = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=suffix)
    os.close(fd)
    tmp = Path(name)
    try:
        yield tmp
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


__all__ = ["atomic_output", "remove_stale_temporaries"]


def write_json_atomic(path, obj) -> None:
    """Write JSON to ``path`` via a temporary file and a rename."""
    with atomic_output(path) as tmp, open(tmp, "w") as f:
        json.dump(obj, f, indent=2)
        f.write("\n")


def sha256_file(path) -> str:
    """Hex sha256 of a file, read in chunks."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 16), b""):
            h.update(block)
    return h.hexdigest()
