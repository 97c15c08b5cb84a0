#!/usr/bin/env bash
# ctest label `slurm`: `lexdyn-harness sweep submit` against a real Slurm (docs/sweeps.md, "Slurm").
# Starts its own single-node cluster (munged with its own key and socket, slurmctld and slurmd from
# a generated slurm.conf on free ports, state in a temporary folder, no systemd), submits a small
# sweep, waits, compares the merged result with a local run of the same sweep, resubmits after
# removing two points (only those run again), and stops exactly the daemons it started.
#
# Usage: slurm_sweep.sh LEXDYN_HARNESS SWEEP_FILE POINTS
set -euo pipefail
HARNESS="$1"
SWEEP="$2"
POINTS="$3"
for tool in munged slurmctld slurmd sbatch squeue sinfo; do
  command -v "$tool" > /dev/null || [ -x "/usr/sbin/$tool" ] || { echo "slurm_sweep: $tool is not installed (harness/scripts/install-deps.sh installs slurm-wlm and munge)" >&2; exit 1; }
done
export PATH="$PATH:/usr/sbin"

T="$(mktemp -d /tmp/lexdyn-slurm.XXXXXX)"
PIDS=()
cleanup() {
  local rc=$?
  for pid in "${PIDS[@]}"; do kill "$pid" 2> /dev/null || true; done
  for pid in "${PIDS[@]}"; do
    for _ in $(seq 50); do kill -0 "$pid" 2> /dev/null || break; sleep 0.1; done
    kill -9 "$pid" 2> /dev/null || true
  done
  if [ $rc -ne 0 ]; then
    echo "--- logs (failed) ---" >&2
    tail -n 20 "$T"/log/* "$T"/out-slurm/slurm/*/*.log 2> /dev/null >&2 || true
  fi
  rm -rf "$T"
  exit $rc
}
trap cleanup EXIT

mkdir -p "$T/munge" "$T/state" "$T/spool" "$T/log"
chmod 700 "$T/munge"
head -c 1024 /dev/urandom > "$T/munge/key"
chmod 600 "$T/munge/key"
munged --foreground --key-file="$T/munge/key" --socket="$T/munge/sock" --pid-file="$T/munge/pid" \
  --log-file="$T/log/munged.log" --seed-file="$T/munge/seed" --force > "$T/log/munged.out" 2>&1 &
PIDS+=($!)
for _ in $(seq 100); do [ -S "$T/munge/sock" ] && break; sleep 0.05; done
[ -S "$T/munge/sock" ] || { echo "slurm_sweep: munged did not start" >&2; exit 1; }

read -r P1 P2 < <(python3 -c '
import socket
ports = []
socks = []
for _ in range(2):
    s = socket.socket(); s.bind(("127.0.0.1", 0)); ports.append(s.getsockname()[1]); socks.append(s)
print(*ports)')
HOST="$(hostname)"
CPUS="$(nproc)"
cat > "$T/slurm.conf" << EOF
ClusterName=lexdyntest
SlurmctldHost=$HOST(127.0.0.1)
SlurmctldPort=$P1
SlurmdPort=$P2
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$T/munge/sock
CredType=cred/munge
StateSaveLocation=$T/state
SlurmdSpoolDir=$T/spool
SlurmctldPidFile=$T/slurmctld.pid
SlurmdPidFile=$T/slurmd.pid
SlurmctldLogFile=$T/log/slurmctld.log
SlurmdLogFile=$T/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
NodeName=$HOST NodeAddr=127.0.0.1 CPUs=$CPUS State=UNKNOWN
PartitionName=lexdyn Nodes=$HOST Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF="$T/slurm.conf"
slurmctld -D -f "$SLURM_CONF" > "$T/log/slurmctld.out" 2>&1 &
PIDS+=($!)
slurmd -D -f "$SLURM_CONF" -N "$HOST" > "$T/log/slurmd.out" 2>&1 &
PIDS+=($!)
t0=$(date +%s.%N)
for _ in $(seq 200); do
  sinfo -h -o %t 2> /dev/null | grep -q idle && break
  sleep 0.1
done
sinfo -h -o %t | grep -q idle || { echo "slurm_sweep: the node did not become idle" >&2; sinfo >&2 || true; exit 1; }
echo "slurm_sweep: cluster up in $(python3 -c "print(round($(date +%s.%N) - $t0, 2))") s (ports $P1 $P2)"

wait_for_queue() {
  for _ in $(seq 1800); do
    [ -z "$(squeue -h 2> /dev/null)" ] && return 0
    sleep 0.2
  done
  echo "slurm_sweep: jobs still queued after 6 minutes" >&2
  squeue >&2
  return 1
}

strip() {  # results.jsonl without the wall times
  python3 -c '
import json, sys
for line in open(sys.argv[1]):
    j = json.loads(line)
    for r in j["runs"].values():
        r.pop("wall_s")
    print(json.dumps(j, sort_keys=True))' "$1"
}
failures() { python3 -c 'import json,sys; print(json.dumps(json.load(open(sys.argv[1]))["failures"], sort_keys=True))' "$1"; }

# 1. Submit, wait, compare with a local run.
t1=$(date +%s.%N)
"$HARNESS" sweep submit "$SWEEP" --out "$T/out-slurm" --points "$POINTS" --chunk 2 --no-db
wait_for_queue
t2=$(date +%s.%N)
[ -f "$T/out-slurm/summary.json" ] || { echo "slurm_sweep: the merge job wrote no summary" >&2; exit 1; }
"$HARNESS" sweep run "$SWEEP" --out "$T/out-local" --points "$POINTS" -j "$CPUS" --no-db --quiet > /dev/null 2>&1 || true
t3=$(date +%s.%N)
diff <(strip "$T/out-local/results.jsonl") <(strip "$T/out-slurm/results.jsonl") > /dev/null || { echo "slurm_sweep: Slurm and local results differ" >&2; exit 1; }
diff <(failures "$T/out-local/summary.json") <(failures "$T/out-slurm/summary.json") || { echo "slurm_sweep: shrunk failures differ" >&2; exit 1; }
tasks=$(ls "$T"/out-slurm/slurm/submit-1/task-*.log | wc -l)
echo "slurm_sweep: $POINTS points in $tasks array tasks + merge: $(python3 -c "print(round($t2 - $t1, 1))") s on Slurm, $(python3 -c "print(round($t3 - $t2, 1))") s locally; the results are the same"

# 2. Two points lost: submitting again runs only those.
rm "$T/out-slurm/points/000001.json" "$T/out-slurm/points/000003.json" "$T/out-slurm/results.jsonl" "$T/out-slurm/summary.json"
rm -r "$T/out-slurm/runs/000001" "$T/out-slurm/runs/000003"
"$HARNESS" sweep submit "$SWEEP" --out "$T/out-slurm" --points "$POINTS" --chunk 2 --no-db
[ "$(cat "$T/out-slurm/slurm/submit-2/points.txt" | tr '\n' ' ')" = "1 3 " ] || { echo "slurm_sweep: the resubmission does not list exactly points 1 and 3" >&2; exit 1; }
wait_for_queue
[ "$(ls "$T"/out-slurm/slurm/submit-2/task-*.log | wc -l)" = 1 ] || { echo "slurm_sweep: the resubmission ran more than one array task" >&2; exit 1; }
diff <(strip "$T/out-local/results.jsonl") <(strip "$T/out-slurm/results.jsonl") > /dev/null || { echo "slurm_sweep: results differ after the resubmission" >&2; exit 1; }
echo "slurm_sweep: the resubmission ran points 1 and 3 only; the results are the same"
