"""Where the compute time goes: estimators, filters, compilation and workflow stages.

The paper reports full LLS ≈ 35× and bias-only LLS ≈ 20× faster than NLLS without
saying how it timed them.  The project measures them side by side in one process, at
several pose counts, with the compiled kernels and with the numpy reference
implementations (:mod:`accelcal.kernels`):

* :func:`time_interleaved`: per-problem wall time (``time.perf_counter``) of every
  method (× backend) on the *same* problems, in one process, repeated, after one untimed
  warm-up call per method (CasADi builds its solver once per pose count, numba loads its
  kernels); the garbage collector is off while timing, as in :mod:`timeit`, and the
  backend is switched outside the timed region.  Two interleavings: ``block`` (per
  repeat, each method solves all problems in a row, methods taking turns; the headline
  numbers) and ``problem`` (all methods back to back on every problem).  Per-problem
  interleaving makes the closed forms slower: a microsecond solve starts with caches an
  IPOPT solve has just evicted.  Both are recorded.
* :func:`time_batched`: throughput of the vectorised closed forms (``full_lls_batch``,
  ``bias_lls_batch``, ``full_als_batch``) on a stack of problems.
* :func:`summarize_timing`: median and IQR per pose count × method × backend, and the
  speed-up of each closed form over its NLLS baseline: the median of the per-problem
  paired ratios ``t_NLLS / t_LLS`` (same problem, same repeat) and the ratio of the medians.
* :func:`filter_timing`: cost per step of the Batista filter (own covariance, covariance
  sequence, shared-gain Monte Carlo) and of Tereshkov's estimator (one run, batched).
* :func:`compile_timing`: first-call time of every compiled kernel in a fresh process,
  with an empty disk cache (compilation) and with the cache it left (loading).
* :func:`stage_job_seconds`: wall and CPU seconds per workflow stage from Snakemake's
  benchmark files.

The estimators are called through their public functions (:func:`accelcal.full_lls`
etc.), so the benchmark measures whatever the library currently does.  Wall times
depend on the machine and its load: they are recorded, never asserted on.
"""

from __future__ import annotations

import gc
import importlib
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Mapping, Sequence
from functools import partial

import numpy as np
import pandas as pd

from accelcal import kernels
from accelcal.errors import AccelcalError
from accelcal.registry import estimators
from accelcal.simulation import random_directions, sample_truth, simulate_poses
from accelcal.tereshkov.estimator import run_estimator

from .first_calls import FIRST_CALLS, SCRIPT
from .montecarlo import grid_seed
from .report import read_benchmarks, stage_times
from .tereshkov.montecarlo import build_scenario, estimator_params
from .tereshkov.vehicle import sensor_chunks

#: The estimators timed: the registry's accelerometer estimators.
_TIMED = estimators("accelerometer")
#: Single-problem estimators timed (``f(z, g)``; those that use the noise level get the
#: noise std in :func:`run_benchmark`), and the batched forms of the closed forms.
SINGLE_METHODS: dict[str, Callable] = {e.name: e.load() for e in _TIMED}
BATCH_METHODS: dict[str, Callable] = {e.batch_name: e.load_batch() for e in _TIMED
                                      if e.batch and e.family == "closed_form"}
#: The estimator of each timed method (single or batched).
_ESTIMATOR_OF = {e.name: e for e in _TIMED} | {e.batch_name: e for e in _TIMED if e.batch}
#: The baseline each method is compared with (the registry's).
BASELINE = {m: e.baseline for m, e in _ESTIMATOR_OF.items() if e.baseline and m in {*SINGLE_METHODS, *BATCH_METHODS}}
#: Methods with a compiled kernel, timed under each backend; the others (NLLS) once.
COMPILED_METHODS = tuple(m for m, e in _ESTIMATOR_OF.items() if e.compiled and m in {*SINGLE_METHODS, *BATCH_METHODS})
#: Backend label of the methods without a compiled path.
NO_BACKEND = "casadi"


