#!/bin/bash
# CPU time of a whole `vkvcm render` process (user + sys, the time it takes to start, build
# its kernels, render one 16x16 iteration and write the EXR) with a cold and with a warm
# kernel cache (docs/kernel-cache.md), for pt, bpt and vcm. Prints a markdown table.
#
# Cold: VKVCM_CACHE_DIR and MESA_SHADER_CACHE_DIR (Mesa's own shader cache, which
# lavapipe uses) are new empty folders. Warm: the next run, with the same two folders.
# Mesa only: one more run with --no-kernel-cache and Mesa's cache warm (what vkvcm's
# cache saves on top of Mesa's: shaderc's compiles).
# Each round runs cold then warm for every estimator, rotating which estimator goes
# first, so that a drift in the machine's speed spreads over all of them. The table gives
# the median and the range over the rounds. Run it on an otherwise idle machine.
#
# Usage: scripts/startup_bench.sh [ROUNDS]      (default 5)
# Environment: VKVCM (the binary; default target/release/vkvcm, build it first with
#   cargo build --release), SCENE (default gbs_s), ALGOS (default "pt bpt vcm"),
#   VK_DRIVER_FILES (default: lavapipe where its ICD file exists).
set -euo pipefail
rounds=${1:-5}
root=$(cd "$(dirname "$0")/.." && pwd)
bin=${VKVCM:-$root/target/release/vkvcm}
scene=${SCENE:-gbs_s}
read -r -a algos <<< "${ALGOS:-pt bpt vcm}"
if [ ! -x "$bin" ]; then
    echo "no vkvcm binary at $bin (cargo build --release, or set VKVCM)" >&2
    exit 2
fi
lvp=/usr/share/vulkan/icd.d/lvp_icd.json
if [ -z "${VK_DRIVER_FILES:-}" ] && [ -f "$lvp" ]; then
    export VK_DRIVER_FILES=$lvp
fi
unset VKVCM_VALIDATION VKVCM_GLSL_DIR
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# cpu_seconds DIR ALGO [ARG...]: runs one render with its caches in DIR and the extra
# arguments ARG; prints the process's user+sys seconds (getrusage of the child, from
# Python: no dependency on GNU time).
cpu_seconds() {
    VKVCM_CACHE_DIR="$1/vkvcm" MESA_SHADER_CACHE_DIR="$1/mesa" python3 - "$bin" "$scene" "$1/out.exr" "$@" <<'EOF'
import resource, subprocess, sys
bin, scene, out, _, algo, *extra = sys.argv[1:]
r = subprocess.run([bin, "render", scene, "-a", algo, "--width", "16", "--height", "16",
                    "--iterations", "1", "-o", out, *extra], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
if r.returncode != 0:
    sys.exit("vkvcm failed:\n" + r.stderr.decode(errors="replace"))
u = resource.getrusage(resource.RUSAGE_CHILDREN)
print(f"{u.ru_utime + u.ru_stime:.3f}")
EOF
}

results=$work/results.txt
: > "$results"
n=${#algos[@]}
for ((round = 0; round < rounds; round++)); do
    for ((i = 0; i < n; i++)); do
        algo=${algos[$(((i + round) % n))]}
        dir=$work/r$round-$algo
        mkdir -p "$dir"
        echo "$algo cold $(cpu_seconds "$dir" "$algo")" >> "$results"
        echo "$algo warm $(cpu_seconds "$dir" "$algo")" >> "$results"
        echo "$algo mesa $(cpu_seconds "$dir" "$algo" --no-kernel-cache)" >> "$results"
        rm -rf "$dir"
    done
    echo "round $((round + 1))/$rounds done" >&2
done

commit=$(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown)
if ! git -C "$root" diff --quiet HEAD 2>/dev/null; then
    commit="$commit (with uncommitted changes)"
fi
# The devices' summary lines of `vkvcm devices` ("0: NAME (TYPE), driver ..., Vulkan ...").
device=$("$bin" devices 2>/dev/null | grep -E '^[0-9]+: ' | paste -sd ';' - || true)
mesa=$(dpkg-query -W -f '${Version}' mesa-vulkan-drivers 2>/dev/null ||
    grep -o 'Mesa [0-9][^ )]*' <<< "$device" | head -n 1 || true)
echo "Start-up CPU time (user + sys) of \`vkvcm render $scene --width 16 --height 16 --iterations 1\`"
echo
echo "- date: $(date -u '+%Y-%m-%d %H:%M UTC')"
echo "- commit: $commit"
echo "- binary: $bin"
echo "- device: ${device:-unknown}"
echo "- Mesa: ${mesa:-unknown}"
echo "- rounds: $rounds (cold: empty vkvcm and Mesa caches; warm: the next run, with them;"
echo "  Mesa only: --no-kernel-cache, Mesa's cache warm)"
echo
python3 - "$results" "${algos[@]}" <<'EOF'
import statistics, sys
path, algos = sys.argv[1], sys.argv[2:]
runs = {}
for line in open(path):
    algo, kind, secs = line.split()
    runs.setdefault((algo, kind), []).append(float(secs))
def cell(xs):
    return f"{statistics.median(xs):.2f} ({min(xs):.2f}-{max(xs):.2f})"
print("| estimator | cold CPU s (median, range) | warm CPU s | Mesa only CPU s | warm / cold |")
print("|---|---|---|---|---|")
for a in algos:
    cold, warm, mesa = (runs[(a, kind)] for kind in ("cold", "warm", "mesa"))
    ratio = statistics.median(warm) / statistics.median(cold)
    print(f"| {a} | {cell(cold)} | {cell(warm)} | {cell(mesa)} | {ratio:.2f} |")
EOF
