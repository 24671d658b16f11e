#!/usr/bin/env bash
# End-to-end test of scripts/reference-slurm.sh on a real one-node Slurm cluster.
#
#   cargo build --release && scripts/install-slurm.sh && scripts/test-slurm.sh
#
# Everything lives in a fresh temporary directory: a munge key and socket, a slurm.conf
# (SLURM_CONF) for this machine's CPUs and memory with proctrack/linuxproc, task/none, no
# accounting and no cgroups, and the daemons' state and logs. munged, slurmctld and slurmd run
# as children of this script (no systemd), on ports of their own, and are stopped, and the
# directory removed, on any exit. Needs root (or a user that may run the daemons), the
# binaries from scripts/install-slurm.sh, python3, and target/release/dibench (built first;
# this script builds nothing; DIBENCH_TARGET names another build directory, which the jobs
# get as DIBENCH_BIN). Then:
#   1. a 4-task array of reference-slurm.sh plus an afterok `dibench merge` job: the merged
#      reference must match a single-process `dibench reference` of the same spp and seed up
#      to f32 roundoff (the equality shard.rs promises), and its shards must be bit for bit
#      the shards a local `reference --shard i/4` writes;
#   2. an array whose task 2 exits 1 plus an afterok merge: the task must be reported FAILED
#      and the merge cancelled without running.
# Prints PASS/FAIL lines; exits non-zero on any failure. Every wait has a timeout
# (DIBENCH_SLURM_TIMEOUT seconds per wait, default 90); DIBENCH_SLURM_KEEP=1 keeps the
# temporary directory for inspection.
set -euo pipefail

repo=$(cd "$(dirname "$0")/.." && pwd)
cd "$repo"
export PATH="$PATH:/usr/sbin:/sbin"
wait_s=${DIBENCH_SLURM_TIMEOUT:-90}
scene=cornell
spp=256
seed=7
shards=4
failures=0

pass() { echo "PASS: $*"; }
failed() {
  echo "FAIL: $*"
  failures=$((failures + 1))
}
die() {
  echo "FAIL: $*" >&2
  exit 1
}

missing=()
for tool in munged mungekey slurmctld slurmd sbatch sinfo scontrol scancel squeue python3; do
  command -v "$tool" >/dev/null 2>&1 || missing+=("$tool")
