"""Compile the installed packages to bytecode, skipping the files no process of the project imports.

Run by tools/setup.sh with the environment's own interpreter, after the lock is installed
(uv and pip are told not to compile): ``.venv/bin/python tools/bytecode.py``.

Why compile at all: where ``PYTHONDONTWRITEBYTECODE`` is set (this machine, some CI
runners) a module without its ``.pyc`` is compiled again by every process that imports it,
and the workflow and the tests start hundreds of processes (measured: importing the
workflow scripts' stack takes 5.4 s of CPU per process without bytecode).

Why not everything: uv's ``--compile-bytecode`` compiled all 8,377 files (186 MB) of
site-packages, most of the install's time, and 2,568 of them (80 MB) are files no process
imports.  Recorded with ``tools/import_audit.py`` over the whole test suite (its run of the
workflow on config/ci.yaml included; 319 processes, 2,908 site-packages files imported):
none of the files skipped here was imported, and no module was compiled for want of its
``.pyc``.  (Compiled at import all the same: pytest's assertion rewriting of its plugins'
modules and of scipy's two ``*_test.py`` modules, which no plain ``.pyc`` serves, and the
configuration files cv2 execs; measured, they cost a pytest start < 0.05 s.)

- the packages' own test suites, folders named ``tests`` or ``test`` (41 MB, 2,530 files).
  Folders named ``testing`` are kept: they are libraries other code imports
  (``numpy.testing`` in our tests, ``matplotlib.testing``, ...);
- pymavlink's generated MAVLink dialects (39 MB in 38 files) other than ``all``, the one
  ``pymavlink.mavutil`` imports (``MAVLINK_DIALECT`` defaults to ``all``; the DataFlash
  reader never selects another).  A process that selects another dialect still works: it
  compiles that one module when it imports it.

The rule is by kind of file, not a list of modules, so a new dependency is compiled
without anyone editing this file (the run imported 64 of the 106 MB compiled: a list of
the modules imported would compile less, and would leave a new import uncompiled).
``tests/test_bytecode.py`` keeps it: every installed module the library, the workflow and
the tests import is imported with ``PYTHONDONTWRITEBYTECODE`` set, and none may be a file
this rule skips or be compiled from source.
"""

import compileall
import re
import sys
import sysconfig

#: Installed files not compiled (matched against the whole path, as compileall's ``-x``).
SKIP = re.compile(
    r"[/\\]tests?[/\\]"
    r"|[/\\]pymavlink[/\\]dialects[/\\]v\d+[/\\](?!(all|__init__)\.py$)"
)


def site_dirs():
    """The environment's package folders (one on most platforms, two where lib64 differs)."""
    return sorted({sysconfig.get_path("purelib"), sysconfig.get_path("platlib")})


def main():
    # quiet=2: a few packages ship files that are not valid Python on purpose (templates,
    # Python 2 examples); pip and uv skip those silently too, and an import of one would
    # fail with or without bytecode.
    for folder in site_dirs():
        compileall.compile_dir(folder, quiet=2, rx=SKIP, workers=0)


if __name__ == "__main__":
    sys.exit(main())
