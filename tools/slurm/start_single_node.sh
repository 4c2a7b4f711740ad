#!/bin/bash
# Start a private single-node SLURM cluster on this machine, for tests and for trying the
# SLURM profile (profiles/slurm/) without a real cluster.
#
#     sudo tools/slurm/install_packages.sh          # once: Debian's slurmctld, slurmd, slurm-client, munge
#     tools/slurm/start_single_node.sh DIR          # as root; prints `export SLURM_CONF=...`
#     . DIR/env && sinfo            # SLURM_CONF and PATH && .venv/bin/snakemake all --workflow-profile profiles/slurm
#     tools/slurm/stop_single_node.sh DIR
#
# Everything belongs to DIR: the configuration (DIR/etc/slurm.conf), a munge key and socket
# of its own, state, spool and logs (DIR/log/).  The SLURM commands find this cluster through
# SLURM_CONF (DIR/env), so a system-wide SLURM or munge (/etc/slurm, /run/munge) is neither
# needed nor touched.  The daemons run directly (no systemd): munged, slurmctld and slurmd
# in the foreground of their own sessions; their PIDs go to DIR/pids, and only those are
# stopped by stop_single_node.sh.  No cgroups: ProctrackType=proctrack/linuxproc,
# TaskPlugin=task/none.  No accounting storage (sacct answers "Slurm accounting storage is
# disabled"), as on many small clusters.
#
# The node is this machine: its hostname, all its CPUs, 90 % of its memory; two partitions,
# `main` (the default) and `other` (to check that a chosen partition is used).  Ports: the
# first free pair from 16817 up (override with SLURMCTLD_PORT / SLURMD_PORT).  MinJobAge is
# SLURM's default (300 s): finished jobs stay visible to squeue that long.
set -euo pipefail

