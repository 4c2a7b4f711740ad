"""Compiled kernels for the hot loops, and the switch between them and the numpy reference.

The closed forms are a few thousand floating-point operations, the sequential filters a
few hundred per step; in numpy, the per-call overhead (about a microsecond per call,
tens of calls per problem or step) costs far more than the arithmetic.  The kernels
(:mod:`accelcal._lls_kernels`, :mod:`accelcal.batista._filter_kernels`,
:mod:`accelcal.tereshkov._estimator_kernels`, :mod:`accelcal.noise._fast`) are the same algorithms written as
scalar loops and compiled with numba; :mod:`accelcal.formats._parse_kernels` reads a large
numeric table's lines (pandas' C reader where it gives up or numba is absent).

Why numba: it compiles the plain Python/numpy of the reference implementations (the
same language, read and tested side by side), needs no C toolchain at install time
(wheels for every platform numpy supports), caches the machine code on disk, is
maintained by Anaconda/NVIDIA with a release every few months, and is an optional
dependency: without it (``pip install accelcal`` without the ``fast`` extra) the numpy
implementations run, with identical results.

Selection, per process (environment variable ``ACCELCAL_KERNELS``, or :func:`set_backend`):

* ``auto`` (default): with numba installed, the batched estimators and the filters run
  compiled (numba is imported at their first call); the single-problem estimators
  (:func:`~accelcal.full_lls`, :func:`~accelcal.bias_lls`, :func:`~accelcal.full_als`)
  start in numpy and switch to the compiled kernels by themselves (or as soon as some
  kernel module is loaded) once their calls in the process would have saved, compiled,
  numba's start-up (:data:`STARTUP_S`: importing it and loading the kernels from the
  disk cache, about 0.5 s): each call adds the time its compiled form saves
  (:data:`accelcal.lls.SAVES_S`), which makes about 14 000 full LLS, 9 000 ALS or
  57 000 bias-only LLS calls on 24 poses.  A one-off calibration (the command line, a
  bootstrap of a recording) never pays the start-up; a process that keeps solving pays
  it once, in the call that crosses the threshold (the kernels load, or compile if the
  disk cache is empty, in that call's thread), and then runs 4-16 times faster
  (``tools/bench_kernel_crossover.py`` measures the crossover).  The switch depends on
  the calls made, not on a clock, so a process gives the same numbers every time it runs
  (the two paths agree to rounding, not bit for bit);
* ``numba``: every estimator and filter compiled (an :class:`ImportError` if numba is
  missing);
* ``numpy``: the numpy reference implementations only.

Without numba, ``auto`` is ``numpy``.  The two paths give the same numbers to rounding
(``tests/test_kernels.py``).

Nothing here imports numba until a kernel is first needed, so ``import accelcal``
stays cheap.  The first call of each kernel compiles it (seconds); ``cache=True``
stores the machine code on disk, beside the kernel's source (``__pycache__``) or, if
that folder is not writable, in numba's user-wide cache folder (``NUMBA_CACHE_DIR``
if set); later processes load it in milliseconds.  If no cache folder is writable the
kernels still run, compiled in memory by every process (a warning says so once).
"""

from __future__ import annotations

import importlib
import importlib.util
import os
import warnings

#: Values of ``ACCELCAL_KERNELS``.
BACKENDS = ("auto", "numpy", "numba")

#: numba's start-up in a process [s] (import, and loading the kernels of one module from
#: the disk cache): under ``auto`` the single-problem estimators switch to the compiled
#: kernels once the time their compiled forms would have saved reaches it (measured
#: 0.42-0.50 s of CPU by ``tools/bench_kernel_crossover.py``).
STARTUP_S = 0.5

_choice: str | None = None  # auto, numpy or numba: what was asked for
_backend: str | None = None  # numba or numpy: what runs
_loaded: dict[str, object] = {}
_forgone_s = 0.0  # time the compiled kernels would have saved the single-problem calls so far
_cache_warned = False


def choice() -> str:
    """The backend asked for: ``'auto'``, ``'numpy'`` or ``'numba'`` ($ACCELCAL_KERNELS)."""
    if _choice is None:
        set_backend(os.environ.get("ACCELCAL_KERNELS", "auto").strip().lower() or "auto")
    return _choice


def backend() -> str:
    """The backend in use: ``'numba'`` or ``'numpy'``."""
    if _backend is None:
        choice()
    return _backend


def _resolve(choice: str) -> str:
    if choice not in BACKENDS:
        raise ValueError(f"ACCELCAL_KERNELS must be one of {', '.join(BACKENDS)}, not {choice!r}")
    if choice == "numpy":
        return "numpy"
    try:
        found = importlib.util.find_spec("numba") is not None
    except (ImportError, ValueError):  # a broken or blocked installation counts as absent
        found = False
    if found:
        return "numba"
    if choice == "numba":
        raise ImportError("ACCELCAL_KERNELS=numba but numba is not installed (pip install 'accelcal[fast]')")
    return "numpy"


