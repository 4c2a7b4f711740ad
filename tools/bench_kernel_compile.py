"""numba's cold compile of the kernels, before/after side by side, in fresh processes.

Every fresh clone compiles the kernels once (disk cache, :mod:`accelcal.kernels`).  This
measures what that costs on the workflow's heaviest first user, the discrepancy report of
one measured recording (the job ``discrepancy_measured_report``: both layers, the default
config's rules and stochastic settings), for one or two source trees side by side:

* ``cold``: CPU of a fresh process with an empty ``NUMBA_CACHE_DIR`` (it compiles what it calls);
* ``warm``: CPU of the same run again, loading everything from that cache;
* with ``--per-module``: per kernel module, CPU of a run whose cache holds every other
  module's kernels (that module's compile, in the real callers' signatures) minus ``warm``;
* the sha256 of the report's JSON (the outputs must be byte-identical between trees);
* with ``--signatures``: per kernel, its compiled signatures and numba's compile timers.

Trees alternate within each round (``--rounds``), so that load drifts hit both alike.
A tree is a folder holding ``src/`` and ``config/`` (e.g. ``git archive REV | tar -x -C DIR``)::

    .venv/bin/python tools/bench_kernel_compile.py --csv results/measured/fxos8700_sample2.csv \
        --tree before=/tmp/before --tree after=. --rounds 3 --per-module
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

#: The kernel modules whose disk-cache files ``--per-module`` removes one at a time (file stem
#: of each module: numba names its cache files ``<stem>.<function>-<line>.py3xx.{nbi,nbc}``).
MODULES = ("_fit_kernels", "_fast", "_grid_kernels", "_lls_kernels", "_parse_kernels", "_filter_kernels",
           "_estimator_kernels")


def _digest(h, *outputs) -> None:
    """Add the bytes of every array (or number) in ``outputs`` to the hash ``h``."""
    for o in outputs:
        if isinstance(o, tuple):
            _digest(h, *o)
        else:
            h.update(np.ascontiguousarray(o).tobytes())


def _fit_calls(h) -> None:
    """The fits' three entry points, in the argument types of their callers
    (:mod:`accelcal.discrepancy.fit`, :mod:`accelcal.discrepancy.residuals`): a polynomial
    and an additive effect, then a harmonic one (the coupled Newton)."""
    from accelcal.discrepancy import _fit_kernels as K

    rng = np.random.default_rng(0)
    n = 24
    z = rng.normal(size=(n, 3))
    z /= np.linalg.norm(z, axis=1, keepdims=True)
    poly = (rng.normal(size=(2, n)), np.array([2, 0], np.int64), np.array([False, True]), np.zeros(2, np.bool_),
            np.zeros((2, 1, 3, 3, 3)))
    harm = (np.ones((1, n)), np.array([2], np.int64), np.array([False]), np.array([True]),
            0.01 * rng.normal(size=(1, 4, 3, 3, 3)))
    for arrays, q in ((poly, 15), (harm, 13)):
        p = 0.01 * rng.normal(size=q)
        sig = np.full(n, 0.01)
        _digest(h, K.lm_fit(p, z * 1.01 + 0.02, *arrays, 1.0, 1e-12, sig, 50, 1e-10))
        _digest(h, K.lopo_step(p + 0.001 * rng.normal(size=(n, q)), z, *arrays, 1.0, 1e-12, sig, True))
        _digest(h, K.lopo_step(p + 0.001 * rng.normal(size=(n, q)), z, *arrays, 1.0, 1e-12, sig, False))
        _digest(h, K.evaluate_batch(p + 0.001 * rng.normal(size=(3, q)), z, *arrays, 1.0, True, 1e-12)[::2])


def _noise_calls(h) -> None:
    """The stochastic layer's three kernels, in their callers' argument types (one read-only)."""
    from accelcal.noise import _fast as F

    rng = np.random.default_rng(0)
    H = np.abs(rng.normal(size=(4, 10, 3)))
    y = H @ np.array([1.0, 0.0, 2.0]) * (1 + 0.1 * rng.normal(size=(4, 10)))
    _digest(h, F.irls_gamma(H, y, np.ones(10)))
    _digest(h, F.irls_gamma(np.broadcast_to(H[0], (1, 10, 3)), y[:1], np.ones(10)))
    s = rng.normal(size=(1000, 3))
    _digest(h, F.allan_sums(s, s.mean(axis=0), np.array([1, 2, 4, 8, 16], np.int64)))
    s.flags.writeable = False
    _digest(h, F.allan_sums(s, s.mean(axis=0), np.array([1, 3, 9], np.int64)))
    _digest(h, F.ar1(s, 0.5))


def _grid_calls(h) -> None:
    """The wander grid's kernel."""
    from accelcal.discrepancy.wander import _grid_kernels as W

    rng = np.random.default_rng(0)
    _digest(h, W.grid_minima(rng.normal(size=(2, 3, 4, 5)), rng.uniform(size=(2, 3, 6, 5)), rng.uniform(size=(3, 6)),
                             rng.normal(size=(3, 6)), 5.0, 0.1, 10.0))