def available_backends() -> tuple[str, ...]:
    """``('numba', 'numpy')`` with numba installed, else ``('numpy',)``."""
    previous = kernels.set_backend("auto")  # what 'auto' resolves to here; then the choice made before
    found = kernels.backend()
    kernels.set_backend(previous)
    return ("numba", "numpy") if found == "numba" else ("numpy",)


def _label(key) -> tuple[str, str]:
    """``(method, backend)`` of a method key: a name, or a ``(name, backend)`` pair."""
    return (key[0], key[1]) if isinstance(key, tuple) else (key, "")


def _switch(backend: str) -> None:
    if backend in ("numba", "numpy") and kernels.backend() != backend:
        kernels.set_backend(backend)


def make_problems(rng: np.random.Generator, n_problems: int, n_poses: int, g: float, noise_std: float,
                  identity_m: bool = False) -> np.ndarray:
    """``n_problems`` Burkhard-style problems (T, n, 3): truth of Sec. 2, random poses."""
    truth = sample_truth(rng, n_problems, identity_m=identity_m)
    u = random_directions(rng, n_poses, n_problems)
    return simulate_poses(u, g, truth["M"], truth["bias"], noise_std, rng)


def _schedule(keys: list, T: int, repeats: int, interleave: str) -> list[tuple]:
    """``(repeat, problem, order, method)`` in the order :func:`time_interleaved` runs them."""
    if interleave == "block":
        return [(r, p, k, m) for r in range(repeats)
                for k, m in enumerate(keys[r % len(keys):] + keys[:r % len(keys)])
                for p in range(T)]
    return [(r, p, k, m) for r in range(repeats) for p in range(T)
            for k, m in enumerate(keys[(r + p) % len(keys):] + keys[:(r + p) % len(keys)])]


def time_interleaved(problems: Mapping, g: float, methods: Mapping, repeats: int, interleave: str = "block",
                     clock: Callable[[], float] = time.perf_counter) -> pd.DataFrame:
    """Per-problem wall time of every method, interleaved on identical data.

    Parameters
    ----------
    problems : mapping key -> array (T, n, 3)
        The data each method sees (full and bias-only methods may get different data
        sets, but all methods must get the same number of problems).
    methods : mapping key -> callable ``f(z, g)``
        A key is a method name, or a ``(name, backend)`` pair: the backend
        (:func:`accelcal.kernels.set_backend`) is switched to before each timed call,
        outside the timed region.
    repeats : int
        Passes over all problems.
    interleave : {'block', 'problem'}
        ``'block'``: in every repeat each method solves all problems in a row, the
        methods taking turns (rotating order between repeats): each method runs as it
        would in use, with warm caches.  ``'problem'``: for every problem all methods
        run back to back (rotating order): finest interleaving, but a microsecond closed
        form then starts with the caches an IPOPT solve left cold (about 2x slower).

    Returns
    -------
    DataFrame with ``interleave, method, backend, repeat, problem, order, seconds, status``
    (``ok``, or the class of the :class:`~accelcal.errors.AccelcalError` the call raised:
    a failed solve is timed like any other, and its status says so).
    """
    if interleave not in ("block", "problem"):
        raise ValueError(f"interleave must be 'block' or 'problem', not {interleave!r}")
    keys = list(methods)
    T = {len(problems[m]) for m in keys}
    if len(T) != 1:
        raise ValueError("every method must get the same number of problems")
    T = T.pop()
    previous = kernels.choice()
    for m in keys:  # warm-up (solver build, kernels, caches), untimed
        _switch(_label(m)[1])
        _call(methods[m], problems[m][0], g)
    schedule = _schedule(keys, T, repeats, interleave)
    rows = []
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        for r, p, k, m in schedule:
            name, backend = _label(m)
            _switch(backend)
            f, z = methods[m], problems[m][p]
            t0 = clock()
            status = _call(f, z, g)
            rows.append((interleave, name, backend, r, p, k, clock() - t0, status))
    finally:
        kernels.set_backend(previous)
        if was_enabled:
            gc.enable()
    return pd.DataFrame(rows, columns=["interleave", "method", "backend", "repeat", "problem", "order", "seconds",
                                       "status"])


def _call(f: Callable, z: np.ndarray, g: float) -> str:
    try:
        f(z, g)
    except AccelcalError as e:
        return type(e).__name__
    return "ok"


