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
# disabled"), as on many small clusters; with --accounting, a MariaDB and slurmdbd of its
# own (packages: install_packages.sh --accounting), the account accelcal_test with root as
# its member, and AccountingStorageEnforce=associations (a job needs a valid account).
#
# The node is this machine: its hostname, all its CPUs, 90 % of its memory; two partitions,
# `main` (the default) and `other` (to check that a chosen partition is used).  Ports: the
# first four free ports from 16817 up (slurmctld, slurmd, slurmdbd, MariaDB; override the
# first with SLURMCTLD_PORT).  MinJobAge is
# SLURM's default (300 s): finished jobs stay visible to squeue that long.
set -euo pipefail

usage() { echo "usage: $0 [--accounting] STATE_DIR   (as root; STATE_DIR is created or must be empty)" >&2; exit 2; }
accounting=false
if [ "${1:-}" = --accounting ]; then accounting=true; shift; fi
[ $# -eq 1 ] || usage
die() { echo "start_single_node: $*" >&2; exit 1; }

[ "$(id -u)" -eq 0 ] || die "must run as root (slurmd starts jobs as their users)"
for cmd in munged slurmctld slurmd sbatch squeue sinfo scontrol; do
    command -v "$cmd" >/dev/null || die "$cmd not found: install the packages first (sudo tools/slurm/install_packages.sh)"
done
if $accounting; then
    for cmd in slurmdbd mariadbd mariadb-install-db mariadb sacctmgr; do
        command -v "$cmd" >/dev/null || die "$cmd not found: install the packages first (sudo tools/slurm/install_packages.sh --accounting)"
    done
fi

mkdir -p "$1"
DIR=$(cd "$1" && pwd)
[ -z "$(ls -A "$DIR")" ] || die "$DIR is not empty"
mkdir -p "$DIR"/{etc,munge,log,state,spool,mysql}
chmod 0755 "$DIR"
chmod 0755 "$DIR/munge"  # munged: clients need to reach the socket

port_free() { ! (exec 3<>"/dev/tcp/127.0.0.1/$1") 2>/dev/null; }
CTLD_PORT=${SLURMCTLD_PORT:-}
if [ -z "$CTLD_PORT" ]; then  # four ports: slurmctld, slurmd, slurmdbd, MariaDB
    for p in $(seq 16817 4 16999); do
        if port_free "$p" && port_free $((p + 1)) && port_free $((p + 2)) && port_free $((p + 3)); then
            CTLD_PORT=$p; break
        fi
    done
    [ -n "$CTLD_PORT" ] || die "no four free ports in 16817-17000"
fi
D_PORT=${SLURMD_PORT:-$((CTLD_PORT + 1))}
DBD_PORT=$((CTLD_PORT + 2))
DB_PORT=$((CTLD_PORT + 3))

NODE=$(hostname -s)
# the CPUs this process may use, not OpenMP's thread count: GNU nproc returns
# $OMP_NUM_THREADS when it is set, and the test suite sets it to 1 (tests/conftest.py), which
# made a one-CPU node of a two-core machine (the SLURM jobs meant to run side by side queued)
CPUS=$(env -u OMP_NUM_THREADS -u OMP_THREAD_LIMIT nproc)
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
$(if $accounting; then
    echo "AccountingStorageType=accounting_storage/slurmdbd"
    echo "AccountingStorageHost=127.0.0.1"
    echo "AccountingStoragePort=$DBD_PORT"
    echo "AccountingStorageEnforce=associations"
    echo "AccountingStoragePass=$DIR/munge/munge.socket"  # the munge socket for slurmdbd
else
    echo "AccountingStorageType=accounting_storage/none"
fi)
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

if $accounting; then
    # MariaDB on a port of its own (files in DIR/mysql), the SLURM database daemon on it, and
    # the cluster, the account accelcal_test and root as its member in the database
    mariadb-install-db --no-defaults --datadir="$DIR/mysql" --user=root --skip-test-db \
        --auth-root-authentication-method=socket > "$DIR/log/mariadb-install.out" 2>&1 \
        || { cat "$DIR/log/mariadb-install.out" >&2; stop_started; die "mariadb-install-db failed"; }
    start mariadbd mariadbd --no-defaults --datadir="$DIR/mysql" --user=root --bind-address=127.0.0.1 \
        --port="$DB_PORT" --socket="$DIR/mysql/mysqld.sock" --pid-file="$DIR/mysql/mysqld.pid" \
        --log-error="$DIR/log/mariadb.log"
    for _ in $(seq 100); do [ -S "$DIR/mysql/mysqld.sock" ] && break; sleep 0.2; done
    DB_PASS=$(od -An -N12 -tx1 /dev/urandom | tr -d ' \n')
    mariadb --no-defaults --socket="$DIR/mysql/mysqld.sock" -u root \
        -e "CREATE USER 'slurm'@'127.0.0.1' IDENTIFIED BY '$DB_PASS'; GRANT ALL ON slurm_acct_db.* TO 'slurm'@'127.0.0.1';" \
        || { stop_started; die "could not create the database user (see $DIR/log/mariadb.log)"; }
    cat > "$DIR/etc/slurmdbd.conf" <<DBD
AuthType=auth/munge
AuthInfo=socket=$DIR/munge/munge.socket
DbdHost=localhost
DbdAddr=127.0.0.1
DbdPort=$DBD_PORT
SlurmUser=root
StorageType=accounting_storage/mysql
StorageHost=127.0.0.1
StoragePort=$DB_PORT
StorageUser=slurm
StoragePass=$DB_PASS
StorageLoc=slurm_acct_db
LogFile=$DIR/log/slurmdbd.log
PidFile=$DIR/state/slurmdbd.pid
DBD
    chmod 0600 "$DIR/etc/slurmdbd.conf"
    start slurmdbd slurmdbd -D
    for _ in $(seq 100); do sacctmgr -n list cluster >/dev/null 2>&1 && break; sleep 0.2; done
    sacctmgr -i add cluster accelcal-test > /dev/null \
        && sacctmgr -i add account accelcal_test Description=tests Organization=accelcal > /dev/null \
        && sacctmgr -i add user root Account=accelcal_test > /dev/null \
        || { stop_started; die "sacctmgr could not set up the cluster's accounts (see $DIR/log/slurmdbd.log)"; }
fi
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