done
if [ ${#missing[@]} -gt 0 ]; then
  die "missing ${missing[*]}: run scripts/install-slurm.sh first (apt-get install slurmctld slurmd slurm-client munge; .ci/run installs them that way)"
fi
[ "$(id -u)" -eq 0 ] || die "must run as root: slurmctld here runs as SlurmUser=root"
target=${DIBENCH_TARGET:-target/release}
case $target in /*) ;; *) target=$repo/$target ;; esac
bin=$target/dibench
export DIBENCH_BIN=$bin
[ -x "$bin" ] || die "$bin not found: build it first (cargo build --release); this test builds nothing"

# A job or shell of an outer Slurm must not leak into this cluster.
while read -r v; do unset "$v"; done < <(compgen -e | grep '^SLURM_' || true)

tmp=$(mktemp -d "${TMPDIR:-/tmp}/dibench-slurm.XXXXXX")
chmod 711 "$tmp" # munged wants its socket's directories searchable by all
pids=()          # daemons, in start order
jobs_submitted=()
array='' merge='' array2='' merge2='' redo='' merge3='' # job ids, set by submit

stop() {
  local rc=$?
  set +e
  if [ ${#jobs_submitted[@]} -gt 0 ] && [ -e "$tmp/slurm.conf" ]; then
    timeout 10 scancel "${jobs_submitted[@]}" >/dev/null 2>&1
    # Let the job steps of slurmd end before slurmd does.
    local until=$((SECONDS + 15))
    while [ $SECONDS -lt $until ] &&
      [ -n "$(timeout 5 squeue -h -o %i 2>/dev/null)" ]; do
      sleep 0.5
    done
  fi
  local i pid
  for ((i = ${#pids[@]} - 1; i >= 0; i--)); do
    pid=${pids[i]}
    kill -TERM "$pid" 2>/dev/null || continue
    local until=$((SECONDS + 10))
    while kill -0 "$pid" 2>/dev/null && [ $SECONDS -lt $until ]; do sleep 0.2; done
    kill -KILL "$pid" 2>/dev/null
    wait "$pid" 2>/dev/null
  done
  if [ "$rc" -ne 0 ] && [ -d "$tmp/log" ]; then
    for f in "$tmp"/log/* "$tmp"/jobs/*; do
      [ -f "$f" ] || continue
      echo "--- last lines of $f"
      tail -n 15 "$f"
    done
  fi
  if [ "${DIBENCH_SLURM_KEEP:-0}" = 1 ]; then
    echo "kept $tmp"
  else
    rm -rf "$tmp"
  fi
  exit "$rc"
}
trap stop EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

# Runs "$@" until it succeeds, at most $1 seconds; 1 if it never did.
wait_until() {
  local until=$((SECONDS + $1))
  shift
  until "$@"; do
    [ $SECONDS -lt "$until" ] || return 1
    sleep 0.2
  done
}

port_free() { ! (exec 3<>"/dev/tcp/127.0.0.1/$1") 2>/dev/null; }
port=
for _ in $(seq 50); do
  p=$((20000 + RANDOM % 12000)) # below the ephemeral range
  if port_free "$p" && port_free $((p + 1)); then
    port=$p
    break
  fi
done
[ -n "$port" ] || die "no two free TCP ports found"

node=$(hostname -s)
cpus=$(slurmd -C | sed -n 's/.*CPUs=\([0-9]*\).*/\1/p')
mem=$(slurmd -C | sed -n 's/.*RealMemory=\([0-9]*\).*/\1/p')
if [ -z "$cpus" ] || [ -z "$mem" ]; then
  die "slurmd -C did not report CPUs and RealMemory"
fi
mkdir -m 700 "$tmp/munge" "$tmp/state" "$tmp/spool" "$tmp/log"
mkdir -m 755 "$tmp/run"
mkdir "$tmp/jobs"
cat >"$tmp/slurm.conf" <<EOF
ClusterName=dibench-ci
SlurmctldHost=$node(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$tmp/run/munge.socket
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/run/slurmctld.pid
SlurmdPidFile=$tmp/run/slurmd.pid
SlurmctldLogFile=$tmp/log/slurmctld.log
SlurmdLogFile=$tmp/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SwitchType=switch/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
ReturnToService=2
MailProg=/bin/true
MinJobAge=600
KillWait=5
NodeName=$node NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=ci Nodes=$node Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF=$tmp/slurm.conf

# Seconds since the date +%s%N stamp $1, to 0.1 s.
since() {
  local ms=$((($(date +%s%N) - $1) / 1000000))
  printf '%d.%d' $((ms / 1000)) $((ms % 1000 / 100))
}
start=$SECONDS
t0=$(date +%s%N)
mungekey -c -k "$tmp/munge/munge.key" 2>"$tmp/log/mungekey.log"
munged -F --key-file="$tmp/munge/munge.key" --socket="$tmp/run/munge.socket" \
  --pid-file="$tmp/run/munged.pid" --seed-file="$tmp/munge/seed" \
  --log-file="$tmp/log/munged.log" >"$tmp/log/munged.out" 2>&1 &
pids+=($!)
wait_until 10 test -S "$tmp/run/munge.socket" || die "munged did not create its socket"
slurmctld -D -f "$SLURM_CONF" >"$tmp/log/slurmctld.out" 2>&1 &
pids+=($!)
slurmd -D -f "$SLURM_CONF" -N "$node" >"$tmp/log/slurmd.out" 2>&1 &
pids+=($!)
node_idle() { [ "$(timeout 5 sinfo -h -n "$node" -o %T 2>/dev/null)" = idle ]; }
if wait_until "$wait_s" node_idle; then
  pass "one-node cluster up: node $node idle after $(since "$t0") s ($cpus CPUs, ports $port-$((port + 1)))"
else
  die "node $node not idle within ${wait_s}s (sinfo: $(timeout 5 sinfo -h -o '%T %E' 2>&1))"
fi

# submit VAR ARGS...: sbatch --parsable ARGS, the job id into VAR (and the list to cancel).
submit() {
  local var=$1 id
  shift
  id=$(timeout 20 sbatch --parsable "$@") || die "sbatch $* failed"
  id=${id%%;*}
  jobs_submitted+=("$id")
  printf -v "$var" %s "$id"
}
# `scontrol show job` of $1, one line per (array task) record.
records() { timeout 10 scontrol -o show job "$1" 2>/dev/null; }
field() { sed -n "s/.*[[:space:]]$1=\([^[:space:]]*\).*/\1/p"; }
# True once every record of job $1 is in a final state.
finished() {
  local r
  r=$(records "$1") || return 1
  [ -n "$r" ] || return 1
  ! echo "$r" | field JobState | grep -qvE '^(COMPLETED|FAILED|CANCELLED|TIMEOUT|NODE_FAIL|OUT_OF_MEMORY|BOOT_FAIL|DEADLINE|PREEMPTED)$'
}
# "task:state:exit" for every record of job $1.
states() {
  records "$1" | while read -r line; do
    echo "$(echo "$line" | field ArrayTaskId):$(echo "$line" | field JobState):$(echo "$line" | field ExitCode)"
  done | sort
}
references_in() { find "$1" -path "*/$scene/reference/*.json" -not -path '*/shards/*' 2>/dev/null | sort; }

# 1. The array and its merge, against single-process and local-shard renders.
slurm_out=$tmp/out-slurm
t1=$SECONDS
submit array --array=0-$((shards - 1)) --cpus-per-task=1 --export=ALL,DIBENCH_OUT="$slurm_out" \
  --output="$tmp/jobs/ok-%A_%a.log" scripts/reference-slurm.sh "$scene" "$spp" "$seed"
submit merge --dependency=afterok:"$array" --kill-on-invalid-dep=yes --cpus-per-task=1 \
  --output="$tmp/jobs/ok-merge-%j.log" \
  --wrap="exec '$bin' merge '$scene' --out '$slurm_out'"
if wait_until "$wait_s" finished "$merge" && finished "$array"; then
  got=$(states "$array" | tr '\n' ' ')
  if [ "$(states "$array" | grep -c ':COMPLETED:0:0$')" -eq "$shards" ]; then
    pass "array $array: $shards tasks COMPLETED ($got)"
  else
    failed "array $array: expected $shards COMPLETED tasks, got $got"
  fi
  m=$(states "$merge")
  if [ "$m" = ":COMPLETED:0:0" ]; then
    pass "merge job $merge COMPLETED after the array ($((SECONDS - t1)) s from submission)"
  else
    failed "merge job $merge: $m; log: $(cat "$tmp"/jobs/ok-merge-*.log 2>/dev/null)"
  fi
else
  failed "array $array and merge $merge not finished within ${wait_s}s: $(states "$array" | tr '\n' ' ') / $(states "$merge")"
fi

single_out=$tmp/out-single
t_local=$SECONDS
timeout "$wait_s" "$bin" reference "$scene" --spp "$spp" --seed "$seed" --out "$single_out" \
  >"$tmp/log/single.log" 2>&1 || die "single-process reference failed (exit $?, 124 if past ${wait_s}s): $(tail -n 5 "$tmp/log/single.log")"
local_out=$tmp/out-local
for ((i = 0; i < shards; i++)); do
  timeout "$wait_s" "$bin" reference "$scene" --spp "$spp" --seed "$seed" --shard "$i/$shards" \
    --out "$local_out" >>"$tmp/log/local.log" 2>&1 || die "local shard $i/$shards failed (exit $?, 124 if past ${wait_s}s): $(tail -n 5 "$tmp/log/local.log")"
done

echo "rendered the single-process reference and $shards local shards in $((SECONDS - t_local)) s"
mapfile -t singles < <(references_in "$single_out")
[ ${#singles[@]} -gt 0 ] || die "the single-process reference wrote no manifest under $single_out"
for ref in "${singles[@]}"; do
  name=${ref#"$single_out"/}
  merged=$slurm_out/$name
  if [ ! -f "$merged" ]; then
    failed "$name: the Slurm merge wrote no such reference"
    continue
  fi
  if report=$(python3 scripts/exr-compare.py "$ref" "$merged" 2>&1); then
    pass "$name: Slurm merge equals the single-process reference up to f32 roundoff: $(echo "$report" | tr '\n' ';')"
  else
    failed "$name: Slurm merge differs from the single-process reference: $(echo "$report" | tr '\n' ';')"
  fi
done
if [ "$(references_in "$slurm_out" | sed "s|^$slurm_out/||")" = "$(printf '%s\n' "${singles[@]}" | sed "s|^$single_out/||")" ]; then
  pass "the Slurm merge wrote the same reference set (${#singles[@]} integrand(s))"
else
  failed "reference sets differ: Slurm $(references_in "$slurm_out" | tr '\n' ' ') vs single $(printf '%s ' "${singles[@]}")"
fi
# The shard films (f64 sums and M2) of the array are those of local --shard runs, bit for bit.
shard_sums() { (cd "$1/$scene/reference/shards" && sha256sum -- *.bin 2>/dev/null | sort -k2); }
if [ -n "$(shard_sums "$local_out")" ] && [ "$(shard_sums "$slurm_out")" = "$(shard_sums "$local_out")" ]; then
  pass "the array's $(shard_sums "$slurm_out" | wc -l) shard films equal local --shard i/$shards renders byte for byte"
else
  failed "shard films differ: Slurm [$(shard_sums "$slurm_out" | tr '\n' ' ')] vs local [$(shard_sums "$local_out" | tr '\n' ' ')]"
fi

# 2. A failing task: the array is reported failed and the afterok merge never runs.
cat >"$tmp/failing-shard.sh" <<EOF
#!/usr/bin/env bash
# Shard 2 fails on purpose; the others are ordinary reference-slurm.sh tasks.
set -euo pipefail
if [ "\$SLURM_ARRAY_TASK_ID" = 2 ]; then
  echo "task 2 fails on purpose" >&2
  exit 1
fi
exec '$repo/scripts/reference-slurm.sh' "\$@"
EOF
chmod +x "$tmp/failing-shard.sh"
fail_out=$tmp/out-failing
t2=$SECONDS
submit array2 --array=0-$((shards - 1)) --cpus-per-task=1 --export=ALL,DIBENCH_OUT="$fail_out" \
  --output="$tmp/jobs/bad-%A_%a.log" "$tmp/failing-shard.sh" "$scene" "$spp" "$seed"
submit merge2 --dependency=afterok:"$array2" --kill-on-invalid-dep=yes --cpus-per-task=1 \
  --output="$tmp/jobs/bad-merge-%j.log" \
  --wrap="exec '$bin' merge '$scene' --out '$fail_out'"
if wait_until "$wait_s" finished "$array2" && wait_until "$wait_s" finished "$merge2"; then
  got=$(states "$array2" | tr '\n' ' ')
  if states "$array2" | grep -q '^2:FAILED:1:0$' &&
    [ "$(states "$array2" | grep -c ':COMPLETED:0:0$')" -eq $((shards - 1)) ]; then
    pass "array $array2: task 2 FAILED with exit code 1, the other $((shards - 1)) COMPLETED ($got)"
  else
    failed "array $array2: expected task 2 FAILED (1:0) and the rest COMPLETED, got $got"
  fi
  m=$(records "$merge2")
  state=$(echo "$m" | field JobState)
  reason=$(echo "$m" | field Reason)
  if [ "$state" = CANCELLED ] && [ "$reason" = DependencyNeverSatisfied ]; then
    pass "merge job $merge2 CANCELLED, reason DependencyNeverSatisfied ($((SECONDS - t2)) s from submission)"
  else
    failed "merge job $merge2: state $state, reason $reason (expected CANCELLED, DependencyNeverSatisfied)"
  fi
  if ! compgen -G "$tmp/jobs/bad-merge-*.log" >/dev/null && [ -z "$(references_in "$fail_out")" ]; then
    pass "the merge never ran: no merge log, no merged reference under the failing run's output"
  else
    failed "the merge ran: $(ls "$tmp"/jobs/bad-merge-*.log 2>/dev/null) $(references_in "$fail_out")"
  fi
else
  failed "array $array2 / merge $merge2 not finished within ${wait_s}s: $(states "$array2" | tr '\n' ' ') / $(states "$merge2")"
fi

# 3. Recovery: task 2 again alone (DIBENCH_SHARDS keeps it shard 2 of 4), then the merge; the
# result has the first merge's pixels exactly (same shard films, merged in the same order; the
# files' bytes differ only in the render time their headers record).
submit redo --array=2 --cpus-per-task=1 \
  --export=ALL,DIBENCH_OUT="$fail_out",DIBENCH_SHARDS="$shards" \
  --output="$tmp/jobs/redo-%A_%a.log" scripts/reference-slurm.sh "$scene" "$spp" "$seed"
submit merge3 --dependency=afterok:"$redo" --kill-on-invalid-dep=yes --cpus-per-task=1 \
  --output="$tmp/jobs/redo-merge-%j.log" \
  --wrap="exec '$bin' merge '$scene' --out '$fail_out'"
same_pixels() {
  local a
  for a in "$slurm_out/$scene/reference/"*.json; do
    python3 scripts/exr-compare.py "$a" "$fail_out/$scene/reference/$(basename "$a")" --rel 1e-300 >/dev/null 2>&1 || return 1
  done
}
if wait_until "$wait_s" finished "$merge3" && finished "$redo"; then
  if [ "$(states "$redo")" = "2:COMPLETED:0:0" ] && [ "$(states "$merge3")" = ":COMPLETED:0:0" ] &&
    [ -n "$(references_in "$fail_out")" ] && same_pixels; then
    pass "task 2 redone alone (--array=2, DIBENCH_SHARDS=$shards) and merged: the first merge's pixels, exactly"
  else
    failed "redo: $(states "$redo") / merge $(states "$merge3"); $(cat "$tmp"/jobs/redo-*.log 2>/dev/null | tail -n 3)"
  fi
else
  failed "redo $redo / merge $merge3 not finished within ${wait_s}s: $(states "$redo") / $(states "$merge3")"
fi

if [ "$failures" -eq 0 ]; then
  echo "PASS: test-slurm ($((SECONDS - start)) s from starting munged)"
else
  echo "FAIL: test-slurm: $failures check(s) failed"
  exit 1
fi