def time_batched(problems: Mapping, g: float, methods: Mapping, repeats: int | Mapping[str, int],
                 clock: Callable[[], float] = time.perf_counter) -> pd.DataFrame:
    """Wall time of batched estimators, each on its stack ``problems[key]`` (T, n, 3),
    interleaved per repeat (rotating order), after an untimed warm-up; keys as in
    :func:`time_interleaved`.  ``repeats``: calls per method, or per backend (a mapping
    backend -> calls): a method whose calls are done drops out of the later rounds.

    Returns ``method, backend, repeat, n_problems, seconds, problems_per_s`` and the
    CPU time of the call (``cpu_seconds``, ``time.thread_time``: on a loaded machine a
    call of a few milliseconds may wait for a core, which its wall time counts).
    """
    keys = list(methods)
    calls = {m: repeats if isinstance(repeats, int) else repeats[_label(m)[1]] for m in keys}
    previous = kernels.choice()
    rows = []
    try:
        for m in keys:
            _switch(_label(m)[1])
            methods[m](problems[m][:2], g)
        for r in range(max(calls.values(), default=0)):
            shift = r % len(keys)
            for m in keys[shift:] + keys[:shift]:
                if r >= calls[m]:
                    continue
                name, backend = _label(m)
                _switch(backend)
                z = problems[m]
                c0, t0 = time.thread_time(), clock()
                methods[m](z, g)
                dt, cpu = clock() - t0, time.thread_time() - c0
                rows.append((name, backend, r, len(z), dt, len(z) / dt, cpu))
    finally:
        kernels.set_backend(previous)
    return pd.DataFrame(rows, columns=["method", "backend", "repeat", "n_problems", "seconds", "problems_per_s",
                                       "cpu_seconds"])


def _q(x, q):
    return float(np.quantile(np.asarray(x, float), q))


def _with_backend(df: pd.DataFrame) -> pd.DataFrame:
    return df if "backend" in df else df.assign(backend="")


def summarize_timing(single: pd.DataFrame, batched: pd.DataFrame | None = None,
                     baseline: Mapping[str, str] = BASELINE) -> pd.DataFrame:
    """Per pose count × interleaving × method × backend: median, quartiles and IQR of the
    per-problem time, throughput and the speed-up over the NLLS baseline
    (``baseline``: method -> baseline method).

    ``speedup_median`` (and ``speedup_q25/q75``) are quantiles of the paired ratios
    ``t_baseline / t_method`` over (repeat, problem) for single-problem methods; for a
    batched method, of the ratio of the baseline's median per-problem time at the same
    pose count (``block`` interleaving if timed, else ``problem``) to the batched
    per-problem time of each repeat.  ``speedup_of_medians`` is the ratio of the two medians.
    """
    single = _with_backend(single)
    rows = []
    for (n, il, m, be), d in single.groupby(["n_poses", "interleave", "method", "backend"], sort=False):
        t = d["seconds"].to_numpy()
        rows.append({"n_poses": n, "mode": "single", "interleave": il, "method": m, "backend": be,
                     "n_timings": len(t), "median_s": _q(t, 0.5), "q25_s": _q(t, 0.25), "q75_s": _q(t, 0.75),
                     "problems_per_s": 1.0 / _q(t, 0.5)})
    if batched is not None and len(batched):
        batched = _with_backend(batched)
        for (n, m, be), d in batched.groupby(["n_poses", "method", "backend"], sort=False):
            t = (d["seconds"] / d["n_problems"]).to_numpy()
            cpu = d["cpu_seconds"] if "cpu_seconds" in d else pd.Series(np.nan, index=d.index)
            rows.append({"n_poses": n, "mode": "batch", "interleave": "block", "method": m, "backend": be,
                         "n_timings": len(t), "median_s": _q(t, 0.5), "q25_s": _q(t, 0.25), "q75_s": _q(t, 0.75),
                         "problems_per_s": float(np.median(d["problems_per_s"])),
                         "problems_per_cpu_s": float(np.median(d["n_problems"] / cpu))})
    out = pd.DataFrame(rows)
    if "problems_per_cpu_s" not in out:
        out["problems_per_cpu_s"] = np.nan
    out["iqr_s"] = out["q75_s"] - out["q25_s"]
    out["baseline"] = ""
    for col in ("speedup_median", "speedup_q25", "speedup_q75", "speedup_of_medians"):
        out[col] = np.nan
    # the baseline's median per (pose count, interleaving): NLLS has one backend
    single_med = {(r["n_poses"], r["interleave"], r["method"]): r["median_s"]
                  for _, r in out[out["mode"] == "single"].iterrows() if r["method"] not in baseline}
    for i, row in out.iterrows():
        b, n, il = baseline.get(row["method"]), row["n_poses"], row["interleave"]
        if row["mode"] == "batch":  # against the NLLS median of block timings if there are any
            il = next((x for x in ("block", "problem") if (n, x, b) in single_med), il)
        if b is None or (n, il, b) not in single_med:
            continue
        if row["mode"] == "single":
            d = single[(single["interleave"] == il) & (single["n_poses"] == n)]
            mine = d[(d["method"] == row["method"]) & (d["backend"] == row["backend"])].set_index(["repeat", "problem"])
            base = d[d["method"] == b].set_index(["repeat", "problem"])
            ratio = (base["seconds"] / mine["seconds"]).dropna().to_numpy()
        else:
            d = batched[(batched["method"] == row["method"]) & (batched["backend"] == row["backend"])
                        & (batched["n_poses"] == n)]
            ratio = (single_med[(n, il, b)] / (d["seconds"] / d["n_problems"])).to_numpy()
        out.loc[i, "baseline"] = b
        for col, q in (("speedup_median", 0.5), ("speedup_q25", 0.25), ("speedup_q75", 0.75)):
            out.loc[i, col] = _q(ratio, q)
        out.loc[i, "speedup_of_medians"] = single_med[(n, il, b)] / row["median_s"]
    return out.sort_values(["n_poses", "mode", "interleave"], kind="stable", ignore_index=True)


