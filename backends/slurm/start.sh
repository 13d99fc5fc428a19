#!/usr/bin/env bash
# Start a one-node SLURM cluster on this machine (slurmctld + slurmd on localhost, munge
# authentication), for the `poser slurm` test. Idempotent: a cluster already answering is
# left alone. Prints the path of its slurm.conf; clients need `SLURM_CONF` set to it.
#
# Needs root and Debian's `slurm-wlm` and `munge` (backends/setup.sh installs them as root).
# State, logs and spool live under $POSER_SLURM_DIR (default /tmp/poser-slurm).
set -euo pipefail
dir="${POSER_SLURM_DIR:-/tmp/poser-slurm}"
conf="$dir/slurm.conf"
export SLURM_CONF="$conf"
for tool in slurmctld slurmd munged sbatch sinfo; do
  if ! command -v "$tool" >/dev/null 2>&1 && [ ! -x "/usr/sbin/$tool" ]; then
    echo "error: $tool is missing" >&2
    echo "  help: apt-get install -y slurm-wlm munge (or run backends/setup.sh as root)" >&2
    exit 1
  fi
done
if [ -f "$conf" ] && timeout 5 sinfo -h -o %T 2>/dev/null | grep -q -E '^(idle|mixed|allocated)'; then
  echo "$conf"
  exit 0
fi
mkdir -p "$dir/state" "$dir/spool" "$dir/log"
host="$(hostname -s)"
cpus="$(nproc)"
mem_mb="$(awk '/MemTotal/ {print int($2 / 1024 * 0.8)}' /proc/meminfo)"
cat > "$conf" <<CONF
ClusterName=poser-test
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
MpiDefault=none
SchedulerType=sched/backfill
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem_mb State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
# munge: its key comes with the Debian package; the daemon runs as root here (--force).
mkdir -p /run/munge
chown munge:munge /run/munge 2>/dev/null || true
if ! pgrep -x munged >/dev/null; then
  /usr/sbin/munged --force
fi
pkill -x slurmctld 2>/dev/null || true
pkill -x slurmd 2>/dev/null || true
sleep 1
/usr/sbin/slurmctld -f "$conf" -c
/usr/sbin/slurmd -f "$conf" -c
for _ in $(seq 1 60); do
  if sinfo -h -o %T 2>/dev/null | grep -q -E '^(idle|mixed|allocated)'; then
    echo "$conf"
    exit 0
  fi
  sleep 1
done
echo "error: the one-node SLURM cluster did not come up; logs in $dir/log" >&2
tail -n 20 "$dir/log/slurmctld.log" "$dir/log/slurmd.log" >&2 || true
exit 1
