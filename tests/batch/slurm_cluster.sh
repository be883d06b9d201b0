#!/usr/bin/env bash
# A throw-away single-node Slurm (munged, slurmctld, slurmd) for the batch tests, with all its
# state under one folder (never system paths), started and stopped by PID. No systemd needed.
#   slurm_cluster.sh start DIR   -> prints "export SLURM_CONF=DIR/slurm.conf" once `sinfo` shows the node idle
#   slurm_cluster.sh stop DIR    -> stops the three daemons by their PID files
# Exit 77 (ctest: skipped) when Slurm or munge are not installed or we are not root.
set -euo pipefail
cmd=$1
dir=$(mkdir -p "$2" && cd "$2" && pwd)

stop() {
  for f in "$dir/slurmd.pid" "$dir/slurmctld.pid" "$dir/munge-run/munged.pid"; do
    [ -s "$f" ] || continue
    pid=$(cat "$f")
    kill "$pid" 2>/dev/null || true
    for _ in $(seq 1 100); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -9 "$pid" 2>/dev/null || true
    rm -f "$f"
  done
}

if [ "$cmd" = stop ]; then stop; exit 0; fi

for p in munged slurmctld slurmd sinfo sbatch; do
  command -v "$p" >/dev/null || [ -x "/usr/sbin/$p" ] || { echo "skip: $p is not installed (scripts/install-deps.sh)" >&2; exit 77; }
done
[ "$(id -u)" = 0 ] || { echo "skip: the test Slurm runs its daemons as root" >&2; exit 77; }
id munge >/dev/null 2>&1 || { echo "skip: no munge user" >&2; exit 77; }

stop  # a previous run's daemons, if any
rm -rf "$dir/state" "$dir/spool" "$dir/log" "$dir/munge" "$dir/munge-run"
mkdir -p "$dir/state" "$dir/spool" "$dir/log" "$dir/munge" "$dir/munge-run"
chown munge:munge "$dir/munge" "$dir/munge-run"
chmod 700 "$dir/munge"
chmod 755 "$dir/munge-run"   # 700 fails: "Socket is inaccessible"
dd if=/dev/urandom of="$dir/munge/munge.key" bs=1024 count=1 status=none
chown munge:munge "$dir/munge/munge.key"; chmod 400 "$dir/munge/munge.key"
# Ports from the PID so that two test runs on one machine do not collide.
port=$(( 20000 + ($$ % 10000) * 2 ))
host=$(hostname -s)
cat > "$dir/slurm.conf" <<CONF
ClusterName=tdftest
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$dir/munge-run/munge.socket
SlurmctldPort=$port
SlurmdPort=$((port + 1))
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
MpiDefault=none
SwitchType=switch/none
ReturnToService=2
MaxArraySize=10001
MinJobAge=600
KillWait=30
NodeName=$host NodeAddr=127.0.0.1 CPUs=$(nproc) RealMemory=1000 State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF=$dir/slurm.conf
runuser -u munge -- /usr/sbin/munged -S "$dir/munge-run/munge.socket" --key-file="$dir/munge/munge.key" \
  --log-file="$dir/munge/munged.log" --pid-file="$dir/munge-run/munged.pid" --seed-file="$dir/munge/munged.seed"
/usr/sbin/slurmctld -f "$SLURM_CONF" -i
/usr/sbin/slurmd -f "$SLURM_CONF"
# Bounded wait for the node to come up idle.
for _ in $(seq 1 150); do
  state=$(sinfo -h -o %T 2>/dev/null || true)
  if [ "$state" = idle ]; then echo "export SLURM_CONF=$SLURM_CONF"; exit 0; fi
  sleep 0.2
done
echo "slurm did not come up (sinfo: '${state:-}'); logs in $dir/log" >&2
stop
exit 1