def run_benchmark(seed: int, g: float, noise_std: float, n_poses: Sequence[int], n_problems: int, repeats: int,
                  batch_problems: int, batch_repeats: int | Mapping[str, int],
                  single_methods: Sequence[str] = tuple(SINGLE_METHODS),
                  batch_methods: Sequence[str] = tuple(BATCH_METHODS),
                  interleavings: Sequence[str] = ("block", "problem"), als_known_noise: bool = True,
                  nlls_known_noise: bool = True, backends: Sequence[str] | None = None,
                  stage: str = "burkhard2024_timing") -> tuple[pd.DataFrame, pd.DataFrame]:
    """The whole benchmark, one pose count after the other: problems from the stream
    ``grid_seed(seed, stage, n)``, interleaved single-problem timings (every
    interleaving; the methods of :data:`COMPILED_METHODS` once per backend, the NLLS
    once, all in one schedule) and batched throughput.  Full methods get data with
    ``M ≠ I``; bias-only methods the same directions, bias and noise draw with ``M = I``.
    A method is skipped at a pose count below its minimum (10 full, 4 bias-only).

    Returns ``(single, batched)`` raw timing tables, each with an ``n_poses`` column.
    """
    backends = tuple(backends or available_backends())
    # as in the Monte Carlo: ALS is told the noise std for its correction, NLLS for its stopping rule
    told = {"correction": als_known_noise, "stopping": nlls_known_noise}

    def with_noise(m, f):
        e = _ESTIMATOR_OF[m]
        return partial(f, noise_std=noise_std) if e.needs_noise and told[e.noise_use] else f

    fns = {m: with_noise(m, SINGLE_METHODS[m]) for m in single_methods}
    bfns = {m: with_noise(m, BATCH_METHODS[m]) for m in batch_methods}
    singles, batches = [], []
    for n in n_poses:
        n = int(n)
        ss_single, ss_batch = grid_seed(seed, stage, n).spawn(2)
        zf = make_problems(np.random.default_rng(ss_single), n_problems, n, g, noise_std)
        zb = make_problems(np.random.default_rng(ss_single), n_problems, n, g, noise_std, identity_m=True)
        here = {(m, be if m in COMPILED_METHODS else NO_BACKEND): f for m, f in fns.items()
                if n >= _ESTIMATOR_OF[m].min_poses for be in (backends if m in COMPILED_METHODS else (NO_BACKEND,))}
        problems = {k: (zb if _ESTIMATOR_OF[k[0]].model == "bias" else zf) for k in here}
        for il in interleavings:
            singles.append(time_interleaved(problems, g, here, repeats, interleave=il).assign(n_poses=n))
        bm = {(m, be): f for m, f in bfns.items() if n >= _ESTIMATOR_OF[m].min_poses for be in backends}
        if bm and batch_problems > 0:
            zbf = make_problems(np.random.default_rng(ss_batch), batch_problems, n, g, noise_std)
            zbb = make_problems(np.random.default_rng(ss_batch), batch_problems, n, g, noise_std, identity_m=True)
            bproblems = {k: (zbb if _ESTIMATOR_OF[k[0]].model == "bias" else zbf) for k in bm}
            batches.append(time_batched(bproblems, g, bm, batch_repeats).assign(n_poses=n))
    single = pd.concat(singles, ignore_index=True)
    single = single[["n_poses"] + [c for c in single.columns if c != "n_poses"]]
    batched = pd.concat(batches, ignore_index=True) if batches else pd.DataFrame(
        columns=["n_poses", "method", "backend", "repeat", "n_problems", "seconds", "problems_per_s"])
    batched = batched[["n_poses"] + [c for c in batched.columns if c != "n_poses"]]
    return single, batched


