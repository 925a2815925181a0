#!/usr/bin/env bash
# The workflow on a real SLURM, through Snakemake's executor plugin (make slurm-test).
#
# Installs Debian's slurm-wlm and munge (apt-get, as root), starts munged, slurmctld and
# slurmd on this machine (one node, its CPUs, no accounting database: the plugin then
# asks squeue, not sacct, for its jobs' states), runs the default campaign and a reduced
# behaviour map once locally (snakemake --cores 2) and once through profiles/slurm,
# checks that every output is byte-identical, then makes one map shard fail on purpose
# (a test config) to see Snakemake report it with its SLURM log and retry it, and a
# rerun complete only what is missing. Every daemon it started is stopped on exit.
#
# Usage: tests/slurm/run.sh [WORKDIR]   (default: a new temporary folder)
set -euo pipefail

ROOT="$(cd "$(dirname "$0")/../.." && pwd)"
BIN="$ROOT/.venv/bin"
WORK="${1:-$(mktemp -d /tmp/slipwave-slurm.XXXXXX)}"
mkdir -p "$WORK"
export PATH="$BIN:$PATH"
started=()
began=$(date +%s)

say() { printf '[slurm-test %4ds] %s\n' "$(( $(date +%s) - began ))" "$*"; }

stop_daemons() {
    for name in "${started[@]}"; do
        pkill -x "$name" 2>/dev/null || true
    done
    [ "${#started[@]}" -gt 0 ] && say "stopped: ${started[*]}"
    if [ -e "$WORK/slurm.conf.site" ]; then
        cp "$WORK/slurm.conf.site" /etc/slurm/slurm.conf
    else
        rm -f /etc/slurm/slurm.conf
    fi
    return 0
}
trap stop_daemons EXIT

# 1. Debian's SLURM and munge, and the executor plugin.
if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
    if [ "$(id -u)" != 0 ]; then
        echo "slurm-wlm and munge are missing and only root can apt-get them" >&2
        exit 1
    fi
    say "installing slurm-wlm and munge (apt-get)"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurm-wlm munge >/dev/null
fi
"$BIN/python" -m pip install --quiet -e "$ROOT[slurm]"

# 2. A one-node cluster on localhost.
node="$(hostname -s)"
cpus="$(nproc)"
memory_mb=$(( $(awk '/MemTotal/ {print $2}' /proc/meminfo) / 1024 - 1024 ))
conf="$WORK/slurm"
mkdir -p "$conf/state" "$conf/spool" "$conf/logs"
cat > "$conf/slurm.conf" <<EOF
ClusterName=slipwave-test
SlurmctldHost=$node
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
StateSaveLocation=$conf/state
SlurmdSpoolDir=$conf/spool
SlurmctldPidFile=$conf/slurmctld.pid
SlurmdPidFile=$conf/slurmd.pid
SlurmctldLogFile=$conf/logs/slurmctld.log
SlurmdLogFile=$conf/logs/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
ReturnToService=2
MinJobAge=600
# no accounting database: the executor plugin is told to ask squeue (see below)
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
NodeName=$node CPUs=$cpus RealMemory=$memory_mb State=UNKNOWN
PartitionName=debug Nodes=$node Default=YES MaxTime=INFINITE State=UP
EOF
# The jobs' own srun reads the default location (the plugin's jobs do not inherit
# SLURM_CONF): put the test's configuration there, and any site's back on exit.
if [ -e /etc/slurm/slurm.conf ] && [ ! -e "$WORK/slurm.conf.site" ]; then
    cp /etc/slurm/slurm.conf "$WORK/slurm.conf.site"
fi
mkdir -p /etc/slurm
cp "$conf/slurm.conf" /etc/slurm/slurm.conf
export SLURM_CONF=/etc/slurm/slurm.conf

if ! pgrep -x munged >/dev/null; then
    [ -s /etc/munge/munge.key ] || mungekey --create --force 2>/dev/null \
        || create-munge-key -f >/dev/null
    mkdir -p /run/munge && chown munge:munge /run/munge 2>/dev/null || true
    munged --force
    started+=(munged)
fi
slurmctld -c
started+=(slurmctld)
slurmd
started+=(slurmd)
for _ in $(seq 60); do
    sinfo -h -o %T 2>/dev/null | grep -qx idle && break
    sleep 1
done
sinfo -h -o %T | grep -qx idle || { echo "the node never became idle:" >&2; sinfo >&2; exit 1; }
say "cluster up: node $node, $cpus CPUs, $memory_mb MB"

