#!/usr/bin/env bash
# The Slurm path of docs/distributed.md ("Slurm"), on a real one-node Slurm cluster started on
# this machine (scripts/slurm/local-cluster.sh; as root, with slurm-wlm and munge installed).
#   1. Submits the job array and the merge job with the very command lines of
#      docs/distributed.md (read from it), waits, and checks that the merged image is bit for
#      bit the same render done in one process.
#   2. Submits them again, and stops two array tasks in the middle of their renders: task 1
#      with SIGKILL, task 2 with SIGTERM (what scancel and a time limit send). Checks that
#      task 1 left no file, that the merge refuses task 2's unfinished shard and the set,
#      that the merge job waits (DependencyNeverSatisfied), and that running the two tasks
#      again as the doc says completes the set: the merge job then runs, and its image is
#      again bit-identical to the one-process render.
#   3. A reference as a job array and its merge, then a convergence study against it as a job
#      array (one estimator a task) and the job that joins the rows, again with the command
#      lines of docs/distributed.md; checks the merged reference against the one-process
#      reference bit for bit, and that the joined CSV and plot are there.
# The cluster is stopped, and its folder removed, on every exit (KEEP=1 keeps the folder).
# VKVCM names the binary (default: target/debug/vkvcm, the one `make test` built).
set -euo pipefail

root=$(cd "$(dirname "$0")/.." && pwd)
VKVCM=$(realpath "${VKVCM:-$root/target/debug/vkvcm}")
export VKVCM
[ -x "$VKVCM" ] || { echo "test-slurm.sh: no binary $VKVCM (cargo build first)" >&2; exit 1; }
doc=$root/docs/distributed.md
work=$(mktemp -d /tmp/vkvcm-slurm.XXXXXX)
start=$(date +%s)

cleanup() {
  local rc=$?
  bash "$root/scripts/slurm/local-cluster.sh" stop "$work/cluster" || true
  if [ "${KEEP:-0}" = 1 ] || [ $rc -ne 0 ]; then
    echo "test-slurm.sh: files kept in $work"
  else
    rm -rf "$work"
  fi
  exit $rc
}
trap cleanup EXIT
trap 'echo "test-slurm.sh: FAIL: line $LINENO: $BASH_COMMAND" >&2' ERR

# A progress line, with the seconds since the start.
say() {
  echo "test-slurm.sh: [$(($(date +%s) - start)) s] $*"
}

