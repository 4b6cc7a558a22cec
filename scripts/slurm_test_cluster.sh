#!/usr/bin/env bash
# A throw-away single-node Slurm cluster on localhost, to test job scripts for real:
# munged, slurmctld and slurmd as root, one node with 2 CPUs, one partition (`debug`).
# Everything (configuration, munge key and socket, state, spool, logs) lives in one
# directory, $RB_SLURM_DIR (default /tmp/reconbench-slurm), so nothing in /etc is
# changed and a system Slurm or munge on the machine is left alone.
#
#   scripts/slurm_test_cluster.sh start     # install if needed, start, wait until idle
#   eval "$(scripts/slurm_test_cluster.sh env)"   # SLURM_CONF for sbatch, sinfo, ...
#   scripts/slurm_test_cluster.sh status
#   scripts/slurm_test_cluster.sh stop      # cancel jobs, stop the daemons (and strays)
#   scripts/slurm_test_cluster.sh install   # only the Debian packages
#
# Accounting: Debian's Slurm 22.05 has no text-file accounting storage, so without
# slurmdbd `sacct` cannot work; finished jobs are logged by jobcomp/filetxt to
# $RB_SLURM_DIR/log/jobcomp.log (JobId, JobName, JobState, ExitCode, ...) and stay in
# `scontrol show job` for MinJobAge (10 minutes).
#
# Environment: RB_SLURM_DIR (state directory), RB_SLURM_PORT (slurmctld port, default
# 6817; slurmd uses the next one), RB_SLURM_CPUS (default 2), RB_SLURM_MEM_MIB (node
# memory, default: MemTotal less 1 GiB), RB_SLURM_TIMEOUT (seconds to wait for the node,
# default 60).
set -euo pipefail

D="${RB_SLURM_DIR:-/tmp/reconbench-slurm}"
CONF="$D/etc/slurm.conf"
PORT="${RB_SLURM_PORT:-6817}"
CPUS="${RB_SLURM_CPUS:-2}"
WAIT_S="${RB_SLURM_TIMEOUT:-60}"
# Set in the daemons' environment: how `stop` finds them (and what they started) by id.
MARK="RB_SLURM_CLUSTER=$D"

log() { echo "slurm_test_cluster: $*" >&2; }
die() {
    log "$*"
    exit 1
}

# Debian packages, installed only when a command is missing (quiet, non-interactive).
install_packages() {
    local missing=0 c
    for c in munged slurmctld slurmd sbatch sinfo squeue scontrol scancel; do
        command -v "$c" >/dev/null || missing=1
    done
    [[ $missing == 0 ]] && return 0
    command -v apt-get >/dev/null || die "Slurm is not installed and there is no apt-get"
    [[ $(id -u) == 0 ]] || die "Slurm is not installed; run as root to install it"
    log "installing slurmctld slurmd slurm-client munge (Debian packages)"
    export DEBIAN_FRONTEND=noninteractive
    local out
    out="$(mktemp)"
    # Bounded: without a reachable package registry apt-get would retry for minutes.
    local apt=(timeout 240 apt-get -o Acquire::http::Timeout=20 -o Acquire::Retries=1)
    if ! { "${apt[@]}" update -qq && "${apt[@]}" install -y -qq --no-install-recommends \
        slurmctld slurmd slurm-client munge; } >"$out" 2>&1; then
        cat "$out" >&2
        rm -f "$out"
        die "installing the Slurm packages failed (apt-get output above)"
    fi
    rm -f "$out"
}

# Node memory in MiB: what the machine has less 1 GiB for the system.
node_mem_mib() {
    if [[ -n ${RB_SLURM_MEM_MIB:-} ]]; then
        echo "$RB_SLURM_MEM_MIB"
        return
    fi
    local kib
    kib=$(awk '/^MemTotal:/ {print $2}' /proc/meminfo)
    echo $((kib / 1024 > 2048 ? kib / 1024 - 1024 : kib / 1024))
}

