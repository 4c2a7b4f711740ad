"""Compute-time benchmark of closed-form LLS against iterative NLLS (Burkhard et al. 2024).

The paper reports full LLS ≈ 35× and bias-only LLS ≈ 20× faster than NLLS without
saying how it timed them.  The project measures them side by side in one process, at
several pose counts:

* :func:`time_interleaved`: per-problem wall time (``time.perf_counter``) of every
  method on the *same* problems, in one process, repeated, after one untimed warm-up
  call per method (CasADi builds its solver once per pose count); the garbage
  collector is off while timing, as in :mod:`timeit`.  Two interleavings: ``block``
  (per repeat, each method solves all problems in a row, methods taking turns; the
  headline numbers) and ``problem`` (all methods back to back on every problem).
  Per-problem interleaving makes the closed forms slower: a 0.2 ms solve starts with
  caches an IPOPT solve has just evicted.  Both are recorded.
* :func:`time_batched`: throughput of the vectorised closed forms
  (``full_lls_batch``, ``bias_lls_batch``) on a stack of problems.
* :func:`summarize_timing`: median and IQR per pose count × method, and the speed-up of
  each LLS (and of ALS) over its NLLS baseline: the median of the per-problem paired
  ratios ``t_NLLS / t_LLS`` (same problem, same repeat) and the ratio of the medians.

The estimators are called through their public functions (:func:`accelcal.full_lls`
etc.), so the benchmark measures whatever the library currently does.  Wall times
depend on the machine and its load: they are recorded, never asserted on.
"""

from __future__ import annotations

import gc
import time
from collections.abc import Callable, Mapping, Sequence
from functools import partial

import numpy as np
import pandas as pd

from accelcal.als import full_als
from accelcal.errors import AccelcalError
from accelcal.lls import bias_lls, bias_lls_batch, full_lls, full_lls_batch
from .montecarlo import grid_seed, min_poses
from accelcal.nlls import bias_nlls, full_nlls
from accelcal.simulation import random_directions, sample_truth, simulate_poses

#: Single-problem estimators timed (``f(z, g)``; ALS gets the noise std in :func:`run_benchmark`).
SINGLE_METHODS: dict[str, Callable] = {
    "full_lls": full_lls, "full_als": full_als, "full_nlls": full_nlls, "bias_lls": bias_lls, "bias_nlls": bias_nlls,
}
BATCH_METHODS: dict[str, Callable] = {"full_lls_batch": full_lls_batch, "bias_lls_batch": bias_lls_batch}
#: The NLLS baseline each closed form is compared with.
BASELINE = {"full_lls": "full_nlls", "full_als": "full_nlls", "bias_lls": "bias_nlls",
            "full_lls_batch": "full_nlls", "bias_lls_batch": "bias_nlls"}


def make_problems(rng: np.random.Generator, n_problems: int, n_poses: int, g: float, noise_std: float,
                  identity_m: bool = False) -> np.ndarray:
    """``n_problems`` Burkhard-style problems (T, n, 3): truth of Sec. 2, random poses."""
    truth = sample_truth(rng, n_problems, identity_m=identity_m)
    u = random_directions(rng, n_poses, n_problems)
    return simulate_poses(u, g, truth["M"], truth["bias"], noise_std, rng)


def time_interleaved(problems: Mapping[str, np.ndarray], g: float, methods: Mapping[str, Callable],
                     repeats: int, interleave: str = "block",
                     clock: Callable[[], float] = time.perf_counter) -> pd.DataFrame:
    """Per-problem wall time of every method, interleaved on identical data.

    Parameters
    ----------
    problems : mapping method -> array (T, n, 3)
        The data each method sees (full and bias-only methods may get different data
        sets, but all methods must get the same number of problems).
    methods : mapping name -> callable ``f(z, g)``
    repeats : int
        Passes over all problems.
    interleave : {'block', 'problem'}
        ``'block'``: in every repeat each method solves all problems in a row, the
        methods taking turns (rotating order between repeats): each method runs as it
        would in use, with warm caches.  ``'problem'``: for every problem all methods
        run back to back (rotating order): finest interleaving, but a 0.2 ms closed
        form then starts with the caches an IPOPT solve left cold (about 2x slower).

    Returns
    -------
    DataFrame with ``interleave, method, repeat, problem, order, seconds, status``
    (``ok``, or the class of the :class:`~accelcal.errors.AccelcalError` the call raised:
    a failed solve is timed like any other, and its status says so).
    """
    if interleave not in ("block", "problem"):
        raise ValueError(f"interleave must be 'block' or 'problem', not {interleave!r}")
    names = list(methods)
    T = {len(problems[m]) for m in names}
    if len(T) != 1:
        raise ValueError("every method must get the same number of problems")
    T = T.pop()
    for m in names:  # warm-up (solver build, caches), untimed
        _call(methods[m], problems[m][0], g)
    if interleave == "block":
        schedule = [(r, p, k, m) for r in range(repeats)
                    for k, m in enumerate(names[r % len(names):] + names[:r % len(names)])
                    for p in range(T)]
    else:
        schedule = [(r, p, k, m) for r in range(repeats) for p in range(T)
                    for k, m in enumerate(names[(r + p) % len(names):] + names[:(r + p) % len(names)])]
    rows = []
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        for r, p, k, m in schedule:
            f, z = methods[m], problems[m][p]
            t0 = clock()
            status = _call(f, z, g)
            rows.append((interleave, m, r, p, k, clock() - t0, status))
    finally:
        if was_enabled:
            gc.enable()
    return pd.DataFrame(rows, columns=["interleave", "method", "repeat", "problem", "order", "seconds", "status"])


