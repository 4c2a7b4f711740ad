"""Test-only hook: hold a workflow job at the rename of one of its outputs until the test
lets it go, so that a test can interrupt (kill, Ctrl-C, scancel, time limit) a job that is
certainly running, whatever the machine's load.

Python imports ``sitecustomize`` at start-up from the first folder of ``sys.path`` that has
one; a test puts this folder first on PYTHONPATH for the run it wants to hold, so that the
Snakemake process and every job script it starts (also inside SLURM jobs, which inherit the
environment) load this file.  Nothing in the project imports it, and without
``ACCELCAL_TEST_HOLD_FIFO`` it does nothing.

With ``ACCELCAL_TEST_HOLD_FIFO`` (a named pipe) and ``ACCELCAL_TEST_HOLD_OUTPUT`` (a glob
matched against the absolute path of the file being renamed) set, :func:`os.replace` onto a
matching path first reads the pipe to its end.  The job thus stops where an atomic writer
(``accelcal.atomic.atomic_output``) has written its temporary file whole and not yet
renamed it; the test sees the waiting reader (opening the pipe's write end without blocking
succeeds only while a reader waits) and interrupts the run, or writes and closes the pipe to
let the job finish.
"""

import os

_FIFO = os.environ.get("ACCELCAL_TEST_HOLD_FIFO")
_PATTERN = os.environ.get("ACCELCAL_TEST_HOLD_OUTPUT")

if _FIFO and _PATTERN:
    import fnmatch

    _replace = os.replace

    def _held_replace(src, dst, *args, **kwargs):
        if fnmatch.fnmatch(os.path.abspath(os.fspath(dst)), _PATTERN):
            with open(_FIFO, "rb") as pipe:  # blocks until the test opens the write end
                pipe.read()  # and until it closes it
        return _replace(src, dst, *args, **kwargs)

    os.replace = _held_replace
