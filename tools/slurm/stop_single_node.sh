#!/bin/bash
# Stop the single-node SLURM started by start_single_node.sh in DIR: cancel its jobs, stop
# exactly the daemons listed in DIR/pids (a PID is signalled only while its start time
# still matches the one recorded, so a reused PID is never hit) and remove DIR.
#
#     tools/slurm/stop_single_node.sh [--keep] DIR    # --keep: leave DIR (logs) in place
set -euo pipefail

keep=false
if [ "${1:-}" = --keep ]; then keep=true; shift; fi
[ $# -eq 1 ] || { echo "usage: $0 [--keep] STATE_DIR" >&2; exit 2; }
DIR=$(cd "$1" 2>/dev/null && pwd) || { echo "stop_single_node: no such directory: $1" >&2; exit 0; }
PIDS=$DIR/pids

# is this recorded process still the one we started?
ours() { [ -r "/proc/$2/stat" ] && [ "$(awk '{print $22}' "/proc/$2/stat" 2>/dev/null)" = "$3" ]; }

if [ -f "$PIDS" ]; then
    if grep -q '^slurmctld ' "$PIDS" && ours $(grep '^slurmctld ' "$PIDS"); then
        # cancel every job of this cluster and wait (30 s at most) until none is left
        # running: their processes (slurmstepd and below) would outlive slurmd
        export SLURM_CONF=$DIR/etc/slurm.conf
        jobs=$(squeue -h -o %A 2>/dev/null || true)
        if [ -n "$jobs" ]; then
            scancel $jobs 2>/dev/null || true
            for _ in $(seq 60); do
                [ -z "$(squeue -h -t running,completing,configuring -o %A 2>/dev/null)" ] && break
                sleep 0.5
            done
        fi
    fi
    # slurmd first, then slurmctld, then munged (tac: reverse start order)
    tac "$PIDS" | while read -r name pid start; do
        ours "$name" "$pid" "$start" && kill -TERM "$pid" 2>/dev/null || true
    done
    for _ in $(seq 100); do
        alive=false
        while read -r name pid start; do ours "$name" "$pid" "$start" && alive=true; done < "$PIDS"
        $alive || break
        sleep 0.1
    done
    while read -r name pid start; do
        if ours "$name" "$pid" "$start"; then
            echo "stop_single_node: $name ($pid) ignored SIGTERM for 10 s, killing it" >&2
            kill -KILL "$pid" 2>/dev/null || true
        fi
    done < "$PIDS"
fi
$keep || rm -rf "$DIR"