def preferred_backend(table: pd.DataFrame, method: str) -> str:
    """The backend whose rows of ``method`` stand for the library's default: ``numba``
    if it was timed, else the one there is."""
    bes = set(_with_backend(table).loc[lambda t: t["method"] == method, "backend"])
    return "numba" if "numba" in bes else (sorted(bes)[0] if bes else "")


# ----------------------------------------------------------------------------- filters
def _best(f: Callable[[], object], repeat: int) -> tuple[float, float]:
    """Smallest wall time and smallest CPU time (``time.thread_time``) of ``repeat`` calls."""
    wall, cpu = [], []
    for _ in range(repeat):
        c0, t0 = time.thread_time(), time.perf_counter()
        f()
        wall.append(time.perf_counter() - t0)
        cpu.append(time.thread_time() - c0)
    return min(wall), min(cpu)


def filter_timing(batista_cost: Callable[[], pd.DataFrame], tereshkov_data: Mapping, repeat: int = 3,
                  backends: Sequence[str] | None = None) -> pd.DataFrame:
    """Cost per step of the sequential filters under every backend.

    ``batista_cost(steps)`` times the Batista filter over ``steps`` samples (None: its
    configured number) (:func:`accelcal_repro.batista2011.montecarlo.filter_cost`: the
    filter with its own covariance on one run, the covariance sequence, the shared-gain
    filter per run); it runs once on 50 samples first, untimed (kernels loaded);
    ``tereshkov_data`` (:func:`tereshkov_inputs`: ``gyro``, ``accel``, ``f_ext`` (R, n, 3),
    ``course``, ``speed`` (R, n), ``dt``, ``params``) runs through
    :func:`accelcal.tereshkov.run_estimator` for one run and for all R runs (best of
    ``repeat``, after an untimed warm-up).

    Returns ``filter, implementation, backend, runs, steps, seconds, us_per_step,
    us_per_run_step``.
    """

    backends = tuple(backends or available_backends())
    previous = kernels.choice()
    d = tereshkov_data
    R, n = d["gyro"].shape[:2]
    rows = []
    try:
        for be in backends:
            kernels.set_backend(be)
            batista_cost(50)  # warm-up
            c = batista_cost(None)  # filter_cost measures wall time only
            rows += [{"filter": "batista", "implementation": r["implementation"], "backend": be, "runs": r["runs"],
                      "steps": r["steps"], "seconds": r["seconds"], "cpu_seconds": np.nan} for _, r in c.iterrows()]
            for runs in (1, R):
                args = [d[k][:runs] for k in ("gyro", "accel", "f_ext", "course", "speed")]
                run_estimator(*[a[:, :100] for a in args], d["dt"], d["params"], record_every=100)
                secs, cpu = _best(lambda: run_estimator(*args, d["dt"], d["params"], record_every=100), repeat)
                rows.append({"filter": "tereshkov", "backend": be, "runs": runs, "steps": n, "seconds": secs,
                             "cpu_seconds": cpu,
                             "implementation": "run_estimator (1 run)" if runs == 1 else f"run_estimator ({R} runs)"})
    finally:
        kernels.set_backend(previous)
    out = pd.DataFrame(rows)
    out["us_per_step"] = 1e6 * out["seconds"] / out["steps"]
    out["us_per_run_step"] = out["us_per_step"] / out["runs"]
    return out[["filter", "implementation", "backend", "runs", "steps", "seconds", "cpu_seconds", "us_per_step",
                "us_per_run_step"]]


