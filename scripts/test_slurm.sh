#!/usr/bin/env bash
# make test-slurm: the workflow through a real Slurm on this machine. Starts munged, slurmctld and
# slurmd (as root, Debian's slurm-wlm and munge) with a minimal single-node configuration in a
# temporary folder (NodeName=localhost CPUs=2, proctrack/linuxproc, task/none, state and spool
# there), runs scripts/workflow/Snakefile with the Slurm profile (scripts/workflow/profiles/slurm) on three
# synthetic recordings, checks that every stage ran as a Slurm job and that the outputs and the
# summary are there, and stops its daemons (trap), leaving nothing running.
#   scripts/test_slurm.sh OBJMAP_BINARY [KEEP_DIR]
set -euo pipefail
objmap=$(realpath "$1")
source_dir=$(cd "$(dirname "$0")/.." && pwd)
[ "$(id -u)" -eq 0 ] || { echo "test-slurm: must run as root (it starts slurmctld and slurmd)" >&2; exit 2; }
for tool in munged slurmctld slurmd sbatch scontrol sinfo snakemake; do
  command -v "$tool" > /dev/null || { echo "test-slurm: $tool missing (scripts/install-deps.sh --slurm)" >&2; exit 2; }
done

tmp=$(mktemp -d /tmp/objmap-slurm.XXXXXX)
chmod 755 "$tmp"
pids=()
stop() {
  # Only the daemons this script started, by their pid.
  for pidfile in "$tmp/slurmd.pid" "$tmp/slurmctld.pid" "$tmp/munge/munged.pid"; do
    [ -s "$pidfile" ] || continue
    pid=$(cat "$pidfile")
    kill "$pid" 2> /dev/null || true
    for _ in $(seq 50); do kill -0 "$pid" 2> /dev/null || break; sleep 0.1; done
    kill -9 "$pid" 2> /dev/null || true
  done
  rm -rf "$tmp"
}
trap stop EXIT

# munge: its own key, socket and pid under $tmp.
mkdir -p "$tmp/munge" "$tmp/state" "$tmp/spool"
chmod 700 "$tmp/munge"
mungekey --create --keyfile="$tmp/munge/munge.key" 2> /dev/null || \
  dd if=/dev/urandom of="$tmp/munge/munge.key" bs=1 count=1024 status=none
chmod 400 "$tmp/munge/munge.key"
munged --key-file="$tmp/munge/munge.key" --socket="$tmp/munge/munge.socket" \
  --pid-file="$tmp/munge/munged.pid" --log-file="$tmp/munge/munged.log" \
  --seed-file="$tmp/munge/munged.seed" --force

port=$((17000 + RANDOM % 2000))
cat > "$tmp/slurm.conf" <<EOF
ClusterName=objmaptest
SlurmctldHost=localhost
SlurmUser=root
SlurmdUser=root
SlurmctldPort=$port
SlurmdPort=$((port + 1))
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$tmp/munge/munge.socket
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/slurmctld.log
SlurmdLogFile=$tmp/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
SlurmdParameters=config_overrides
ReturnToService=2
MpiDefault=none
NodeName=localhost CPUs=2 RealMemory=4000 State=UNKNOWN
PartitionName=test Nodes=localhost Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF="$tmp/slurm.conf"
slurmctld -f "$SLURM_CONF"
slurmd -f "$SLURM_CONF"
for _ in $(seq 60); do
  sinfo -h -o '%T' 2> /dev/null | grep -qE '^(idle|mixed)' && break
  sleep 0.5
done
echo "slurm       $(sinfo -h -o '%P %D node(s) %c cpus %m MB %T')"
sinfo -h -o '%T' | grep -qE '^(idle|mixed)' || { echo "test-slurm: the node did not come up"; tail -5 "$tmp/slurmd.log" "$tmp/slurmctld.log"; exit 1; }

# Three synthetic recordings and their manifest.
work="$tmp/work"
mkdir -p "$work"
printf 'name\tdataset\ttrajectory\tsegmentation\tgt_trajectory\tgt_objects\tcorrect\n' > "$work/recordings.tsv"
for seed in 1 2 3; do
  "$objmap" synth --out "$work/scene$seed" --seed "$seed" --frames 30 --scale 0.5 > /dev/null 2>&1
  correct=$([ "$seed" -eq 1 ] && echo yes || echo no)
  printf 'synthetic%s\tscene%s\tscene%s/estimated.txt\tscene%s/segmentation\tscene%s/groundtruth.txt\tscene%s/objects_gt.json\t%s\n' \
    "$seed" "$seed" "$seed" "$seed" "$seed" "$seed" "$correct" >> "$work/recordings.tsv"
done

start=$(date +%s)
(cd "$work" && snakemake -s "$source_dir/scripts/workflow/Snakefile" --profile "$source_dir/scripts/workflow/profiles/slurm" \
   --config manifest=recordings.tsv results=results "objmap=$objmap" > snakemake.log 2>&1) || {
  echo "test-slurm: snakemake failed"; tail -30 "$work/snakemake.log"; exit 1; }
seconds=$(( $(date +%s) - start ))

jobs=$(grep -c "Submitted job .* with external jobid" "$work/snakemake.log" || true)
slurm_logs=$(ls "$work/slurm-logs" | wc -l)
echo "workflow    $jobs jobs submitted through sbatch, $slurm_logs Slurm job logs, ${seconds} s"
echo "jobs        $(grep -o "with external jobid '[0-9]*'" "$work/snakemake.log" | grep -o '[0-9]*' | tr '\n' ' ')"
grep -h "^rule \|^localrule " "$work/snakemake.log" | sort | uniq -c | sed 's/^/  /'
status=0
for n in synthetic1 synthetic2 synthetic3; do
  for f in map/objects.json eval/ate.json eval/objects.json report/report.html; do
    [ -f "$work/results/$n/$f" ] || { echo "missing: $n/$f"; status=1; }
  done
done
[ -f "$work/results/synthetic1/corrected/trajectory_corrected.txt" ] || { echo "missing: corrected"; status=1; }
# Slurm's own record: every job it accepted, its state, and the CPUs and memory it gave it.
accepted=$(grep -c "_slurm_rpc_submit_batch_job: JobId=" "$tmp/slurmctld.log" || true)
completed=$(scontrol -o show job | grep -c "JobState=COMPLETED" || true)
echo "slurmctld   $accepted batch jobs accepted, $completed completed; per job name, CPUs and memory:"
scontrol -o show job | grep -o 'JobName=[^ ]*\|NumCPUs=[0-9]*\|MinMemoryNode=[^ ]*' | paste - - - |
  sort | uniq -c | sed 's/^ */  /'
[ "$completed" -eq "$jobs" ] || { echo "Slurm completed $completed jobs, Snakemake submitted $jobs"; status=1; }
[ "$accepted" -eq "$jobs" ] || { echo "Slurm accepted $accepted jobs, Snakemake submitted $jobs"; status=1; }
[ "$jobs" -ge 22 ] || { echo "expected at least 22 Slurm jobs, got $jobs"; status=1; }
echo
grep "recordings:" "$work/results/summary/summary.md"
sed -n '/^| recording | status/,/^$/p' "$work/results/summary/summary.md"
sed -n '/^## Time and memory per stage/,/^$/{/^## /!p};/^| stage |/,/^$/p' "$work/results/summary/summary.md" | awk 'NF' | uniq
if [ -n "${2:-}" ]; then rm -rf "$2"; cp -r "$work" "$2"; echo "kept        $2"; fi
[ $status -eq 0 ] && echo "test-slurm: ok" || echo "test-slurm: FAILED"
exit $status
