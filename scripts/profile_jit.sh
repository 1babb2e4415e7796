#!/bin/bash
# Where a render's CPU time goes on lavapipe, whose kernels run as JIT-compiled code
# without symbols: samples a running `vkvcm render` with perf, sums the samples per
# shared object and per 4-KiB page of JIT code (a page holds one small function, or a
# part of a kernel's body), and disassembles the hottest page with gdb while the process
# still runs (a small function there is a helper lavapipe calls rather than inlines, e.g.
# its texel-buffer fetch). Needs perf and gdb (apt install linux-perf gdb) and permission
# to attach (root, or kernel.perf_event_paranoid <= 1 and ptrace_scope 0).
#
# Usage: scripts/profile_jit.sh SECONDS VKVCM_RENDER_ARGS...
#   e.g. scripts/profile_jit.sh 4 target/peers/scenes/cornell_mg.gltf -a pt --width 128 --height 128
# Environment: VKVCM (default target/release/vkvcm), WARMUP seconds before sampling
# (default 4: kernel compilation and the first iterations).
set -u
if [ $# -lt 2 ]; then
    sed -n '2,14p' "$0"
    exit 2
fi
seconds=$1
shift
work=$(mktemp -d)
pid=
# The render runs until this script ends, however it ends.
trap '[ -n "$pid" ] && kill "$pid" 2>/dev/null; rm -rf "$work"' EXIT
"${VKVCM:-target/release/vkvcm}" render "$@" --iterations 1000000 -o "$work/out.exr" >"$work/render.log" 2>&1 &
pid=$!
sleep "${WARMUP:-4}"
kill -0 "$pid" 2>/dev/null || { echo "the render ended early:"; cat "$work/render.log"; exit 1; }
perf record -q -o "$work/perf.data" -F 999 -p "$pid" -- sleep "$seconds" >/dev/null 2>&1
echo "## samples per shared object"
perf report -i "$work/perf.data" --sort dso --stdio 2>/dev/null | grep -v '^#' | grep -v '^$' | head -8
echo "## samples per 4-KiB page (top 12)"
perf report -i "$work/perf.data" --sort sym --stdio 2>/dev/null | grep -v '^#' |
    awk 'NF >= 3 && $3 ~ /^0x/ { page = substr($3, 1, length($3) - 3); s[page] += $1 }
         END { for (p in s) printf "%7.2f%% %s000\n", s[p], p }' | sort -rn | head -12 | tee "$work/pages"
hot=$(awk 'NR == 1 { print $2 }' "$work/pages")
echo "## the hottest page, $hot (up to its first ret)"
gdb -p "$pid" -batch -ex "x/120i $hot" 2>/dev/null >"$work/disassembly" || true
grep '^ *0x' "$work/disassembly" | awk '{ print } /\tret/ { exit }'
