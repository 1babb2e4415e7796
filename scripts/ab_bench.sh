#!/bin/bash
# Interleaved A/B(/C...) runs of `vkvcm-bench render` for comparing kernel variants on a
# shared machine, whose speed drifts between runs: interleaved rounds share the drift
# (docs/performance.md, "How to read these figures"). Each variant is
#   NAME:GLSL_DIR:VKVCM_BENCH_BINARY[:ENV=VALUE|:--OPTION=VALUE ...]
# (GLSL_DIR is passed as VKVCM_GLSL_DIR: the shaders are compiled at run time; --OPTION
# items are passed to `vkvcm-bench render`, e.g. :--paths-per-invocation=1). Every round
# runs each variant once, in an order rotated per round so that no variant always runs
# first; prints "NAME ROUND ALGO SAMPLES_PER_CPU_SECOND" lines for scripts/ab_summary.py.
#
# Usage: scripts/ab_bench.sh ROUNDS ALGOS SCENE VARIANT...
#   e.g. git worktree/commit A's vkvcm-bench copied to /tmp/vkvcm-bench_a, its glsl/ to
#   /tmp/glsl_a, ...
#   scripts/ab_bench.sh 3 pt,bpt,vcm gbs_s a:/tmp/glsl_a:/tmp/vkvcm-bench_a b:/tmp/glsl_b:/tmp/vkvcm-bench_a > ab.txt
#   python3 scripts/ab_summary.py ab.txt a
# Environment: SIZE (default 256), ITERATIONS (default 8).
set -euo pipefail
if [ $# -lt 4 ]; then
    sed -n '2,16p' "$0"
    exit 2
fi
rounds=$1
algos=$2
scene=$3
shift 3
variants=("$@")
n=${#variants[@]}
# vkvcm-bench render names a glTF scene by its file stem.
label=$(basename "$scene")
label=${label%.gltf}
label=${label%.glb}
run() {
    local name dir bin extra item
    local envs=() opts=()
    IFS=: read -r name dir bin extra <<< "$1"
    IFS=: read -r -a items <<< "$extra"
    for item in "${items[@]}"; do
        case "$item" in
            --*) opts+=("$item") ;;
            ?*) envs+=("$item") ;;
        esac
    done
    env VKVCM_GLSL_DIR="$dir" "${envs[@]}" "$bin" render --size "${SIZE:-256}" \
        --iterations "${ITERATIONS:-8}" --scenes "$scene" --algos "$algos" "${opts[@]}" 2>/dev/null |
        awk -F'|' -v name="$name" -v round="$2" -v scene="$label" \
            '{ s = $2; a = $3; x = $9; gsub(/ /, "", s); gsub(/ /, "", a); gsub(/ /, "", x);
               if (s == scene) print name, round, a, x }'
}
for r in $(seq 1 "$rounds"); do
    for i in $(seq 0 $((n - 1))); do
        run "${variants[$(((i + r) % n))]}" "$r"
    done
done
