#!/usr/bin/env bash
# A single-node Slurm cluster inside this test's own folder: munged, slurmctld and slurmd with a
# generated slurm.conf (proctrack/linuxproc, task/none, only on 127.0.0.1), a 4-shard bake of a
# shared scene submitted with examples/slurm/submit.sh (a job array per phase, the merge after
# them with afterok), the merged asset compared byte for byte with the one-process bake, and
# every daemon stopped. Skips (77), saying why, when the daemons cannot run here (not root, no
# Slurm outside CI, or they do not come up) or the shared scenes are missing.
#   slurm_test.sh PRTSUB WORK_DIR SCENES_DIR
set -uo pipefail
prtsub=$1 work=$2 scenes=$3
root=$(cd "$(dirname "$0")/../.." && pwd)
skip() {
  echo "SKIP: $*"
  exit 77
}
for tool in munged slurmctld slurmd sbatch squeue scontrol sinfo; do
  if ! command -v "$tool" > /dev/null && ! [ -x "/usr/sbin/$tool" ]; then
    [ "${CI:-}" = true ] && { echo "FAIL: $tool missing in CI (.ci/deps installs slurm-wlm and munge)"; exit 1; }
    skip "$tool is not installed (apt-get install slurm-wlm munge)"
  fi
done
export PATH=$PATH:/usr/sbin
[ "$(id -u)" -eq 0 ] || skip "slurmd needs root to launch jobs here (running as $(id -un))"
scene=$scenes/house_on_site.obj
[ -f "$scene" ] || skip "no shared scenes at $scenes"

rm -rf "$work" && mkdir -p "$work"/{munge,state,spool,log,job} && cd "$work"
chmod 700 munge
dd if=/dev/urandom of=munge/key bs=1024 count=1 status=none && chmod 400 munge/key
node=$(hostname -s)
port=$((20000 + RANDOM % 20000))
cat > slurm.conf <<CONF
ClusterName=prtsubtest
SlurmctldHost=$node(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
AuthType=auth/munge
AuthInfo=socket=$work/munge/sock
CredType=cred/munge
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/log/slurmctld.log
SlurmdLogFile=$work/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
SwitchType=switch/none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
NodeName=$node NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=test Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF=$work/slurm.conf
stop() {
  scontrol shutdown > /dev/null 2>&1
  for i in $(seq 50); do
    pgrep -f "$work/slurm.conf" > /dev/null || break
    sleep 0.2
  done
  for f in slurmctld.pid slurmd.pid; do [ -f "$f" ] && kill "$(cat "$f")" 2> /dev/null; done
  munged -s --socket="$work/munge/sock" > /dev/null 2>&1
  sleep 0.5
  if pgrep -f "$work/slurm.conf" > /dev/null || pgrep -f "$work/munge/sock" > /dev/null; then
    echo "FAIL: a daemon is still running"
    pkill -9 -f "$work/slurm.conf"; pkill -9 -f "$work/munge/sock"
    exit 1
  fi
  echo "every daemon stopped"
}
trap stop EXIT
munged -f --socket="$work/munge/sock" --key-file="$work/munge/key" --log-file="$work/log/munged.log" \
  --pid-file="$work/munge/pid" --seed-file="$work/munge/seed" || skip "munged did not start: $(tail -3 log/munged.log 2> /dev/null)"
slurmctld -f "$work/slurm.conf" || skip "slurmctld did not start: $(tail -3 log/slurmctld.log 2> /dev/null)"
slurmd -f "$work/slurm.conf" -N "$node" || skip "slurmd did not start: $(tail -3 log/slurmd.log 2> /dev/null)"
for i in $(seq 100); do
  [ "$(sinfo -h -o %T 2> /dev/null)" = idle ] && break
  sleep 0.3
done
[ "$(sinfo -h -o %T 2> /dev/null)" = idle ] || skip "the node did not come up: $(tail -3 log/slurmd.log log/slurmctld.log 2> /dev/null)"
echo "cluster up: $(sinfo -h -o '%P %D %T %c')"

options=(--rays 64)
export PRTSUB=$prtsub
merge=$(bash "$root/examples/slurm/submit.sh" 4 "$work/job/parts" "$work/job/sharded.ply" "$scene" "${options[@]}" | tee job/submit.log | tail -1)
cat job/submit.log
state=""
for i in $(seq 600); do
  state=$(scontrol show job "$merge" 2> /dev/null | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p')
  case $state in COMPLETED | FAILED | CANCELLED | TIMEOUT | NODE_FAIL | OUT_OF_MEMORY) break ;; esac
  sleep 0.5
done
echo "merge job $merge: $state"
if [ "$state" != COMPLETED ]; then
  echo "FAIL: the merge did not complete"
  tail -n 5 job/parts/*.log
  squeue
  exit 1
fi
"$prtsub" bake "$scene" "${options[@]}" -o job/single.ply > job/single.log
parts=$(ls job/parts/*.part | wc -l)
echo "$parts parts"
cmp job/single.ply job/sharded.ply || { echo "FAIL: the merged asset differs from the one-process bake"; exit 1; }
echo "4 shards on Slurm = one process, byte for byte"