def _call(f: Callable, z: np.ndarray, g: float) -> str:
    try:
        f(z, g)
    except AccelcalError as e:
        return type(e).__name__
    return "ok"


def time_batched(problems: Mapping[str, np.ndarray], g: float, methods: Mapping[str, Callable],
                 repeats: int, clock: Callable[[], float] = time.perf_counter) -> pd.DataFrame:
    """Wall time of batched estimators, each on its stack ``problems[method]`` (T, n, 3),
    interleaved per repeat (rotating order), after an untimed warm-up.

    Returns ``method, repeat, n_problems, seconds, problems_per_s``.
    """
    names = list(methods)
    for m in names:
        methods[m](problems[m][:2], g)
    rows = []
    for r in range(repeats):
        shift = r % len(names)
        for m in names[shift:] + names[:shift]:
            z = problems[m]
            t0 = clock()
            methods[m](z, g)
            dt = clock() - t0
            rows.append((m, r, len(z), dt, len(z) / dt))
    return pd.DataFrame(rows, columns=["method", "repeat", "n_problems", "seconds", "problems_per_s"])


def _q(x, q):
    return float(np.quantile(np.asarray(x, float), q))


def summarize_timing(single: pd.DataFrame, batched: pd.DataFrame | None = None,
                     baseline: Mapping[str, str] = BASELINE) -> pd.DataFrame:
    """Per pose count × interleaving × method: median, quartiles and IQR of the
    per-problem time, throughput and the speed-up over the NLLS baseline
    (``baseline``: method -> baseline).

    ``speedup_median`` (and ``speedup_q25/q75``) are quantiles of the paired ratios
    ``t_baseline / t_method`` over (repeat, problem) for single-problem methods; for a
    batched method, of the ratio of the baseline's median per-problem time at the same
    pose count (``block`` interleaving if timed, else ``problem``) to the batched
    per-problem time of each repeat.  ``speedup_of_medians`` is the ratio of the two medians.
    """
    rows = []
    for (n, il, m), d in single.groupby(["n_poses", "interleave", "method"], sort=False):
        t = d["seconds"].to_numpy()
        rows.append({"n_poses": n, "mode": "single", "interleave": il, "method": m, "n_timings": len(t),
                     "median_s": _q(t, 0.5), "q25_s": _q(t, 0.25), "q75_s": _q(t, 0.75),
                     "problems_per_s": 1.0 / _q(t, 0.5)})
    if batched is not None and len(batched):
        for (n, m), d in batched.groupby(["n_poses", "method"], sort=False):
            t = (d["seconds"] / d["n_problems"]).to_numpy()
            rows.append({"n_poses": n, "mode": "batch", "interleave": "block", "method": m, "n_timings": len(t),
                         "median_s": _q(t, 0.5), "q25_s": _q(t, 0.25), "q75_s": _q(t, 0.75),
                         "problems_per_s": float(np.median(d["problems_per_s"]))})
    out = pd.DataFrame(rows)
    out["iqr_s"] = out["q75_s"] - out["q25_s"]
    out["baseline"] = ""
    for col in ("speedup_median", "speedup_q25", "speedup_q75", "speedup_of_medians"):
        out[col] = np.nan
    single_med = {(r["n_poses"], r["interleave"], r["method"]): r["median_s"]
                  for _, r in out[out["mode"] == "single"].iterrows()}
    for i, row in out.iterrows():
        b, n, il = baseline.get(row["method"]), row["n_poses"], row["interleave"]
        if row["mode"] == "batch":  # against the NLLS median of block timings if there are any
            il = next((x for x in ("block", "problem") if (n, x, b) in single_med), il)
        if b is None or (n, il, b) not in single_med:
            continue
        if row["mode"] == "single":
            d = single[(single["interleave"] == il) & (single["n_poses"] == n)]
            paired = d.pivot_table(index=["repeat", "problem"], columns="method", values="seconds")
            ratio = (paired[b] / paired[row["method"]]).dropna().to_numpy()
        else:
            d = batched[(batched["method"] == row["method"]) & (batched["n_poses"] == n)]
            ratio = (single_med[(n, il, b)] / (d["seconds"] / d["n_problems"])).to_numpy()
        out.loc[i, "baseline"] = b
        for col, q in (("speedup_median", 0.5), ("speedup_q25", 0.25), ("speedup_q75", 0.75)):
            out.loc[i, col] = _q(ratio, q)
        out.loc[i, "speedup_of_medians"] = single_med[(n, il, b)] / row["median_s"]
    return out.sort_values(["n_poses", "mode", "interleave"], kind="stable", ignore_index=True)


