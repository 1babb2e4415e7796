#!/usr/bin/env bash
# Cost against resolution: whole-process CPU seconds of `vkvcm render` at a large frame
# and at 256x256 with about the same number of samples (pixels x iterations), and
# samples per CPU-second of each. Charges the whole process (start-up, kernel builds,
# film read-back and EXR writing included), measured by /usr/bin/time.
#   scripts/resolution_scaling.sh [BINARY]      (default target/release/vkvcm)
# vcm also with 65,536 light subpaths per iteration (--light-paths), the count of 256x256.
# Prints one row per estimator and frame; run on an idle machine.
set -euo pipefail
bin=${1:-target/release/vkvcm}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
run() {  # algo width height iterations [light paths per iteration]
    local t=$out/time
    local extra=()
    [ $# -ge 5 ] && extra=(--light-paths "$5")
    /usr/bin/time -f "%U %S %M" -o "$t" "$bin" render gbs_s -a "$1" --width "$2" --height "$3" -i "$4" \
        "${extra[@]}" -o "$out/img.exr" >/dev/null 2>&1
    read -r user sys rss <"$t"
    python3 - "$1" "$2" "$3" "$4" "${5:-$(($2 * $3))}" "$user" "$sys" "$rss" <<'PY'
import sys
algo, w, h, it, n_l, user, sys_, rss = sys.argv[1:]
cpu = float(user) + float(sys_)
samples = int(w) * int(h) * int(it)
n_l = "" if algo == "pt" else n_l
print(f"| {algo} | {w}x{h} | {n_l} | {it} | {samples / 1e6:.2f} M | {cpu:.1f} | {samples / cpu / 1e3:.0f} k | {int(rss) / 1024:.0f} MiB |")
PY
}
echo "| estimator | frame | light paths / iteration | iterations | samples | CPU s | samples / CPU-s | peak RSS |"
echo "|---|---|---|---|---|---|---|---|"
run pt 3840 2160 2
run pt 256 256 253
run vcm 1920 1080 2
run vcm 1920 1080 2 65536
run vcm 3840 2160 1 65536
run vcm 256 256 63
