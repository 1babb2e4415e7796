#!/usr/bin/env bash
# The Slurm path of docs/distributed.md ("Slurm"), on a real one-node Slurm cluster started on
# this machine (scripts/slurm/local-cluster.sh; as root, with slurm-wlm and munge installed).
#   1. Submits the job array and the merge job with the very command lines of
#      docs/distributed.md (read from it), waits, and checks that the merged image is bit for
#      bit the same render done in one process.
#   2. Submits them again, kills one array task with SIGKILL in the middle of its render, and
#      checks that no file the merge accepts is left for that shard, that the merge job waits
#      (DependencyNeverSatisfied), and that running the task again as the doc says completes the
#      set: the merge then runs and is again bit-identical to the one-process render.
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

# A progress line, with the seconds since the start.
say() {
  echo "test-slurm.sh: [$(($(date +%s) - start)) s] $*"
}

fail() {
  echo "test-slurm.sh: FAIL: $*" >&2
  for f in "$work"/*.out "$work"/kill/*.out; do
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

# The field $2 (JobState, ExitCode, Reason) of job $1 (a job id or ARRAYID_TASK).
job_field() {
  scontrol -o show job "$1" | tr ' ' '\n' | sed -n "s/^$2=//p" | head -n1
}

# Waits up to $2 seconds for job $1 to end; fails unless it ended in state $3.
wait_job() {
  local id=$1 timeout=$2 want=$3 state
  for _ in $(seq $((timeout * 10))); do
    state=$(job_field "$id" JobState)
    case "$state" in
      PENDING | RUNNING | CONFIGURING | COMPLETING | "") sleep 0.1 ;;
      *) break ;;
    esac
  done
  [ "$state" = "$want" ] || fail "job $id: state $state after up to $timeout s, expected $want"
}

export VK_DRIVER_FILES=${VK_DRIVER_FILES:-/usr/share/vulkan/icd.d/lvp_icd.json}
export VK_ICD_FILENAMES=${VK_ICD_FILENAMES:-$VK_DRIVER_FILES}
eval "$(bash "$root/scripts/slurm/local-cluster.sh" start "$work/cluster")"
say "one-node cluster up ($(sinfo -h -N -o '%N, %c CPUs'))"

# The render: tiny, and vcm (the default), whose merge radius follows the global iteration
# index. 64 iterations per shard, so that a shard renders long enough (about a second
# here) to be killed in the middle.
repo=$root
n=3
render=(gbs_s --width 32 --height 32 --iterations 192 --seed 7)
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

# 2. The same, with array task 1 killed (SIGKILL) in the middle of its render.
mkdir kill
cd kill
eval "$submit_array"
eval "$submit_merge"
killed=${array}_1
log=vkvcm-shard-${killed}.out
# Its first progress line comes after its first iteration: from then on it is rendering.
for _ in $(seq 600); do
  grep -q '^progress:' "$log" 2>/dev/null && break
  [ "$(job_field "$killed" JobState)" = PENDING ] || [ "$(job_field "$killed" JobState)" = RUNNING ] ||
    fail "task $killed ended before it could be killed"
  sleep 0.05
done
scancel --batch --signal=KILL "$killed"
say "2. array job $array: task 1 killed (SIGKILL) in the middle of its render"
wait_job "$killed" 30 FAILED
[ "$(job_field "$killed" ExitCode)" = 0:9 ] || fail "task $killed: exit $(job_field "$killed" ExitCode), expected 0:9 (SIGKILL)"
grep -q 'wrote' "$log" && fail "task $killed wrote its shard before the kill (render longer)"
wait_job "${array}_0" 60 COMPLETED
wait_job "${array}_2" 60 COMPLETED
for _ in $(seq 50); do
  [ "$(job_field "$merge" Reason)" = DependencyNeverSatisfied ] && break
  sleep 0.1
done
[ "$(job_field "$merge" JobState)/$(job_field "$merge" Reason)" = PENDING/DependencyNeverSatisfied ] ||
  fail "merge job $merge: $(job_field "$merge" JobState)/$(job_field "$merge" Reason), expected PENDING/DependencyNeverSatisfied"
# No file the killed task left is accepted in shard 1's place, under its name or any other.
if "$VKVCM" merge shards/shard-0.exr shards/shard-1.exr shards/shard-2.exr -o refused.exr; then
  fail "a merge accepted the shards of a set whose shard 1 was killed"
fi
for f in shards/*; do
  case "$f" in shards/shard-0.exr | shards/shard-2.exr) continue ;; esac
  if "$VKVCM" merge shards/shard-0.exr "$f" shards/shard-2.exr -o refused.exr; then
    fail "a merge accepted $f, left by the killed task"
  fi
done
[ -e refused.exr ] && fail "a refused merge left refused.exr"
say "2. no file left that a merge accepts; the merge job waits (DependencyNeverSatisfied)"
k=1
eval "$rerun_task"
eval "$update_merge"
wait_job "$merge" 120 COMPLETED
"$VKVCM" diff --exact merged.exr ../one.exr || fail "merged.exr after the re-run differs from the one-process render"
say "2. task 1 run again ($rerun), merged image bit-identical to the one-process render"
say "ok"
