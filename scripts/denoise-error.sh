#!/usr/bin/env bash
# The relative MSE against a long render of noisy pt renders and of the same renders
# denoised by `vkvcm denoise` (OIDN, guided by the albedo and normal AOVs), at a few
# iteration counts (docs/denoising.md). Needs OIDN (scripts/setup-oidn.sh).
#
#   scripts/denoise-error.sh VKVCM [OUT_DIR]
#
# SCENES (default: glm_c, gbs_s and tests/khronos/BoxTextured.gltf), SIZE (128x96),
# ITERATIONS (4 16 64) and REF_ITERATIONS (1024) override the defaults. Prints one line
# per scene and count: scene, iterations, relMSE noisy, relMSE denoised (colour alone),
# relMSE denoised (albedo + normal).
set -euo pipefail
vkvcm=$(realpath "${1:?usage: scripts/denoise-error.sh VKVCM [OUT_DIR]}")
out=${2:-$(mktemp -d)}
root=$(cd "$(dirname "$0")/.." && pwd)
scenes=${SCENES:-"glm_c gbs_s $root/tests/khronos/BoxTextured.gltf"}
size=${SIZE:-128x96}
counts=${ITERATIONS:-"4 16 64"}
ref_iterations=${REF_ITERATIONS:-1024}
frame=(--width "${size%x*}" --height "${size#*x}" --algo pt -q)
rel_mse() { "$vkvcm" diff "$1" "$2" | awk '$1 == "rel_mse" { print $2 }'; }
mkdir -p "$out"
echo "scene iterations noisy denoised_colour_only denoised_albedo_normal"
for scene in $scenes; do
  name=$(basename "$scene" .gltf)
  "$vkvcm" render "$scene" "${frame[@]}" --seed 99 -i "$ref_iterations" -o "$out/$name-ref.exr"
  for n in $counts; do
    noisy="$out/$name-$n.exr"
    "$vkvcm" render "$scene" "${frame[@]}" -i "$n" --aov albedo,normal -o "$noisy"
    "$vkvcm" denoise "$noisy" --no-aux -o "$out/$name-$n-colour.exr" > /dev/null
    "$vkvcm" denoise "$noisy" -o "$out/$name-$n-aux.exr" > /dev/null
    echo "$name $n $(rel_mse "$noisy" "$out/$name-ref.exr") $(rel_mse "$out/$name-$n-colour.exr" "$out/$name-ref.exr") $(rel_mse "$out/$name-$n-aux.exr" "$out/$name-ref.exr")"
  done
done