def _first_calls(h) -> None:
    """The calls of the ``kernel_cache`` job (:func:`accelcal_repro.first_calls.kernel_first_calls`:
    every estimator's compiled kernels, the filters', Tereshkov's), their results hashed."""
    import pickle

    from accelcal_repro.first_calls import kernel_first_calls

    for _, call in kernel_first_calls():
        h.update(pickle.dumps(call(), protocol=4))


CALLS = {"fit": _fit_calls, "noise": _noise_calls, "grid": _grid_calls, "first": _first_calls}


def _worker(args) -> None:
    """One discrepancy report in this process, as the workflow's script makes it; prints a
    JSON line (CPU seconds, the report's sha256, and the kernels' signatures if asked)."""
    if args.calls:
        t0 = time.process_time()
        h = hashlib.sha256()
        for name in args.calls.split(","):
            CALLS[name](h)
        line = {"cpu": time.process_time() - t0, "sha256": h.hexdigest(), "loaded": []}
        if args.signatures:
            line["kernels"] = _signatures({m.removeprefix("accelcal."): sys.modules[m] for m in sorted(sys.modules)
                                           if m.startswith("accelcal.") and m.rsplit(".", 1)[-1] in MODULES})
        print(json.dumps(line))
        return
    import yaml

    from accelcal import kernels
    from accelcal.discrepancy.report import StochasticSettings, discrepancy_report
    from accelcal.discrepancy.rules import Rules
    from accelcal.formats import read
    from accelcal.jsonsafe import json_safe
    from accelcal_repro.discrepancy.sessions import with_disjoint_rests
    from accelcal_repro.measured.sources import source

    cfg = yaml.safe_load(open(os.path.join(args.tree_dir, "config", "config.yaml")))
    name = os.path.basename(args.csv).removesuffix(".csv")
    g = cfg["measured"]["recordings"][name]["g"]
    t0 = time.process_time()
    rec, note = with_disjoint_rests(read(args.csv, strict=True))
    report = discrepancy_report(rec, g, rules=Rules.from_config(cfg["discrepancy"]["rules"]),
                                stochastic=StochasticSettings.from_config(cfg["discrepancy"]["stochastic"]),
                                unit=source(name).unit)
    out = report.to_dict()
    out.update({"recording": name, "g": g, "unit": source(name).unit, "rate": rec.rate})
    if note:
        out["notes"] = [*out.get("notes", []), note]
    text = json.dumps(json_safe(out), indent=1, sort_keys=False) + "\n"
    cpu = time.process_time() - t0
    line = {"cpu": cpu, "sha256": hashlib.sha256(text.encode()).hexdigest(), "loaded": sorted(kernels._loaded)}
    if args.signatures:
        line["kernels"] = _signatures(kernels._loaded)
    if args.json_out:
        with open(args.json_out, "w") as fh:
            fh.write(text)
    print(json.dumps(line))


def _signatures(loaded: dict) -> dict:
    """Per kernel: its signatures, with numba's compile timers of each (all, and LLVM's part;
    nested: a caller's time includes its callees' compiles)."""
    from numba.core.registry import CPUDispatcher

    found = {}
    for modname, mod in loaded.items():
        for attr, obj in vars(mod).items():
            if isinstance(obj, CPUDispatcher) and obj.signatures:
                rows = []
                for sig in obj.signatures:
                    timers = obj.get_metadata(sig).get("timers", {}) if obj.overloads[sig].metadata else {}
                    rows.append([str(sig), round(timers.get("compiler_lock", 0.0), 2),
                                 round(timers.get("llvm_lock", 0.0), 2)])
                found[f"{modname}.{attr}"] = rows
    return found