write_conf() {
    local host mem
    host="$(hostname -s)"
    mem="$(node_mem_mib)"
    mkdir -p "$D/etc"
    : >"$D/etc/plugstack.conf"
    cat >"$CONF" <<EOF
# Written by scripts/slurm_test_cluster.sh: a single-node test cluster.
ClusterName=reconbench
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$PORT
SlurmdPort=$((PORT + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$D/munge/munge.socket
CredType=cred/munge
StateSaveLocation=$D/state
SlurmdSpoolDir=$D/spool
SlurmctldPidFile=$D/run/slurmctld.pid
SlurmdPidFile=$D/run/slurmd.pid
SlurmctldLogFile=$D/log/slurmctld.log
SlurmdLogFile=$D/log/slurmd.log
PlugStackConfig=$D/etc/plugstack.conf
# No cgroups needed: processes are tracked through their parent links.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU_Memory
SchedulerType=sched/builtin
SchedulerParameters=sched_interval=2
MpiDefault=none
ReturnToService=2
JobAcctGatherType=jobacct_gather/linux
JobAcctGatherFrequency=5
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/filetxt
JobCompLoc=$D/log/jobcomp.log
MinJobAge=600
KillWait=10
InactiveLimit=0
SlurmdTimeout=60
MaxArraySize=1001
SlurmdParameters=config_overrides
NodeName=$host NodeAddr=127.0.0.1 CPUs=$CPUS RealMemory=$mem State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
}

# Our own munged on our own socket and key (the key is made once, 0600, root's).
start_munge() {
    mkdir -p "$D/munge"
    chmod 700 "$D/munge"
    if [[ ! -s $D/munge/munge.key ]]; then
        dd if=/dev/urandom of="$D/munge/munge.key" bs=1024 count=1 status=none
    fi
    chmod 600 "$D/munge/munge.key"
    env "$MARK" munged --force \
        --socket="$D/munge/munge.socket" \
        --key-file="$D/munge/munge.key" \
        --pid-file="$D/munge/munged.pid" \
        --seed-file="$D/munge/munged.seed" \
        --log-file="$D/log/munged.log" ||
        die "munged did not start (see $D/log/munged.log)"
}

start() {
    install_packages
    stop_quietly
    rm -rf "$D/state" "$D/spool" "$D/run" "$D/log"
    mkdir -p "$D/state" "$D/spool" "$D/run" "$D/log"
    write_conf
    start_munge
    env "$MARK" SLURM_CONF="$CONF" slurmctld -c -f "$CONF" ||
        die "slurmctld did not start (see $D/log/slurmctld.log)"
    env "$MARK" SLURM_CONF="$CONF" slurmd -f "$CONF" ||
        die "slurmd did not start (see $D/log/slurmd.log)"
    wait_idle
    log "up: $(SLURM_CONF="$CONF" sinfo -h -o '%P %D nodes %c CPUs %m MiB %t')"
    log "use it with: export SLURM_CONF=$CONF"
}

# Waits until sinfo shows the node idle.
wait_idle() {
    local t0=$SECONDS state=""
    while ((SECONDS - t0 < WAIT_S)); do
        state="$(SLURM_CONF="$CONF" timeout 10 sinfo -h -N -o '%t' 2>/dev/null || true)"
        [[ $state == idle ]] && return 0
        sleep 1
    done
    log "node not idle after ${WAIT_S}s (state: '${state:-none}'); last log lines:"
    tail -n 5 "$D/log/slurmctld.log" "$D/log/slurmd.log" >&2 2>/dev/null || true
    exit 1
}

# Process ids of what this cluster started: the daemons (they carry $MARK in their
# environment), the slurmstepd they started (working directory under $D; slurmd does not
# pass its environment on) and all their descendants (the jobs).
cluster_pids() {
    local p cwd marked=()
    for p in /proc/[0-9]*; do
        p="${p#/proc/}"
        [[ $p == "$$" ]] && continue
        if { tr '\0' '\n' <"/proc/$p/environ"; } 2>/dev/null | grep -qxF "$MARK"; then
            marked+=("$p")
        elif [[ "$(cat "/proc/$p/comm" 2>/dev/null)" == slurmstepd ]]; then
            cwd="$(readlink "/proc/$p/cwd" 2>/dev/null || true)"
            [[ $cwd == "$D" || $cwd == "$D"/* ]] && marked+=("$p")
        fi
    done
    ((${#marked[@]})) || return 0
    # Descendants, by walking parent links (ps gives pid and ppid of every process).
    ps -e -o pid=,ppid= | awk -v roots="${marked[*]}" '
        BEGIN { n = split(roots, r, " "); for (i = 1; i <= n; i++) keep[r[i]] = 1 }
        { parent[$1] = $2 }
        END {
            do {
                changed = 0
                for (p in parent) if (!(p in keep) && (parent[p] in keep)) { keep[p] = 1; changed = 1 }
            } while (changed)
            for (p in keep) print p
        }'
}

# Sends TERM to the given pids, waits up to 10 s, then KILLs the ones left.
kill_pids() {
    (($#)) || return 0
    kill -TERM "$@" 2>/dev/null || true
    local left
    for _ in $(seq 1 50); do
        left=()
        for p in "$@"; do
            kill -0 "$p" 2>/dev/null && left+=("$p")
        done
        ((${#left[@]})) || return 0
        sleep 0.2
    done
    kill -KILL "${left[@]}" 2>/dev/null || true
}

# Cancels the jobs (bounded wait), then ends every process the cluster started.
stop_quietly() {
    local ctld
    ctld="$(cat "$D/run/slurmctld.pid" 2>/dev/null || true)"
    if [[ -f $CONF && -n $ctld ]] && kill -0 "$ctld" 2>/dev/null; then
        SLURM_CONF="$CONF" timeout 10 scancel --quiet --user=root 2>/dev/null || true
        local t0=$SECONDS
        while ((SECONDS - t0 < 15)); do
            [[ -z "$(SLURM_CONF="$CONF" timeout 5 squeue -h -o %i 2>/dev/null || true)" ]] && break
            sleep 1
        done
    fi
    local pids
    mapfile -t pids < <(cluster_pids)
    kill_pids "${pids[@]}"
    rm -f "$D/run/"*.pid "$D/munge/munged.pid" "$D/munge/munge.socket"*
}

stop() {
    stop_quietly
    log "stopped (state in $D)"
}

status() {
    if [[ ! -f $CONF ]]; then
        echo "no test cluster in $D"
        return 1
    fi
    SLURM_CONF="$CONF" timeout 10 sinfo || return 1
    SLURM_CONF="$CONF" timeout 10 squeue
}

case "${1:-}" in
install) install_packages ;;
start) start ;;
stop) stop ;;
status) status ;;
env) echo "export SLURM_CONF=$CONF" ;;
*)
    echo "usage: $0 start|stop|status|env|install" >&2
    exit 2
    ;;
esac