def tereshkov_inputs(cfg: Mapping, runs: int, duration_s: float) -> dict:
    """Sensor data of ``runs`` field runs of ``duration_s`` from the ``tereshkov`` stage
    config (:func:`accelcal_repro.tereshkov.montecarlo.build_scenario`): ``gyro``,
    ``accel``, ``f_ext`` (R, n, 3), ``course``, ``speed`` (R, n), ``dt``, and the
    estimator ``params``."""

    c = {k: (dict(v) if isinstance(v, dict) else v) for k, v in cfg.items()}
    c["scenarios"] = dict(c.get("scenarios", {})) | {"field": {"runs": int(runs), "duration_s": float(duration_s)}}
    batch = build_scenario(c, "field").batch
    parts = {k: [] for k in ("gyro", "accel", "f_ext", "course", "speed")}
    for ch in sensor_chunks(batch, 60.0):
        for k in parts:
            parts[k].append(getattr(ch, k))
    out = {k: np.ascontiguousarray(np.concatenate(v, axis=1)) for k, v in parts.items()}
    out["dt"] = 1.0 / batch.sensors.imu_rate
    out["params"] = estimator_params(c)
    return out


# ----------------------------------------------------------------------------- compilation
def compile_timing(calls: Sequence[str] | str = "all", python: str = sys.executable,
                   keep_cache: bool = False) -> pd.DataFrame:
    """First-call time of compiled kernels, in fresh processes with their own numba cache
    folder (``NUMBA_CACHE_DIR``, so the project's own cache is neither used nor touched):
    ``cold`` (empty cache: the compilation) and ``cached`` (a second process loading what
    the first wrote).  ``calls``: names of :data:`FIRST_CALLS` (in that order; a kernel
    shared with an earlier call is compiled there), or ``'all'``.  Also the import time of
    the estimators and of numba.  ``keep_cache``: copy what the cold process compiled into
    the project's own cache (:func:`copy_kernel_cache`) instead of discarding it.

    Returns ``call, cold_s, cached_s`` (empty without numba).
    """
    if calls != "all":
        unknown = sorted(set(calls) - set(FIRST_CALLS))
        if unknown:
            raise ValueError(f"unknown first call(s) {unknown}; known: {list(FIRST_CALLS)}")
        calls = list(calls)
    if "numba" not in available_backends():
        return pd.DataFrame(columns=["call", "cold_s", "cached_s"])
    runs = {}
    with tempfile.TemporaryDirectory(prefix="accelcal-numba-cache-") as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache, ACCELCAL_KERNELS="numba")
        for which in ("cold", "cached"):
            out = subprocess.run([python, "-c", SCRIPT, json.dumps(calls)], env=env, capture_output=True,
                                 text=True, check=True)
            runs[which] = dict(json.loads(out.stdout.strip().splitlines()[-1])["rows"])
        if keep_cache:
            copy_kernel_cache(cache)
    return pd.DataFrame({"call": list(runs["cold"]), "cold_s": list(runs["cold"].values()),
                         "cached_s": [runs["cached"][c] for c in runs["cold"]]})