def run_benchmark(seed: int, g: float, noise_std: float, n_poses: Sequence[int], n_problems: int, repeats: int,
                  batch_problems: int, batch_repeats: int,
                  single_methods: Sequence[str] = tuple(SINGLE_METHODS),
                  batch_methods: Sequence[str] = tuple(BATCH_METHODS),
                  interleavings: Sequence[str] = ("block", "problem"), als_known_noise: bool = True,
                  nlls_known_noise: bool = True,
                  stage: str = "burkhard2024_timing") -> tuple[pd.DataFrame, pd.DataFrame]:
    """The whole benchmark, one pose count after the other: problems from the stream
    ``grid_seed(seed, stage, n)``, interleaved single-problem timings (every
    interleaving) and batched throughput.  Full methods get data with ``M ≠ I``;
    bias-only methods the same directions, bias and noise draw with ``M = I``.  A method
    is skipped at a pose count below its minimum (10 full, 4 bias-only).

    Returns ``(single, batched)`` raw timing tables, each with an ``n_poses`` column.
    """
    fns = {m: SINGLE_METHODS[m] for m in single_methods}
    if "full_als" in fns and als_known_noise:  # as in the Monte Carlo: ALS is told the noise std
        fns["full_als"] = partial(full_als, noise_std=noise_std)
    for m in ("full_nlls", "bias_nlls"):  # and NLLS, for its stopping tolerance
        if m in fns and nlls_known_noise:
            fns[m] = partial(SINGLE_METHODS[m], noise_std=noise_std)
    singles, batches = [], []
    for n in n_poses:
        n = int(n)
        ss_single, ss_batch = grid_seed(seed, stage, n).spawn(2)
        zf = make_problems(np.random.default_rng(ss_single), n_problems, n, g, noise_std)
        zb = make_problems(np.random.default_rng(ss_single), n_problems, n, g, noise_std, identity_m=True)
        here = {m: f for m, f in fns.items() if n >= min_poses(m)}
        problems = {m: (zb if m.startswith("bias") else zf) for m in here}
        for il in interleavings:
            singles.append(time_interleaved(problems, g, here, repeats, interleave=il).assign(n_poses=n))
        bm = [m for m in batch_methods if n >= min_poses(m.removesuffix("_batch"))]
        if bm and batch_problems > 0:
            zbf = make_problems(np.random.default_rng(ss_batch), batch_problems, n, g, noise_std)
            zbb = make_problems(np.random.default_rng(ss_batch), batch_problems, n, g, noise_std, identity_m=True)
            bproblems = {m: (zbb if m.startswith("bias") else zbf) for m in bm}
            batches.append(time_batched(bproblems, g, {m: BATCH_METHODS[m] for m in bm}, batch_repeats)
                           .assign(n_poses=n))
    single = pd.concat(singles, ignore_index=True)
    single = single[["n_poses"] + [c for c in single.columns if c != "n_poses"]]
    batched = pd.concat(batches, ignore_index=True) if batches else pd.DataFrame(
        columns=["n_poses", "method", "repeat", "n_problems", "seconds", "problems_per_s"])
    batched = batched[["n_poses"] + [c for c in batched.columns if c != "n_poses"]]
    return single, batched


__all__ = [
    "BASELINE",
    "BATCH_METHODS",
    "SINGLE_METHODS",
    "make_problems",
    "run_benchmark",
    "summarize_timing",
    "time_batched",
    "time_interleaved",
]
