"""Per test module: CPU (the xdist worker's own and its finished subprocesses', e.g. a
Snakemake run and its jobs), summed phase seconds, first start and last end [s from the
run's start] and worker, from the files a test run writes with $ACCELCAL_TEST_TIMELINE
(tests/conftest.py):

    ACCELCAL_TEST_TIMELINE=/tmp/tl .venv/bin/python -m pytest
    .venv/bin/python tools/test_timeline.py /tmp/tl [N]

A module's CPU is the worker's CPU counter at its last phase minus the counter at the
phase before its first one, so a session fixture is charged to the module that made it
(the CI workflow run: test_workflow.py's first setup).  Not counted: processes that are
not the worker's waited-for children (the real-SLURM module's daemons and SLURM jobs).
"""

import sys
from collections import Counter
from pathlib import Path


def read(folder: Path):
    """{worker: [(end time, phase, seconds, module, cpu so far)]} of the workers' files."""
    runs = {}
    for path in sorted(folder.glob("gw*.tsv")) or sorted(folder.glob("master.tsv")):
        rows = []
        for line in path.read_text().splitlines():
            t, worker, when, seconds, nodeid, cpu = line.split("\t")
            rows.append((float(t), when, float(seconds), nodeid.split("::")[0].rsplit("/", 1)[-1], float(cpu)))
        runs[path.stem] = rows
    return runs


def table(runs):
    """(per-module rows sorted by CPU, total CPU, run start, run end)."""
    cpu, phases, span = Counter(), Counter(), {}
    t0 = min(t - s for rows in runs.values() for t, _, s, _, _ in rows)
    t1 = max(t for rows in runs.values() for t, *_ in rows)
    for worker, rows in runs.items():
        before = 0.0
        for t, when, seconds, module, counter in rows:
            cpu[module] += counter - before
            before = counter
            phases[module] += seconds
            first, last, _ = span.get(module, (t - seconds, t, worker))
            span[module] = (min(first, t - seconds), max(last, t), worker)
    out = [(m, c, phases[m], span[m][0] - t0, span[m][1] - t0, span[m][2]) for m, c in cpu.most_common()]
    return out, sum(cpu.values()), t0, t1


def main(folder: str, n: str = "40") -> None:
    rows, total, t0, t1 = table(read(Path(folder)))
    print(f"{len(rows)} modules, {total:.1f} CPU-s counted, {t1 - t0:.1f} s from the first phase to the last")
    print(f"| module | CPU s | phases s | start s | end s | worker |\n|---|---:|---:|---:|---:|---|")
    for module, c, p, a, b, w in rows[:int(n)]:
        print(f"| {module} | {c:.1f} | {p:.1f} | {a:.0f} | {b:.0f} | {w} |")


if __name__ == "__main__":
    main(*sys.argv[1:])
