#!/usr/bin/env bash
# A private one-node Slurm cluster in a folder, for tests and benchmarks on one machine
# (Debian's slurm-wlm and munge; needs root, as slurmd does):
#   eval "$(scripts/slurm/local-cluster.sh start DIR)"   # exports SLURM_CONF; DIR must be empty or absent
#   sbatch ...; squeue ...
#   scripts/slurm/local-cluster.sh stop DIR              # stops its daemons by their PIDs
# It runs its own munged (own key, pid, log and seed files in DIR; its socket in a mode-0755
# folder /tmp/ispm-munge.XXXXXX, since munged refuses a socket below any folder that not all
# may enter, as DIR can be, e.g. under a mktemp -d or /root; DIR/munge.sockdir names it),
# `slurmctld -D -c` and `slurmd -D -N localhost` with a minimal DIR/slurm.conf (linuxproc
# process tracking, no task plugin, select/cons_tres, one node with this machine's CPUs,
# kill_invalid_depend so that a failed job cancels the jobs that depend on it, state and
# spool in DIR, ports from PORT_BASE, default a free pair near 20000 + PID). Nothing outside
# DIR but the socket folder is touched (stop removes it); no system daemon is used. Exit 77 (with the reason) when it cannot start
# a cluster here: not root, or a missing binary.
set -u
cmd=${1:-}; DIR=${2:-}
[ -n "$cmd" ] && [ -n "$DIR" ] || { echo "usage: local-cluster.sh start|stop DIR" >&2; exit 2; }

stop() {
  for name in slurmd slurmctld munged; do
    [ -f "$DIR/$name.pid" ] || continue
    pid=$(cat "$DIR/$name.pid")
    kill "$pid" 2>/dev/null
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -9 "$pid" 2>/dev/null
    rm -f "$DIR/$name.pid"
  done
  if [ -f "$DIR/munge.sockdir" ]; then
    sock=$(cat "$DIR/munge.sockdir")
    case $sock in /tmp/ispm-munge.*) rm -rf "$sock" ;; esac
    rm -f "$DIR/munge.sockdir"
  fi
}

if [ "$cmd" = stop ]; then stop; exit 0; fi
[ "$cmd" = start ] || { echo "usage: local-cluster.sh start|stop DIR" >&2; exit 2; }
skip() { echo "local-cluster: cannot start a Slurm cluster here: $*" >&2; exit 77; }
[ "$(id -u)" -eq 0 ] || skip "not root (slurmd must run as root)"
for b in munged slurmctld slurmd sbatch squeue sinfo scontrol; do
  command -v "$b" > /dev/null || [ -x "/usr/sbin/$b" ] || skip "no $b (apt-get install slurm-wlm munge)"
done
PATH=$PATH:/usr/sbin
mkdir -p "$DIR" && DIR=$(cd "$DIR" && pwd)
[ -z "$(ls -A "$DIR")" ] || { echo "local-cluster: $DIR is not empty" >&2; exit 2; }
mkdir -p "$DIR/state" "$DIR/spool" "$DIR/log"
SOCKDIR=$(mktemp -d /tmp/ispm-munge.XXXXXX) || { echo "local-cluster: cannot make a socket folder in /tmp" >&2; exit 1; }
chmod 0755 "$SOCKDIR"
echo "$SOCKDIR" > "$DIR/munge.sockdir"
SOCKET=$SOCKDIR/munge.socket
chmod 0700 "$DIR/state"
head -c 1024 /dev/urandom > "$DIR/munge.key" && chmod 0400 "$DIR/munge.key"

free_port() { ! (exec 3<>"/dev/tcp/127.0.0.1/$1") 2>/dev/null; }
port=${PORT_BASE:-$((20000 + ($$ % 20000) * 2))}
while ! free_port "$port" || ! free_port $((port + 1)); do port=$((port + 2)); done

munged -F --socket="$SOCKET" --key-file="$DIR/munge.key" --pid-file="$DIR/munged.pidfile" \
  --log-file="$DIR/log/munged.log" --seed-file="$DIR/munged.seed" > "$DIR/log/munged.out" 2>&1 &
echo $! > "$DIR/munged.pid"
cat > "$DIR/slurm.conf" <<CONF
ClusterName=ispm-local
SlurmctldHost=localhost
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$SOCKET
CredType=cred/munge
StateSaveLocation=$DIR/state
SlurmdSpoolDir=$DIR/spool
SlurmctldPidFile=$DIR/slurmctld.pidfile
SlurmdPidFile=$DIR/slurmd.pidfile
SlurmctldLogFile=$DIR/log/slurmctld.log
SlurmdLogFile=$DIR/log/slurmd.log
PlugStackConfig=$DIR/plugstack.conf
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
SchedulerParameters=sched_interval=1
DependencyParameters=kill_invalid_depend
MpiDefault=none
SwitchType=switch/none
ReturnToService=2
JobCompType=jobcomp/none
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
MinJobAge=600
NodeName=localhost NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=local Nodes=localhost Default=YES MaxTime=INFINITE State=UP
CONF
: > "$DIR/plugstack.conf"
export SLURM_CONF=$DIR/slurm.conf
for _ in $(seq 50); do [ -S "$SOCKET" ] && break; sleep 0.1; done
if [ ! -S "$SOCKET" ]; then
  echo "local-cluster: munged did not start; $DIR/log/munged.out:" >&2
  tail -n 5 "$DIR/log/munged.out" >&2
  stop
  exit 1
fi
slurmctld -D -c -f "$SLURM_CONF" > "$DIR/log/slurmctld.out" 2>&1 &
echo $! > "$DIR/slurmctld.pid"
slurmd -D -N localhost -f "$SLURM_CONF" > "$DIR/log/slurmd.out" 2>&1 &
echo $! > "$DIR/slurmd.pid"
for _ in $(seq 100); do
  sinfo -h -o %T 2>/dev/null | grep -qx idle && { echo "export SLURM_CONF=$SLURM_CONF"; exit 0; }
  sleep 0.2
done
echo "local-cluster: the node did not come up in 20 s; logs in $DIR/log:" >&2
tail -n 5 "$DIR"/log/*.out "$DIR"/log/*.log >&2 2>/dev/null
stop
exit 1