fail() {
  echo "test-slurm.sh: FAIL: $*" >&2
  for f in "$work"/*.out "$work"/failures/*.out; do
    [ -f "$f" ] && { echo "--- $f" >&2; cat "$f" >&2; }
  done
  exit 1
}

# The line of docs/distributed.md that starts with $1: a shell command the test runs as is.
doc_line() {
  local line
  line=$(awk -v p="$1" 'index($0, p) == 1 { print; exit }' "$doc")
  [ -n "$line" ] || fail "docs/distributed.md has no line starting with '$1'"
  printf '%s\n' "$line"
}

# The field $2 (JobState, ExitCode, Reason) of job $1 (a job id or ARRAYID_TASK); empty
# when slurmctld does not answer in 5 s.
job_field() {
  timeout 5 scontrol -o show job "$1" | tr ' ' '\n' | sed -n "s/^$2=//p" | head -n1
}

# Waits up to $2 seconds of wall time for job $1 to end; fails unless it ended in state $3.
wait_job() {
  local id=$1 want=$3 state deadline=$(($(date +%s) + $2))
  while [ "$(date +%s)" -lt "$deadline" ]; do
    state=$(job_field "$id" JobState)
    case "$state" in
      PENDING | RUNNING | CONFIGURING | COMPLETING | "") sleep 0.1 ;;
      *) break ;;
    esac
  done
  [ "$state" = "$want" ] || fail "job $id: state $state after up to $2 s, expected $want"
}

# The pid of array task $1's vkvcm once it is rendering: after its first progress line, which
# follows its first iteration. The log is read every 20 ms; fails if the task ends first.
rendering_pid() {
  local task=$1 log=vkvcm-shard-$1.out pid="" p i
  for i in $(seq 3000); do
    if [ -z "$pid" ]; then
      for p in $(scontrol listpids "$(job_field "$task" JobId)" 2>/dev/null | awk 'NR > 1 { print $1 }' || true); do
        [ "$(cat "/proc/$p/comm" 2>/dev/null)" = vkvcm ] && pid=$p
      done
    fi
    if [ -n "$pid" ] && grep -q '^progress:' "$log" 2>/dev/null; then
      echo "$pid"
      return 0
    fi
    if [ $((i % 25)) = 0 ]; then
      case "$(job_field "$task" JobState)" in
        PENDING | CONFIGURING | RUNNING) ;;
        *) fail "task $task ended before it could be stopped" ;;
      esac
    fi
    sleep 0.02
  done
  fail "task $task did not start rendering in 60 s"
}

export VK_DRIVER_FILES=${VK_DRIVER_FILES:-/usr/share/vulkan/icd.d/lvp_icd.json}
export VK_ICD_FILENAMES=${VK_ICD_FILENAMES:-$VK_DRIVER_FILES}
eval "$(bash "$root/scripts/slurm/local-cluster.sh" start "$work/cluster")"
say "one-node cluster up ($(sinfo -h -N -o '%N, %c CPUs'))"

# The render: tiny, and vcm (the default), whose merge radius follows the global iteration
# index. 128 iterations per shard, so that a shard renders long enough (0.5-1 s on a quiet
# machine) to be stopped in the middle: the signal follows its first progress line within
# about 20 ms.
repo=$root
n=3
render=(gbs_s --width 32 --height 32 --iterations 384 --seed 7)
cd "$work"
"$VKVCM" render "${render[@]}" -o one.exr --quiet
say "one-process render done"

submit_array=$(doc_line 'array=$(sbatch')
submit_merge=$(doc_line 'merge=$(sbatch')
rerun_task=$(doc_line 'rerun=$(sbatch')
update_merge=$(doc_line 'scontrol update')

# 1. The array and the merge as the doc submits them.
eval "$submit_array"
eval "$submit_merge"
say "1. array job $array and merge job $merge submitted"
wait_job "$merge" 120 COMPLETED
for k in $(seq 0 $((n - 1))); do
  [ "$(job_field "${array}_$k" JobState)" = COMPLETED ] || fail "array task ${array}_$k did not complete"
done
[ -s merged.png ] || fail "the merge job wrote no merged.png"
"$VKVCM" diff --exact merged.exr one.exr || fail "merged.exr differs from the one-process render"
say "1. merged image bit-identical to the one-process render"

# 2. The same in a second folder, with two array tasks stopped in the middle of their renders:
# task 1 killed with SIGKILL (as by the OOM killer: nothing can be written), task 2 sent SIGTERM
# (as by scancel or the time limit: vkvcm writes what it has rendered).
mkdir failures
cd failures
eval "$submit_array"
eval "$submit_merge"
pid=$(rendering_pid "${array}_1")
kill -KILL "$pid" || fail "task ${array}_1 finished before the SIGKILL reached it (a machine this loaded needs longer shards)"
say "2. array job $array: task 1 killed (SIGKILL) in the middle of its render"
pid=$(rendering_pid "${array}_2")
kill -TERM "$pid" || fail "task ${array}_2 finished before the SIGTERM reached it (a machine this loaded needs longer shards)"
say "2. task 2 sent SIGTERM in the middle of its render"
wait_job "${array}_0" 60 COMPLETED
wait_job "${array}_1" 30 FAILED
[ "$(job_field "${array}_1" ExitCode)" = 0:9 ] ||
  fail "task ${array}_1: exit $(job_field "${array}_1" ExitCode), expected 0:9 (killed by signal 9)"
grep -q 'wrote' "vkvcm-shard-${array}_1.out" && fail "task ${array}_1 wrote its shard before the kill"
wait_job "${array}_2" 30 FAILED
grep -q '(interrupted)' "vkvcm-shard-${array}_2.out" || fail "task ${array}_2 was not interrupted by the SIGTERM"
# Task 1 left nothing; task 2 its unfinished shard, which a merge refuses.
[ "$(cd shards && echo *)" = "shard-0.exr shard-2.exr" ] ||
  fail "the shards folder holds $(cd shards && echo *), expected shard-0.exr shard-2.exr"
if "$VKVCM" merge shards/shard-0.exr shards/shard-1.exr shards/shard-2.exr -o refused.exr 2>err.txt; then
  fail "a merge accepted the set whose shard 1 was killed"
fi
grep -qF shards/shard-1.exr err.txt || fail "the refusal does not name shards/shard-1.exr: $(cat err.txt)"
say "2. refused as it should be: $(cat err.txt)"
# The unfinished shard 2 among step 1's shards 0 and 1 (the same render, merged there).
if "$VKVCM" merge ../shards/shard-0.exr ../shards/shard-1.exr shards/shard-2.exr -o refused.exr 2>err.txt; then
  fail "a merge accepted the unfinished shard of the task sent SIGTERM"
fi
grep -qF shards/shard-2.exr err.txt || fail "the refusal does not name shards/shard-2.exr: $(cat err.txt)"
say "2. refused as it should be: $(cat err.txt)"
[ -e refused.exr ] && fail "a refused merge wrote refused.exr"
for _ in $(seq 50); do
  [ "$(job_field "$merge" Reason)" = DependencyNeverSatisfied ] && break
  sleep 0.1
done
[ "$(job_field "$merge" JobState)/$(job_field "$merge" Reason)" = PENDING/DependencyNeverSatisfied ] ||
  fail "merge job $merge: $(job_field "$merge" JobState)/$(job_field "$merge" Reason), expected PENDING/DependencyNeverSatisfied"
say "2. the merge job waits (DependencyNeverSatisfied)"
k=1,2
eval "$rerun_task"
eval "$update_merge"
wait_job "$merge" 120 COMPLETED
"$VKVCM" diff --exact merged.exr ../one.exr || fail "merged.exr after the re-run differs from the one-process render"
say "2. tasks 1 and 2 run again (job $rerun); merged image bit-identical to the one-process render"

# 3. A reference split over an array and merged, then a convergence study split over its
# estimators and joined, with the lines of docs/distributed.md ("References and convergence
# studies"), tiny: 2 reference shards of 3 iterations per half, 2 estimators of 0.2 s each.
mkdir "$work/study"
cd "$work/study"
n=2
ref=(glm_c --width 16 --height 16 --algo pt --iterations 12 --seed 7)
m=2
study=(glm_c --reference ref.exr --algos pt,bpt --time 0.2 --checkpoints 2)
"$VKVCM" reference "${ref[@]}" -o one-ref.exr >one-ref.txt 2>&1 || fail "vkvcm reference: $(cat one-ref.txt)"
eval "$(doc_line 'refs=$(sbatch')"
eval "$(doc_line 'refmerge=$(sbatch')"
eval "$(doc_line 'rows=$(sbatch')"
eval "$(doc_line 'plot=$(sbatch')"
say "3. reference array $refs, merge $refmerge, converge array $rows and rows job $plot submitted"
wait_job "$plot" 180 COMPLETED
"$VKVCM" diff --exact ref.exr one-ref.exr || fail "the merged reference differs from the one-process reference"
[ -s converge.png ] || fail "the rows job wrote no converge.png"
[ "$(cut -d, -f1 converge.csv | tr '\n' ' ')" = "estimator pt pt bpt bpt " ] ||
  fail "converge.csv holds $(cut -d, -f1 converge.csv | tr '\n' ' '), expected the rows of pt and bpt"
say "3. merged reference bit-identical to the one-process reference; converge.csv and converge.png written"
say "ok"
