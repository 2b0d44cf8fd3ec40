#!/usr/bin/env bash
# slurm-local.sh - run a real, single-node Slurm cluster on this machine for
# tests and CI, without touching /etc/slurm, /etc/munge or any init system.
#
#   tools/slurm-local.sh start          STATE_DIR   # write config, start munged+slurmctld+slurmd
#   tools/slurm-local.sh stop           STATE_DIR   # cancel jobs, stop daemons (idempotent)
#   tools/slurm-local.sh status         STATE_DIR   # print sinfo; exit 0 when the node is usable
#   tools/slurm-local.sh restart-slurmd STATE_DIR   # (re)start slurmd only, e.g. after kill -9
#
# After `start`, run `source STATE_DIR/env.sh` (or eval the printed export
# line) so sbatch/squeue/sacct/scancel talk to this cluster.
#
# Needs Debian's slurm-wlm (22.05) and munge packages; this script never
# installs anything. It must run as root: slurmd has to be able to start jobs
# as the submitting user, and SlurmUser=root avoids creating a slurm account.
#
# Why the configuration looks the way it does:
# - Everything (config, state, spool, logs, pid files, munge key and socket)
#   lives in STATE_DIR, so two checkouts or CI jobs do not share state and
#   `rm -rf STATE_DIR` after `stop` leaves the machine as it was. Clients find
#   the config through SLURM_CONF and the munge socket through AuthInfo.
# - Containers and CI runners rarely delegate cgroups, so process tracking uses
#   proctrack/linuxproc (parent/child walk of /proc) and task/none; no
#   cgroup.conf is written and no cgroup plugin is loaded. Consequence: --mem
#   is used for scheduling only, it is NOT enforced on the running job.
# - select/cons_tres + CR_Core_Memory makes --mem count against the node's
#   RealMemory, so memory-hungry array tasks are not started together.
#   DefMemPerCPU keeps jobs that do not pass --mem from claiming the whole node.
# - There is no slurmdbd: `sacct` alone says accounting is disabled, but
#   jobcomp/filetxt records every finished job, and `sacct -c` reads that file
#   (state, exit code, times; no MaxRSS). MinJobAge keeps finished jobs in
#   squeue/scontrol for a while so callers can also read their final state.
# - Short SlurmdTimeout/ping settings so a dead slurmd is noticed in seconds,
#   not minutes; ReturnToService=2 lets a restarted slurmd bring the node back
#   without an admin `scontrol update`.
set -euo pipefail

prog=${0##*/}
# The daemons and munge tools live in sbin, which CI shells may not have in PATH.
PATH=$PATH:/usr/sbin:/sbin

die() {
    printf '%s: error: %s\n' "$prog" "$*" >&2
    exit 1
}

usage() {
    printf 'usage: %s {start|stop|status|restart-slurmd} STATE_DIR\n' "$prog" >&2
    exit 2
}

[[ $# -eq 2 ]] || usage
cmd=$1
case $cmd in
    start | stop | status | restart-slurmd) ;;
    *) usage ;;
esac
[[ -n $2 ]] || usage
if [[ ! -d $2 ]]; then
    case $cmd in
        start) mkdir -p -- "$2" || die "cannot create state directory $2" ;;
        stop) exit 0 ;;
        *) die "state directory $2 does not exist" ;;
    esac
fi
state=$(cd -- "$2" && pwd -P) || die "cannot use state directory $2"

conf=$state/slurm.conf
ctld_port=${SLURM_LOCAL_CTLD_PORT:-6817}
slurmd_port=${SLURM_LOCAL_SLURMD_PORT:-6818}
munge_dir=$state/munge
munge_sock=$munge_dir/munge.socket
export SLURM_CONF=$conf