def fill_kernel_cache(python: str = sys.executable) -> pd.DataFrame:
    """Every first call of :data:`FIRST_CALLS` once, compiled (``ACCELCAL_KERNELS=numba``),
    in a fresh process that writes the project's own numba disk cache (unlike
    :func:`compile_timing`): the processes started after it load the kernels instead of
    compiling them, or of waiting for one another's compilation
    (:func:`accelcal.kernels.njit`'s lock).  Returns ``call, first_s`` (empty without numba)."""
    if "numba" not in available_backends():
        return pd.DataFrame(columns=["call", "first_s"])
    out = subprocess.run([python, "-c", SCRIPT, json.dumps("all")], env=dict(os.environ, ACCELCAL_KERNELS="numba"),
                         capture_output=True, text=True, check=True)
    rows = json.loads(out.stdout.strip().splitlines()[-1])["rows"]
    return pd.DataFrame(rows, columns=["call", "first_s"])


def kernel_cache_and_compile_timing(calls: Sequence[str] | str = "all",
                                    python: str = sys.executable) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The compile job: the project's numba cache filled (:func:`fill_kernel_cache`'s
    table) and the first-call times (:func:`compile_timing`'s), with one compilation
    when ``calls`` is ``'all'``: the cold process of the timing compiles every kernel into
    an empty folder, which is then copied into the project's cache (the cold times are
    then the fill's first calls).  Otherwise the timed calls are a subset and the cache is
    filled by a process of its own, as before (measured on the default config: the second
    compilation cost 24 s of CPU in a fresh clone)."""
    if calls != "all":
        return fill_kernel_cache(python), compile_timing(calls, python)
    timing = compile_timing("all", python, keep_cache=True)
    return timing.rename(columns={"cold_s": "first_s"})[["call", "first_s"]], timing


def copy_kernel_cache(cache_dir: str | os.PathLike) -> int:
    """Copy the numba disk cache that processes wrote with ``NUMBA_CACHE_DIR=cache_dir``
    into the folders where this process's kernels look for it (numba's own choice: the
    kernels' ``__pycache__``, or ``$NUMBA_CACHE_DIR``).  The entries are keyed by the
    source's content hash, not by its folder, so a copy loads as the original does.
    Index and machine code only (no lock files).  Returns the number of files copied."""
    from numba.core.caching import UserProvidedCacheLocator  # numba is optional (the fast extra)

    pairs = set()
    for name in kernels.KERNEL_MODULES:
        module = importlib.import_module(f"accelcal.{name}")
        target = next((d._cache.cache_path for d in vars(module).values()
                       if getattr(getattr(d, "_cache", None), "cache_path", None)), None)
        if target is not None:
            pairs.add((os.path.join(os.fspath(cache_dir),
                                    UserProvidedCacheLocator.get_suitable_cache_subpath(module.__file__)), target))
    copied = 0
    for source, target in sorted(pairs):
        if not os.path.isdir(source):
            continue
        os.makedirs(target, exist_ok=True)
        for entry in sorted(os.listdir(source)):
            if entry.endswith((".nbi", ".nbc")):
                shutil.copy2(os.path.join(source, entry), os.path.join(target, entry))
                copied += 1
    return copied


# ----------------------------------------------------------------------------- stages
def stage_job_seconds(benchmarks_dir) -> pd.DataFrame:
    """Per workflow stage: jobs, summed wall seconds and CPU seconds, largest peak memory,
    from Snakemake's benchmark files (:func:`accelcal_repro.report.read_benchmarks`) as
    they are now: the last run of each job."""

    return stage_times(read_benchmarks(benchmarks_dir))


__all__ = [
    "BASELINE",
    "BATCH_METHODS",
    "COMPILED_METHODS",
    "FIRST_CALLS",
    "NO_BACKEND",
    "SINGLE_METHODS",
    "available_backends",
    "compile_timing",
    "copy_kernel_cache",
    "fill_kernel_cache",
    "kernel_cache_and_compile_timing",
    "filter_timing",
    "make_problems",
    "preferred_backend",
    "run_benchmark",
    "stage_job_seconds",
    "summarize_timing",
    "tereshkov_inputs",
    "time_batched",
    "time_interleaved",
]