# 3. The same workflow twice: locally, then through the plugin.
CONFIG="$ROOT/tests/slurm/reduced.yaml"
SLURM_ARGS=(--profile profiles/slurm --slurm-status-command squeue --slurm-no-account
            --slurm-init-seconds-before-status-checks 2 --configfile reduced.yaml)
copy() {
    rm -rf "$1" && mkdir -p "$1"
    for name in Snakefile workflow config profiles raw_data; do
        cp -r "$ROOT/$name" "$1/"
    done
    cp "$CONFIG" "$1/reduced.yaml"
}
outputs() {  # checksums of every output but the logs
    (cd "$1" && find results reports -type f ! -path 'results/logs/*' ! -name '*.log' \
        ! -name README.md -print0 | sort -z | xargs -0 sha256sum)
}

copy "$WORK/local"
say "local run (snakemake --cores 2)"
(cd "$WORK/local" && snakemake --cores 2 --configfile reduced.yaml --quiet rules \
    > "$WORK/local.log" 2>&1)

copy "$WORK/cluster"
say "SLURM run (snakemake --profile profiles/slurm)"
(cd "$WORK/cluster" && snakemake "${SLURM_ARGS[@]}" > "$WORK/cluster.log" 2>&1)
jobs=$(grep -c "has been submitted with SLURM jobid" "$WORK/cluster.log" || true)
say "SLURM jobs submitted: $jobs"

outputs "$WORK/local" > "$WORK/local.sha256"
outputs "$WORK/cluster" > "$WORK/cluster.sha256"
if ! diff -u "$WORK/local.sha256" "$WORK/cluster.sha256"; then
    echo "the SLURM run's outputs differ from the local run's" >&2
    exit 1
fi
say "$(wc -l < "$WORK/local.sha256") outputs byte-identical (checksums: $WORK/local.sha256)"

# 4. A job that fails: reported with its SLURM log, retried with more memory; then,
# without retries, a failure that stays, and a rerun that makes only what is missing.
fail() { echo "$*" >&2; exit 1; }
copy "$WORK/failing"
cp "$ROOT/tests/slurm/failing.yaml" "$WORK/failing/failing.yaml"
FAILING=(--profile profiles/slurm --slurm-status-command squeue --slurm-no-account
         --slurm-init-seconds-before-status-checks 2 --configfile failing.yaml)
say "a map job that needs more memory than its first attempt has (retries: 2)"
(cd "$WORK/failing" && snakemake results/map/map.nc "${FAILING[@]}" > "$WORK/retried.log" 2>&1) \
    || fail "the retried run failed: $WORK/retried.log"
grep -q "Error in rule map_row" "$WORK/retried.log" || fail "no failure was reported"
grep -Eo "slurm_logs/[^ ]+\.log" "$WORK/retried.log" | head -1 | sed 's/^/  its SLURM log: /'
grep -q "Trying to restart" "$WORK/retried.log" || fail "the failed job was not retried"
say "failed at attempt 1 (30 MB), passed at attempt 2 (60 MB): $(grep -c 'Trying to restart' "$WORK/retried.log" || true) restart(s)"

rm -f "$WORK/failing/results/map/rows/160/job0-0.nc" "$WORK/failing/results/map/map.nc"
say "the same without retries: the job fails for good"
set +e
(cd "$WORK/failing" && snakemake results/map/map.nc "${FAILING[@]}" --retries 0 \
    > "$WORK/failed.log" 2>&1)
status=$?
set -e
[ "$status" != 0 ] || fail "the run without retries did not fail"
[ ! -e "$WORK/failing/results/map/rows/160/job0-0.nc" ] || fail "a failed job left its output"
grep -q "needs about" "$WORK/failing/results/logs/map/160/job0-0.log" \
    || fail "the job's log does not say why it failed"
sed 's/^/  its log: /' "$WORK/failing/results/logs/map/160/job0-0.log" | tail -1
say "rerun with its memory raised (--set-resources map_row:mem_mb=1000)"
(cd "$WORK/failing" && snakemake results/map/map.nc "${FAILING[@]}" \
    --set-resources map_row:mem_mb=1000 > "$WORK/rerun.log" 2>&1) \
    || fail "the rerun failed: $WORK/rerun.log"
rerun=$(grep -c "has been submitted with SLURM jobid" "$WORK/rerun.log" || true)
[ "$(grep -c "wildcards: height_ratio=0.25" "$WORK/rerun.log")" = 0 ] \
    || fail "the rerun made again a shard that was already there"
say "rerun: $rerun SLURM jobs (the missing shard and the map), the rest kept"
say "passed in $(( $(date +%s) - began )) s; work folder $WORK"
