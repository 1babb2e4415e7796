#!/usr/bin/env bash
# Scene size on the height-field grids of scripts/make_grid_scene.py: the BVH build time
# (`vkvcm-bench bvh-build`, median of 5, 2 threads), and of one `vkvcm render -a pt`
# (256x256, 32 iterations): the load time when over 1 s (shorter loads print no line),
# device memory (and bytes per triangle), the process's peak host memory and the rays per
# second of GPU time. A size NxK places a grid of N triangles K times (instances of one
# mesh: K x N triangles in the scene, N stored); NxKf renders the same file with
# --flatten-instances (K x N stored; the build column is then blank).
#   scripts/scene_size.sh [TRIANGLES[xINSTANCES[f]]...]   (default 1000000 4500000 10000000)
# Environment: VKVCM (default target/release/vkvcm), VKVCM_BENCH (default
# target/release/vkvcm-bench: cargo build --release -p vkvcm-tools). Run on an idle machine.
set -euo pipefail
bin=${VKVCM:-target/release/vkvcm}
bench_bin=${VKVCM_BENCH:-target/release/vkvcm-bench}
here=$(cd "$(dirname "$0")" && pwd)
sizes=("$@")
[ ${#sizes[@]} -gt 0 ] || sizes=(1000000 4500000 10000000)
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
echo "| triangles | stored (instances) | load s | BVH build s | device MiB | device bytes / triangle | peak RSS MiB | rays / s (GPU time) |"
echo "|---|---|---|---|---|---|---|---|"
for size in "${sizes[@]}"; do
    flatten=()
    case "$size" in *f) flatten=(--flatten-instances); size=${size%f} ;; esac
    n=${size%x*}
    k=1
    [ "$size" = "$n" ] || k=${size#*x}
    python3 "$here/make_grid_scene.py" "$n" "$out/grid.glb" "$k" >/dev/null
    "$bench_bin" bvh-build --scenes "$out/grid.glb" --threads 2 >"$out/build" 2>&1
    /usr/bin/time -f "%M" -o "$out/rss" "$bin" render "$out/grid.glb" -a pt --width 256 --height 256 -i 32 \
        "${flatten[@]}" --verbose --profile -o "$out/img.exr" >"$out/log" 2>&1
    python3 - "$out/log" "$out/rss" "$out/build" "$k" "${#flatten[@]}" <<'PY'
import re, sys
k = int(sys.argv[4])
flattened = sys.argv[5] == "1"
log = open(sys.argv[1]).read()
rss = int(open(sys.argv[2]).read().split()[-1]) / 1024
built = re.search(r"(\d+) triangles, .*median ([\d.]+) s", open(sys.argv[3]).read())
tris, build = int(built.group(1)), float(built.group(2))
took = re.search(r"loading .*: took ([\d.]+) s", log)
load = f"{float(took.group(1)):.1f}" if took else "< 1"
total = float(re.search(r"^\s*total\s+([\d.]+)\s*$", log, re.M).group(1))
rays = re.search(r"rays: .*, ([\d.]+) M/s of GPU time", log).group(1)
stored = f"{tris * k:,} (flattened)" if flattened else f"{tris:,}" + (f" ({k})" if k > 1 else "")
built = "" if flattened else f"{build:.2f}"
print(f"| {tris * k:,} | {stored} | {load} | {built} | {total:.0f} | {total * 2**20 / (tris * k):.1f} | {rss:.0f} | {rays} M |")
PY
done
