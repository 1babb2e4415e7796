#!/usr/bin/env bash
# Renders every estimator (and the connection and kernel variants) on the four reference
# scenes and the hard cases at fixed seeds with two vkvcm binaries, and checks that every
# pair of images is bit-identical in every channel (`vkvcm diff --exact`). For changes that
# must not change any image (refactoring, scheduling, memory layout).
#
#   scripts/bit-identical.sh OLD_VKVCM NEW_VKVCM [OUT_DIR]
#
# OLD_VKVCM is typically a release build of the commit before the change:
#   git worktree add /tmp/vkvcm-old <commit> &&
#   cargo build --release --manifest-path /tmp/vkvcm-old/Cargo.toml --target-dir target/old
#   scripts/bit-identical.sh target/old/release/vkvcm target/release/vkvcm
# Runs on lavapipe unless VK_DRIVER_FILES says otherwise. SIZE, ITERATIONS and SEED
# override the frame (default 24x24, 2 iterations, seed 7: a few minutes in all), SCENES
# the scene list (default: the four reference scenes and scenes/hard/*.gltf).
set -euo pipefail
old=${1:?usage: scripts/bit-identical.sh OLD_VKVCM NEW_VKVCM [OUT_DIR]}
new=${2:?usage: scripts/bit-identical.sh OLD_VKVCM NEW_VKVCM [OUT_DIR]}
out=${3:-$(mktemp -d)}
size=${SIZE:-24}
iterations=${ITERATIONS:-2}
seed=${SEED:-7}
root=$(cd "$(dirname "$0")/.." && pwd)
if [ -z "${VK_DRIVER_FILES:-}" ]; then
  lvp=$(ls /usr/share/vulkan/icd.d/lvp_icd*.json 2>/dev/null | head -n1 || true)
  [ -n "$lvp" ] && export VK_DRIVER_FILES=$lvp
fi
mkdir -p "$out"

scenes=${SCENES:-}
if [ -z "$scenes" ]; then
  scenes="gbs_s glm_c gbs_p gbs_b"
  for f in "$root"/scenes/hard/*.gltf; do scenes="$scenes $f"; done
fi
# Each variant: a name and the render flags.
variants=(
  "el|--algo el"
  "pt|--algo pt"
  "pt-generic|--algo pt --generic"
  "lt|--algo lt"
  "bpt|--algo bpt"
  "bpt-path|--algo bpt --connect path"
  "ppm|--algo ppm"
  "bpm|--algo bpm"
  "vcm|--algo vcm"
  "vcm-path|--algo vcm --connect path"
  "vcm-cache2|--algo vcm --connect cache --cache-connections 2"
  "vcm-storage|--algo vcm --reads storage --paths-per-invocation 3"
)

n=0
failed=0
for scene in $scenes; do
  tag=$(basename "$scene" .gltf)
  for v in "${variants[@]}"; do
    name=${v%%|*}
    flags=${v#*|}
    n=$((n + 1))
    for which in old new; do
      bin=$old
      [ "$which" = new ] && bin=$new
      # shellcheck disable=SC2086
      "$bin" render "$scene" $flags --width "$size" --height "$size" --iterations "$iterations" \
        --seed "$seed" -o "$out/${tag}_${name}_$which.exr" >"$out/${tag}_${name}_$which.log" 2>&1 ||
        { echo "FAIL $tag $name: the $which binary failed (see $out/${tag}_${name}_$which.log)"; failed=$((failed + 1)); continue 2; }
    done
    if "$new" diff --exact "$out/${tag}_${name}_old.exr" "$out/${tag}_${name}_new.exr" >/dev/null 2>"$out/${tag}_${name}.diff"; then
      echo "same $tag $name"
    else
      echo "DIFF $tag $name: $(cat "$out/${tag}_${name}.diff")"
      failed=$((failed + 1))
    fi
  done
done
echo "$((n - failed)) passed, $failed failed"
[ "$failed" = 0 ]