# Slurm and munged refuse unix socket paths longer than sun_path allows.
((${#munge_sock} < 100)) || die "state directory path too long for the munge socket: $munge_sock"

need_cmds() {
    local c missing=()
    for c in "$@"; do
        command -v "$c" >/dev/null 2>&1 || missing+=("$c")
    done
    ((${#missing[@]} == 0)) ||
        die "missing ${missing[*]}; install with: apt-get install --no-install-recommends slurm-wlm munge"
}

# pid_alive PIDFILE NAME: prints the pid when the pid file names a live
# process whose command is NAME (guards against recycled pids).
pid_alive() {
    local pid
    [[ -r $1 ]] || return 1
    pid=$(<"$1")
    [[ $pid =~ ^[0-9]+$ ]] || return 1
    [[ -r /proc/$pid/comm && $(<"/proc/$pid/comm") == "$2" ]] || return 1
    printf '%s\n' "$pid"
}

# stop_daemon PIDFILE NAME: SIGTERM, wait up to 20 s, then SIGKILL.
stop_daemon() {
    local pid i
    pid=$(pid_alive "$1" "$2") || { rm -f -- "$1"; return 0; }
    kill -TERM "$pid" 2>/dev/null || true
    for ((i = 0; i < 200; i++)); do
        [[ -d /proc/$pid ]] || break
        sleep 0.1
    done
    if [[ -d /proc/$pid ]]; then
        printf '%s: %s (pid %s) ignored SIGTERM, killing it\n' "$prog" "$2" "$pid" >&2
        kill -KILL "$pid" 2>/dev/null || true
        while [[ -d /proc/$pid ]]; do sleep 0.1; done
    fi
    rm -f -- "$1"
}

show_logs() {
    local f
    for f in "$state"/log/*.log; do
        [[ -e $f ]] || continue
        printf '==== %s (last 30 lines) ====\n' "$f" >&2
        tail -n 30 -- "$f" >&2
    done
}

# node_ok: true when the controller answers and the node is neither down,
# drained nor unresponsive (sinfo marks the latter with a trailing '*').
node_ok() {
    local st
    st=$(timeout 10 sinfo -h -N -o '%T' 2>/dev/null) || return 1
    [[ -n $st ]] || return 1
    case $st in
        *'*'* | *down* | *drain* | *fail* | *unknown* | *not_responding*) return 1 ;;
    esac
    return 0
}

# daemon_died PIDFILE NAME: true when the daemon wrote its pid file and is
# gone again (e.g. fatal config error), so waiting longer is pointless.
daemon_died() {
    [[ -s $1 ]] && ! pid_alive "$1" "$2" >/dev/null
}

# wait_node_ok: up to 30 s for the node to become usable; fails early when
# slurmctld or slurmd has exited.
wait_node_ok() {
    local deadline=$((SECONDS + 30))
    while ((SECONDS < deadline)); do
        node_ok && return 0
        if daemon_died "$state/run/slurmctld.pid" slurmctld ||
            daemon_died "$state/run/slurmd.pid" slurmd; then
            return 1
        fi
        sleep 0.1
    done
    return 1
}

# port_in_use PORT: true when something already listens on 127.0.0.1:PORT.
port_in_use() {
    (: <>"/dev/tcp/127.0.0.1/$1") 2>/dev/null
}

write_config() {
    local host cpus topo memkb realmem defmem
    host=$(hostname -s) || die "hostname -s failed"
    [[ -n $host ]] || die "hostname -s is empty"
    # slurmctld only starts on a host named in SlurmctldHost, and slurmd picks
    # its NodeName from the hostname; the explicit 127.0.0.1 addresses avoid
    # depending on the hostname resolving to anything reachable.
    cpus=$(nproc)
    # slurmd -C reports the socket/core/thread layout; a NodeName line that
    # disagrees with it makes slurmd register the node as invalid/drained.
    topo=$(slurmd -C 2>/dev/null | sed -n 's/^NodeName=[^ ]* \(CPUs=.*\) RealMemory=.*/\1/p')
    [[ -n $topo ]] || topo="CPUs=$cpus"
    memkb=$(awk '/^MemAvailable:/ {print $2}' /proc/meminfo)
    [[ $memkb =~ ^[0-9]+$ ]] || die "cannot read MemAvailable from /proc/meminfo"
    # Stay below what is free now: a RealMemory above what slurmd measures
    # drains the node ("Low RealMemory"), and the OS needs some headroom.
    ((memkb >= 300 * 1024)) || die "only $((memkb / 1024)) MiB of memory available, need at least 300 MiB"
    realmem=$((memkb * 9 / 10 / 1024))
    defmem=$((realmem / cpus))
    ((defmem <= 1024)) || defmem=1024

    cat >"$conf" <<EOF
# Generated by $prog for a throw-away local test cluster; see that script.
ClusterName=osgbtf-local
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
AuthType=auth/munge
CredType=cred/munge
# cred_expire is also the delay before a requeued job may start again
# (default 120 s, which makes node-failure tests slow).
AuthInfo=socket=$munge_sock,cred_expire=10

StateSaveLocation=$state/ctld
SlurmdSpoolDir=$state/spool
SlurmctldPidFile=$state/run/slurmctld.pid
SlurmdPidFile=$state/run/slurmd.pid
SlurmctldLogFile=$state/log/slurmctld.log
SlurmdLogFile=$state/log/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info

ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobContainerType=job_container/none
MpiDefault=none
# Debian has no mail program configured; without this slurmctld logs an error.
MailProg=/bin/true
SwitchType=switch/none

SchedulerType=sched/backfill
# Requeued jobs only become eligible by time, and are then picked up by the
# periodic passes (defaults 30 s / 60 s); shorten them for fast tests.
SchedulerParameters=bf_interval=2,sched_interval=5
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
DefMemPerCPU=$defmem

JobAcctGatherType=jobacct_gather/linux
JobAcctGatherFrequency=task=5
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/filetxt
JobCompLoc=$state/log/jobcomp.txt

SlurmdTimeout=10
SlurmctldTimeout=10
MessageTimeout=5
InactiveLimit=0
KillWait=5
MinJobAge=600
ReturnToService=2
JobRequeue=1

NodeName=$host NodeAddr=127.0.0.1 NodeHostname=$host $topo RealMemory=$realmem State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
    cat >"$state/env.sh" <<EOF
# source this to use the local Slurm cluster in $state
export SLURM_CONF=$conf
EOF
}

start_munge() {
    local i
    if pid_alive "$munge_dir/munged.pid" munged >/dev/null; then
        return 0
    fi
    mkdir -p -- "$munge_dir"
    # munged refuses a socket directory that is group/world writable, and also
    # one that other users cannot traverse (0700): it wants exactly 0711-like.
    chmod 0711 "$munge_dir"
    if [[ ! -s $munge_dir/munge.key ]]; then
        mungekey --create --keyfile="$munge_dir/munge.key" >/dev/null ||
            die "mungekey could not create $munge_dir/munge.key"
    fi
    chmod 0600 "$munge_dir/munge.key"
    rm -f -- "$munge_sock" "$munge_sock.lock"
    munged --key-file="$munge_dir/munge.key" --socket="$munge_sock" \
        --pid-file="$munge_dir/munged.pid" --log-file="$state/log/munged.log" \
        --seed-file="$munge_dir/munged.seed" </dev/null >>"$state/log/munged.log" 2>&1 ||
        { show_logs; die "munged failed to start"; }
    for ((i = 0; i < 100; i++)); do
        [[ -S $munge_sock ]] && return 0
        daemon_died "$munge_dir/munged.pid" munged && break
        sleep 0.1
    done
    show_logs
    die "munged did not create $munge_sock"
}

start_slurmd() {
    pid_alive "$state/run/slurmd.pid" slurmd >/dev/null && return 0
    # -N: do not rely on slurmd deriving the same short name from gethostname().
    SLURM_CONF=$conf slurmd -f "$conf" -N "$(hostname -s)" </dev/null >>"$state/log/slurmd.log" 2>&1
}

# fail_start MESSAGE: show what the daemons said, undo the partial start.
fail_start() {
    timeout 10 sinfo -N -l >&2 2>/dev/null || true
    show_logs
    do_stop >/dev/null 2>&1 || true
    die "$1"
}

do_start() {
    local port
    need_cmds slurmctld slurmd sinfo scontrol squeue scancel munged mungekey
    ((EUID == 0)) || die "must run as root (slurmd has to start jobs as their users)"
    if pid_alive "$state/run/slurmctld.pid" slurmctld >/dev/null; then
        die "slurmctld from $state is already running; run '$prog stop $state' first"
    fi
    # Another Slurm on the default ports would otherwise answer our clients
    # (with a different munge key) and the start would only time out.
    for port in "$ctld_port" "$slurmd_port"; do
        if port_in_use "$port"; then
            die "port $port on 127.0.0.1 is already in use (another Slurm?); set SLURM_LOCAL_CTLD_PORT/SLURM_LOCAL_SLURMD_PORT"
        fi
    done
    mkdir -p -- "$state/ctld" "$state/spool" "$state/run" "$state/log"
    # Pid files left by a crash would make the liveness checks misfire.
    rm -f -- "$state/run/slurmctld.pid" "$state/run/slurmd.pid"
    write_config
    start_munge
    SLURM_CONF=$conf slurmctld -f "$conf" </dev/null >>"$state/log/slurmctld.log" 2>&1 ||
        fail_start "slurmctld failed to start"
    # slurmd registers once at startup; give it a controller to talk to.
    local deadline=$((SECONDS + 15))
    until timeout 5 scontrol ping 2>/dev/null | grep -q UP; do
        if ((SECONDS >= deadline)) || daemon_died "$state/run/slurmctld.pid" slurmctld; then
            fail_start "slurmctld did not come up"
        fi
        sleep 0.1
    done
    start_slurmd || fail_start "slurmd failed to start"
    wait_node_ok || fail_start "node did not become ready within 30 s"
    printf 'export SLURM_CONF=%s\n' "$conf"
}

# descendants PID: prints PID and all its descendants, parents first.
descendants() {
    local child
    printf '%s\n' "$1"
    for child in $(pgrep -P "$1" || true); do
        descendants "$child"
    done
}

# Job steps (slurmstepd and the job's processes) outlive a slurmd that died
# or was killed before it could cancel them. Find the steps of this instance
# through the SLURM_CONF they inherited from our slurmd and kill their trees.
kill_stray_steps() {
    local pid victims=()
    for pid in $(pgrep -x slurmstepd || true); do
        tr '\0' '\n' <"/proc/$pid/environ" 2>/dev/null | grep -qxF "SLURM_CONF=$conf" || continue
        mapfile -t -O "${#victims[@]}" victims < <(descendants "$pid")
    done
    ((${#victims[@]} == 0)) || kill -KILL "${victims[@]}" 2>/dev/null || true
}

do_stop() {
    local i
    if pid_alive "$state/run/slurmctld.pid" slurmctld >/dev/null; then
        # Stopping slurmd leaves running jobs alive, and slurmctld would save
        # them as running for the next start; cancel them all first and let
        # slurmd kill their process trees.
        timeout 10 scancel --partition=debug >/dev/null 2>&1 || true
        if pid_alive "$state/run/slurmd.pid" slurmd >/dev/null; then
            for ((i = 0; i < 100; i++)); do
                [[ -z $(timeout 5 squeue -h -t running,completing -o %i 2>/dev/null) ]] && break
                sleep 0.1
            done
        fi
    fi
    # Each takes 1-2 s to shut down; they do not need each other for it.
    stop_daemon "$state/run/slurmd.pid" slurmd &
    stop_daemon "$state/run/slurmctld.pid" slurmctld &
    wait
    kill_stray_steps
    stop_daemon "$munge_dir/munged.pid" munged
    rm -f -- "$munge_sock" "$munge_sock.lock"
}

do_status() {
    [[ -f $conf ]] || die "no cluster configured in $state (run '$prog start $state')"
    need_cmds sinfo
    if ! timeout 10 sinfo; then
        die "slurmctld from $state does not answer"
    fi
    node_ok || die "node is not usable (down, drained or not responding)"
}

do_restart_slurmd() {
    [[ -f $conf ]] || die "no cluster configured in $state (run '$prog start $state')"
    need_cmds slurmd sinfo
    stop_daemon "$state/run/slurmd.pid" slurmd
    start_slurmd || { show_logs; die "slurmd failed to start"; }
    if ! wait_node_ok; then
        timeout 10 sinfo -N -l >&2 || true
        show_logs
        die "node did not become ready within 30 s after restarting slurmd"
    fi
}

case $cmd in
    start) do_start ;;
    stop) do_stop ;;
    status) do_status ;;
    restart-slurmd) do_restart_slurmd ;;
    *) usage ;;
esac
