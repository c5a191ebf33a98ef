#!/bin/bash
# A single-node Slurm cluster on this machine, from Debian's slurm-wlm and munge: enough to run
# scanreg's pair jobs as a Slurm array (README, "Large projects") and the test that does
# (tests_integration --gtest_filter='PairJobs.ASlurm*'). CI runs it before the tests.
#   sudo packaging/slurm/single-node.sh          # install, configure, start; waits until the node is idle
#   sudo packaging/slurm/single-node.sh --stop   # stop the daemons again
# It writes /etc/slurm/slurm.conf (refuses to replace one it did not write) and starts munged,
# slurmctld and slurmd as plain processes (no systemd needed: containers and CI machines). The node
# offers every CPU and the machine's memory less 512 MB; jobs run as the user who submits them.
set -euo pipefail

conf=/etc/slurm/slurm.conf
marker="# written by scanreg packaging/slurm/single-node.sh"

if [ "${1:-}" = "--stop" ]; then
  pkill -x slurmd || true
  pkill -x slurmctld || true
  pkill -x munged || true
  exit 0
fi
[ "$(id -u)" -eq 0 ] || { echo "single-node.sh: run as root (it installs packages and starts daemons)" >&2; exit 1; }

if ! command -v slurmctld > /dev/null || ! command -v munged > /dev/null; then
  export DEBIAN_FRONTEND=noninteractive
  apt-get -o DPkg::Lock::Timeout=900 -qq update > /dev/null
  apt-get -o DPkg::Lock::Timeout=900 -qq install -y --no-install-recommends slurm-wlm munge > /dev/null
fi

if [ -e "$conf" ] && ! grep -qF "$marker" "$conf"; then
  echo "single-node.sh: $conf exists and was not written by this script; not replacing it" >&2
  exit 1
fi

node=$(hostname -s)
cpus=$(nproc)
memory_mb=$(( $(awk '/^MemTotal:/ {print $2}' /proc/meminfo) / 1024 - 512 ))
mkdir -p /etc/slurm /var/spool/slurmctld /var/spool/slurmd /var/log/slurm /run/munge
cat > "$conf.tmp" << EOF
$marker
ClusterName=scanreg
SlurmctldHost=$node(127.0.0.1)
SlurmUser=root
AuthType=auth/munge
StateSaveLocation=/var/spool/slurmctld
SlurmdSpoolDir=/var/spool/slurmd
SlurmctldPidFile=/run/slurmctld.pid
SlurmdPidFile=/run/slurmd.pid
SlurmctldLogFile=/var/log/slurm/slurmctld.log
SlurmdLogFile=/var/log/slurm/slurmd.log
# No cgroups: containers and CI machines rarely delegate them.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
ReturnToService=2
NodeName=$node NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$memory_mb State=UNKNOWN
PartitionName=main Nodes=$node Default=YES MaxTime=INFINITE State=UP
EOF
mv "$conf.tmp" "$conf"

# munge: a key (the package makes one; make one if it did not), then the daemon.
if [ ! -s /etc/munge/munge.key ]; then
  mungekey --create --keyfile=/etc/munge/munge.key
fi
chown -R munge:munge /etc/munge /run/munge /var/lib/munge /var/log/munge 2> /dev/null || true
chmod 0400 /etc/munge/munge.key
pgrep -x munged > /dev/null || runuser -u munge -- /usr/sbin/munged

pkill -x slurmd || true
pkill -x slurmctld || true
sleep 1
/usr/sbin/slurmctld
/usr/sbin/slurmd

# Wait until the node takes jobs.
for _ in $(seq 60); do
  state=$(sinfo -h -N -o '%t' 2> /dev/null | head -1 || true)
  case "$state" in
    idle | mix | alloc)
      echo "single-node.sh: Slurm node $node ($cpus CPUs, $memory_mb MB) is $state"
      exit 0
      ;;
  esac
  sleep 1
done
echo "single-node.sh: the Slurm node did not become idle; see /var/log/slurm/slurmctld.log and slurmd.log" >&2
sinfo -N -l >&2 || true
exit 1
