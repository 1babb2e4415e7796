#!/usr/bin/env bash
# A one-node Slurm cluster on this machine, for scripts/test-slurm.sh and for trying the job
# scripts of docs/distributed.md ("Slurm") without a cluster:
#   local-cluster.sh start DIR   starts munged, slurmctld and slurmd with everything (config,
#                                key, state, spool, logs, sockets) under DIR; prints the line
#                                `export SLURM_CONF=DIR/slurm.conf` that sbatch, squeue and
#                                scontrol need
#   local-cluster.sh stop DIR    cancels the cluster's jobs and stops the three daemons that
#                                `start DIR` started
# As root (the daemons run as root, and so do the jobs), with Debian 12's slurm-wlm and munge
# (scripts/setup-debian.sh). No systemd and no cgroups: the daemons are started by hand,
# processes are tracked through /proc (proctrack/linuxproc), tasks are not confined
# (task/none), so it runs in a container too. The ports are not Slurm's defaults, so that a
# cluster this machine may already belong to is not disturbed.
set -euo pipefail

usage() { echo "usage: local-cluster.sh start|stop DIR" >&2; exit 2; }
[ $# -eq 2 ] || usage
cmd=$1
dir=$(realpath -m "$2")
ctld_port=${VKVCM_SLURMCTLD_PORT:-16817}
slurmd_port=${VKVCM_SLURMD_PORT:-16818}

# Stops the daemons whose pid files are the arguments: SIGTERM to all, then up to 10 s for
# them to exit (each takes 1-2 s), then SIGKILL to any still there. Only a process whose
# command line names DIR is signalled (a stale pid file may name another process by now).
stop_daemons() {
  local pids=() pid f
  for f in "$@"; do
    [ -f "$f" ] || continue
    pid=$(cat "$f")
    rm -f "$f"
    [ -n "$pid" ] && { tr '\0' ' ' <"/proc/$pid/cmdline"; } 2>/dev/null | grep -qF "$dir/" || continue
    kill "$pid" 2>/dev/null && pids+=("$pid")
  done
  for pid in "${pids[@]}"; do
    for _ in $(seq 100); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -9 "$pid" 2>/dev/null || true
  done
}

# Waits up to $1 seconds of wall time for the command after it to succeed. Each try is
# cut at 5 s: with no slurmctld listening (e.g. its port taken by another cluster) a
# client command such as sinfo retries for far longer than the whole wait.
wait_for() {
  local deadline=$(($(date +%s) + $1)); shift
  while [ "$(date +%s)" -lt "$deadline" ]; do
    timeout 5 "$@" >/dev/null 2>&1 && return 0
    sleep 0.1
  done
  return 1
}

start() {
  if [ "$(id -u)" -ne 0 ]; then
    echo "local-cluster.sh: must run as root" >&2
    exit 1
  fi
  for tool in munged mungekey slurmctld slurmd sbatch; do
    command -v "$tool" >/dev/null || {
      echo "local-cluster.sh: $tool not found: install slurm-wlm and munge (scripts/setup-debian.sh)" >&2
      exit 1
    }
  done
  mkdir -p "$dir"/{state,spool,munge}
  chmod 700 "$dir/munge"
  local host cpus
  host=$(hostname -s)
  cpus=$(nproc)

  # munge: a key of this cluster's own, and a socket under DIR (AuthInfo points Slurm at it).
  rm -f "$dir/munge/munge.key"
  mungekey --create --keyfile="$dir/munge/munge.key"
  munged --force --key-file="$dir/munge/munge.key" --socket="$dir/munge/munge.socket" \
    --pid-file="$dir/munge/munged.pid" --log-file="$dir/munge/munged.log" \
    --seed-file="$dir/munge/munged.seed"

  cat > "$dir/slurm.conf" <<CONF
# Written by scripts/slurm/local-cluster.sh: a one-node cluster on $host.
ClusterName=vkvcm-local
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$dir/munge/munge.socket
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SwitchType=switch/none
MpiDefault=none
MailProg=/bin/true
SchedulerType=sched/builtin
# Jobs start as soon as they are submitted (the default waits up to 3 s to batch them).
SchedulerParameters=batch_sched_delay=0
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=local Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
  export SLURM_CONF=$dir/slurm.conf
  # -c: a clean start (no jobs from an earlier cluster in the same DIR).
  slurmctld -c -f "$SLURM_CONF"
  slurmd -f "$SLURM_CONF"
  if ! wait_for 30 bash -c 'sinfo -h -N -o %T | grep -qE "^(idle|mixed|allocated)"'; then
    echo "local-cluster.sh: the node did not come up in 30 s; logs in $dir" >&2
    sinfo -N -l >&2 || true
    tail -n 20 "$dir/slurmctld.log" "$dir/slurmd.log" >&2 || true
    exit 1
  fi
  echo "export SLURM_CONF=$SLURM_CONF"
}

stop() {
  # Jobs still running (a test that failed half-way) are cancelled first: their processes
  # belong to slurmd's step daemons, which would otherwise outlive the cluster.
  if [ -f "$dir/slurmctld.pid" ]; then
    export SLURM_CONF=$dir/slurm.conf
    timeout 10 scancel --quiet --user "$(id -un)" 2>/dev/null || true
    wait_for 10 bash -c '[ -z "$(squeue -h -o %i)" ]' || true
  fi
  stop_daemons "$dir/slurmd.pid" "$dir/slurmctld.pid" "$dir/munge/munged.pid"
}

case "$cmd" in
  start) start ;;
  stop) stop ;;
  *) usage ;;
esac
