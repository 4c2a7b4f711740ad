"""Benchmark: `snakemake all` through the SLURM profile on a private single-node SLURM,
with the profile's grouping ("grouped") and without it ("ungrouped": one SLURM job per
rule job, the profile otherwise unchanged).

    sudo .venv/bin/python tools/slurm/benchmark_profile.py                      # CI config, both
    sudo .venv/bin/python tools/slurm/benchmark_profile.py --config config/config.yaml --variants grouped

Needs root and the packages of tools/slurm/install_packages.sh.  Starts a cluster of its
own (tools/slurm/start_single_node.sh) and stops it at the end; each variant runs in a
fresh working directory.  Prints one line per variant and appends it to --out (CSV):
SLURM jobs submitted, local jobs, wall time of the run, SLURM node-time (sum over the
SLURM jobs of allocation to completion, from slurmctld's log), the median and longest
SLURM job, and the machine's load average before and after (wall times on a loaded
machine are not comparable with an idle one's).
"""

import argparse
import csv
import datetime
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import yaml

REPO = Path(__file__).resolve().parents[2]
SNAKEMAKE = Path(sys.executable).with_name("snakemake")
TOOLS = REPO / "tools" / "slurm"
PROFILE = REPO / "profiles" / "slurm"


def profile_variant(variant: str, dest: Path) -> Path:
    settings = yaml.safe_load((PROFILE / "config.yaml").read_text())
    if variant == "ungrouped":
        settings.pop("groups")
        settings.pop("group-components")
    dest.mkdir(parents=True)
    (dest / "config.yaml").write_text(yaml.safe_dump(settings, sort_keys=False))
    return dest


def slurm_job_times(ctld_log: Path, ids: set[str]) -> list[float]:
    """Seconds from allocation to completion of each SLURM job in ``ids``."""
    text = ctld_log.read_text()
    start, end = {}, {}
    for ts, jid in re.findall(r"\[(\S+)\] sched(?:/backfill)?: (?:Allocate|_start_job: Started) JobId=(\d+) ", text):
        start[jid] = datetime.datetime.fromisoformat(ts)
    for ts, jid in re.findall(r"\[(\S+)\] _job_complete: JobId=(\d+) done", text):
        end[jid] = datetime.datetime.fromisoformat(ts)
    missing = ids - (set(start) & set(end))
    if missing:
        raise SystemExit(f"benchmark_profile: no start/end in slurmctld's log for SLURM jobs {sorted(missing)}")
    return [(end[j] - start[j]).total_seconds() for j in ids]


def run_variant(variant, config, cluster_env, ctld_log, scratch):
    workdir, profile = scratch / f"work_{variant}", profile_variant(variant, scratch / f"profile_{variant}")
    load_before = os.getloadavg()[0]
    t0 = time.perf_counter()
    proc = subprocess.run([str(SNAKEMAKE), "all", "--snakefile", str(REPO / "Snakefile"), "--directory", str(workdir),
                           "--configfile", str(config), "--workflow-profile", str(profile)],
                          cwd=REPO, env=cluster_env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    text = proc.stdout + proc.stderr
    (scratch / f"{variant}.log").write_text(text)
    if proc.returncode != 0:
        raise SystemExit(f"benchmark_profile: the {variant} run failed (log: {scratch / f'{variant}.log'})")
    ids = set(re.findall(r"^Job \S+ has been submitted with SLURM jobid (\d+) ", text, re.M))
    times = slurm_job_times(ctld_log, ids)
    return {"config": str(config.relative_to(REPO)), "variant": variant, "slurm_jobs": len(ids),
            "local_jobs": len(re.findall(r"^localrule \w+:", text, re.M)), "wall_s": round(wall, 1),
            "node_s": round(sum(times)), "median_job_s": round(statistics.median(times)),
            "longest_job_s": round(max(times)), "load_before": load_before, "load_after": os.getloadavg()[0],
            "date": datetime.datetime.now().isoformat(timespec="seconds")}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--config", type=Path, default=REPO / "config" / "ci.yaml")
    ap.add_argument("--variants", default="ungrouped,grouped")
    ap.add_argument("--out", type=Path, help="CSV file to append the rows to")
    args = ap.parse_args(argv)
    config = args.config.resolve()
    with tempfile.TemporaryDirectory(prefix="accelcal-slurm-bench-") as tmp:
        scratch = Path(tmp)
        state = scratch / "cluster"
        subprocess.run([TOOLS / "start_single_node.sh", state], check=True, stdout=subprocess.DEVNULL)
        try:
            env = dict(os.environ)
            for line in (state / "env").read_text().splitlines():
                name, value = line.removeprefix("export ").split("=", 1)
                env[name] = value.replace("$PATH", os.environ["PATH"])
            rows = []
            for variant in args.variants.split(","):
                row = run_variant(variant, config, env, state / "log" / "slurmctld.log", scratch)
                print(", ".join(f"{k} {v}" for k, v in row.items()), flush=True)
                rows.append(row)
        finally:
            subprocess.run([TOOLS / "stop_single_node.sh", state], check=False)
    if args.out:
        new = not args.out.exists()
        with open(args.out, "a", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0]))
            if new:
                w.writeheader()
            w.writerows(rows)


if __name__ == "__main__":
    main()