def set_backend(choice: str) -> str | None:
    """Ask for ``choice`` (one of :data:`BACKENDS`); returns the previous choice (None if
    none had been made), which restores it."""
    global _choice, _backend, _forgone_s
    previous = _choice
    if choice is None:
        _choice = _backend = None
        _forgone_s = 0.0
        return previous
    _backend = _resolve(choice)
    _choice = choice
    return previous


def compiled(module: str, single: bool = False, saves_s: float = 0.0):
    """The kernel module ``accelcal.<module>`` if it is to run compiled, else None.

    ``single``: the caller solves one problem, which a compiled call makes ``saves_s``
    seconds faster; under ``auto`` it gets the kernels once some kernel module is loaded
    in this process, or once such calls have added up :data:`STARTUP_S` (see the module
    docstring).  The module (and numba with it) is imported on the first call that gets
    it; a dictionary lookup after.
    """
    global _backend, _forgone_s
    if _backend != "numba" and backend() != "numba":
        return None
    mod = _loaded.get(module)
    if mod is not None:
        return mod
    if single and _choice == "auto" and not _loaded:
        _forgone_s += saves_s
        if _forgone_s < STARTUP_S:
            return None
    try:
        mod = _loaded[module] = importlib.import_module(f"accelcal.{module}")
    except ImportError as exc:  # numba found but not importable (broken install, wrong llvmlite)
        if _choice == "numba":
            raise
        warnings.warn(f"accelcal: numba cannot be imported ({exc}); using the numpy implementations",
                      RuntimeWarning, stacklevel=2)
        _backend = "numpy"
        return None
    return mod


def load() -> None:
    """Load every kernel module now (numba's start-up paid here), so that the
    single-problem estimators run compiled under ``auto`` too; nothing without numba."""
    for module in KERNEL_MODULES:
        compiled(module)


#: Every kernel module (relative to the accelcal package).
KERNEL_MODULES = ("_lls_kernels", "batista._filter_kernels", "tereshkov._estimator_kernels", "noise._fast",
                  "discrepancy._fit_kernels", "discrepancy.wander._grid_kernels", "formats._parse_kernels")


def jit(*args, **options):
    """``numba.njit`` with the project's options: disk cache, no Python error model (a
    division by zero gives inf/NaN as in numpy, the kernels test for it), no GIL.

    Falls back to an in-memory compilation when numba finds no writable cache folder.
    """
    import numba

    options = {"cache": True, "nogil": True, "error_model": "numpy", **options}

    def decorate(fn):
        global _cache_warned
        try:
            return _one_compiler_at_a_time(numba.njit(**options)(fn))
        except RuntimeError as exc:  # "cannot cache function ...: no locator available"
            if not options.get("cache") or "cache" not in str(exc):
                raise
            if not _cache_warned:
                warnings.warn(f"accelcal: no writable numba cache folder ({exc}); kernels are compiled in "
                              "memory by every process (set NUMBA_CACHE_DIR to a writable folder)",
                              RuntimeWarning, stacklevel=2)
                _cache_warned = True
            return numba.njit(**{**options, "cache": False})(fn)

    return decorate(args[0]) if args and callable(args[0]) else decorate


_locks_held: set[str] = set()


def _one_compiler_at_a_time(dispatcher):
    """``dispatcher`` with its compilation serialised across processes by a lock file
    beside its disk cache: the first process compiles and saves each signature, the
    others wait for it (without CPU) and then load it from the cache.

    Processes that start together on an empty cache (a fresh clone: the parallel jobs of
    the workflow, SLURM jobs, test workers) would otherwise each compile the same
    kernels, ~10-20 s of CPU each.  Without a disk cache, or where locks are not
    available, it compiles as numba does."""
    try:
        import fcntl
    except ImportError:  # not POSIX
        return dispatcher
    folder = getattr(getattr(dispatcher, "_cache", None), "cache_path", None)
    if not folder:
        return dispatcher
    fn = dispatcher.py_func
    lock_path = os.path.join(folder, f"{fn.__module__}.{fn.__qualname__}.compile-lock")
    compile_ = dispatcher.compile

    def compile(sig):
        if lock_path in _locks_held:  # this process holds it already (a recursive compilation)
            return compile_(sig)
        try:
            os.makedirs(folder, exist_ok=True)
            fd = os.open(lock_path, os.O_CREAT | os.O_RDWR, 0o644)
        except OSError:
            return compile_(sig)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX)  # released when the file is closed, or the process ends
            _locks_held.add(lock_path)
            return compile_(sig)  # loads from the disk cache what another process saved meanwhile
        finally:
            _locks_held.discard(lock_path)
            os.close(fd)

    dispatcher.compile = compile
    return dispatcher


__all__ = ["BACKENDS", "KERNEL_MODULES", "STARTUP_S", "backend", "choice", "compiled", "jit", "load", "set_backend"]