usage() { echo "usage: $0 STATE_DIR   (as root; STATE_DIR is created or must be empty)" >&2; exit 2; }
[ $# -eq 1 ] || usage
die() { echo "start_single_node: $*" >&2; exit 1; }

[ "$(id -u)" -eq 0 ] || die "must run as root (slurmd starts jobs as their users)"
for cmd in munged slurmctld slurmd sbatch squeue sinfo scontrol; do
    command -v "$cmd" >/dev/null || die "$cmd not found: install the packages first (sudo tools/slurm/install_packages.sh)"
done

mkdir -p "$1"
DIR=$(cd "$1" && pwd)
[ -z "$(ls -A "$DIR")" ] || die "$DIR is not empty"
mkdir -p "$DIR"/{etc,munge,log,state,spool}
chmod 0755 "$DIR"
chmod 0755 "$DIR/munge"  # munged: clients need to reach the socket

port_free() { ! (exec 3<>"/dev/tcp/127.0.0.1/$1") 2>/dev/null; }
CTLD_PORT=${SLURMCTLD_PORT:-}
D_PORT=${SLURMD_PORT:-}
if [ -z "$CTLD_PORT" ]; then
    for p in $(seq 16817 2 16999); do
        if port_free "$p" && port_free $((p + 1)); then CTLD_PORT=$p; D_PORT=$((p + 1)); break; fi
    done
    [ -n "$CTLD_PORT" ] || die "no free port pair in 16817-17000"
fi

NODE=$(hostname -s)
CPUS=$(nproc)
MEM_MB=$(awk '/^MemTotal:/ {printf "%d", $2 / 1024 * 0.9}' /proc/meminfo)

# munge: a key of its own (1024 random bytes, mode 0400 as munged requires)
dd if=/dev/urandom of="$DIR/munge/munge.key" bs=1024 count=1 status=none
chmod 0400 "$DIR/munge/munge.key"

cat > "$DIR/etc/slurm.conf" <<CONF
# Written by tools/slurm/start_single_node.sh: a private single-node cluster in $DIR
ClusterName=accelcal-test
SlurmctldHost=$NODE(127.0.0.1)
SlurmctldPort=$CTLD_PORT
SlurmdPort=$D_PORT
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$DIR/munge/munge.socket
StateSaveLocation=$DIR/state
SlurmdSpoolDir=$DIR/spool/slurmd-%n
SlurmctldPidFile=$DIR/state/slurmctld.pid
SlurmdPidFile=$DIR/spool/slurmd.pid
SlurmctldLogFile=$DIR/log/slurmctld.log
SlurmdLogFile=$DIR/log/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
# no cgroups, no systemd
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SwitchType=switch/none
MpiDefault=none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
ReturnToService=2
MinJobAge=300
# a cancelled or timed-out job gets SIGTERM, then SIGKILL after KillWait seconds
KillWait=5
NodeName=$NODE NodeAddr=127.0.0.1 CPUs=$CPUS RealMemory=$MEM_MB State=UNKNOWN
PartitionName=main Nodes=$NODE Default=YES MaxTime=INFINITE State=UP
PartitionName=other Nodes=$NODE MaxTime=INFINITE State=UP
CONF
# The SLURM commands find this cluster through SLURM_CONF.  One exception: inside every job,
# snakemake-executor-plugin-slurm-jobstep (0.6.1) starts `srun` with every SLURM_* variable
# removed but a few job ids, SLURM_CONF included, so that srun looks for /etc/slurm/slurm.conf
# and fails ("Could not establish a configuration source").  A real cluster has that file;
# this one gets an `srun` first on PATH that puts SLURM_CONF back.
mkdir -p "$DIR/bin"
cat > "$DIR/bin/srun" <<SRUN
#!/bin/sh
SLURM_CONF=$DIR/etc/slurm.conf exec $(command -v srun) "\$@"
SRUN
chmod +x "$DIR/bin/srun"
cat > "$DIR/env" <<ENV
export SLURM_CONF=$DIR/etc/slurm.conf
export PATH=$DIR/bin:\$PATH
ENV
export SLURM_CONF=$DIR/etc/slurm.conf

# start one daemon in the foreground of its own session, output to its log; record its PID
# with its start time (stop_single_node.sh checks both, so a reused PID is never killed)
start() {
    local name=$1; shift
    setsid "$@" < /dev/null >> "$DIR/log/$name.out" 2>&1 &
    local pid=$!
    sleep 0.2
    kill -0 "$pid" 2>/dev/null || { cat "$DIR/log/$name.out" >&2; stop_started; die "$name exited at once"; }
    echo "$name $pid $(awk '{print $22}' "/proc/$pid/stat")" >> "$DIR/pids"
}
stop_started() { "$(dirname "$0")/stop_single_node.sh" --keep "$DIR" >&2 || true; }

start munged munged --foreground --force --socket="$DIR/munge/munge.socket" \
    --key-file="$DIR/munge/munge.key" --pid-file="$DIR/munge/munged.pid" \
    --log-file="$DIR/log/munged.log" --seed-file="$DIR/munge/munged.seed"
for _ in $(seq 50); do [ -S "$DIR/munge/munge.socket" ] && break; sleep 0.1; done
[ -S "$DIR/munge/munge.socket" ] || { stop_started; die "munged did not create its socket (see $DIR/log/munged.*)"; }

start slurmctld slurmctld -D -f "$SLURM_CONF"
start slurmd slurmd -D -f "$SLURM_CONF" -N "$NODE"

# ready when the node is idle
for _ in $(seq 120); do
    state=$(sinfo -h -n "$NODE" -p main -o %T 2>/dev/null || true)
    [ "$state" = idle ] && break
    sleep 0.5
done
if [ "${state:-}" != idle ]; then
    tail -n 20 "$DIR"/log/slurm*.log >&2 || true
    stop_started
    die "node $NODE not idle after 60 s (state: ${state:-no answer}); logs in $DIR/log"
fi
cat "$DIR/env"