def _run(tree: str, cache: str, args, signatures: bool = False) -> dict:
    """One worker in a fresh process on ``tree`` with ``cache`` as numba's cache folder."""
    env = {**os.environ, "NUMBA_CACHE_DIR": cache, "PYTHONPATH": os.path.join(tree, "src"),
           "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
    cmd = [sys.executable, os.path.abspath(__file__), "--worker", "--tree-dir", tree, "--csv", args.csv or ""]
    if args.calls:
        cmd += ["--calls", args.calls]
    if signatures:
        cmd.append("--signatures")
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    done = subprocess.run(cmd, env=env, capture_output=True, text=True, check=False)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode:
        raise SystemExit(f"worker failed on {tree}:\n{done.stderr[-3000:]}")
    line = json.loads(done.stdout.strip().splitlines()[-1])
    line["process_cpu"] = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return line


def _without(cache: str, stem: str, into: str) -> None:
    """``into``: a copy of the cache folder without the files of kernel module ``stem``."""
    shutil.copytree(cache, into, ignore=lambda d, names: [n for n in names if n.startswith(stem + ".")])


def _round(trees: dict, args, order: list) -> dict:
    rows = {}
    for label in order:
        tree = trees[label]
        with tempfile.TemporaryDirectory(prefix="nbcache-") as tmp:
            cache = os.path.join(tmp, "cache")
            os.makedirs(cache)
            cold = _run(tree, cache, args, signatures=args.signatures)
            warm = _run(tree, cache, args)
            row = {"cold": cold["process_cpu"], "warm": warm["process_cpu"], "sha256": cold["sha256"],
                   "sha256_warm": warm["sha256"]}
            if args.signatures:
                row["kernels"] = cold["kernels"]
            if args.per_module:
                for stem in MODULES:
                    part = os.path.join(tmp, stem)
                    _without(cache, stem, part)
                    row[stem] = _run(tree, part, args)["process_cpu"] - warm["process_cpu"]
            rows[label] = row
        print(json.dumps({"tree": label, **{k: (round(v, 2) if isinstance(v, float) else v)
                                             for k, v in row.items() if k != "kernels"}}), flush=True)
    return rows


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--csv", help="a measured recording's canonical CSV (results/measured/NAME.csv)")
    ap.add_argument("--calls", help=f"instead of the report, only these modules' kernels ({', '.join(CALLS)})")
    ap.add_argument("--tree", action="append", default=[], help="LABEL=DIR (a folder with src/ and config/)")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--per-module", action="store_true", help="also each kernel module's cold compile alone")
    ap.add_argument("--signatures", action="store_true", help="print each kernel's signatures and timers")
    ap.add_argument("--out", help="write every round's numbers here (JSON)")
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--tree-dir", help=argparse.SUPPRESS)
    ap.add_argument("--json-out", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.worker:
        return _worker(args)
    if not (args.csv or args.calls):
        ap.error("give --csv or --calls")
    args.csv = args.csv and os.path.abspath(args.csv)
    trees = dict(t.split("=", 1) for t in (args.tree or [f"here={os.getcwd()}"]))
    trees = {k: os.path.abspath(v) for k, v in trees.items()}
    labels = list(trees)
    rounds = []
    for i in range(args.rounds):
        rounds.append(_round(trees, args, labels if i % 2 == 0 else labels[::-1]))
        if args.signatures:
            for label, row in rounds[-1].items():
                print(f"--- {label}: signatures (cold; numba's timers, nested: all / in LLVM, s)")
                for name, sigs in sorted(row["kernels"].items()):
                    for sig, t, t_llvm in sigs:
                        print(f"  {name:45s} {t:6.2f} {t_llvm:6.2f}  {sig}")
    print("summary (median over rounds, CPU s):")
    keys = [k for k in rounds[0][labels[0]] if k not in ("sha256", "sha256_warm", "kernels")]
    for k in keys:
        vals = {lb: sorted(r[lb][k] for r in rounds) for lb in labels}
        print(f"  {k:18s} " + "  ".join(f"{lb} {v[len(v) // 2]:7.2f} [{v[0]:.2f}-{v[-1]:.2f}]"
                                          for lb, v in vals.items()))
    shas = {r[lb][s] for r in rounds for lb in labels for s in ("sha256", "sha256_warm")}
    print(f"  report sha256: {'identical' if len(shas) == 1 else 'DIFFERENT'} ({', '.join(sorted(shas))})")
    if args.out:
        with open(args.out, "w") as fh:
            json.dump(rounds, fh, indent=1)


if __name__ == "__main__":
    main()
