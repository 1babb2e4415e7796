#!/usr/bin/env bash
# The tests `make test` runs on SwiftShader (scripts/install-swiftshader.sh) beside the
# whole suite on lavapipe: a second Vulkan implementation with other limits (no
# shaderInt64 or 64-bit atomics, 65536 texels per texel buffer, subgroups of 4). The set
# covers, at the sizes of the lavapipe tests (seconds measured on SwiftShader on the
# project's 2-core machine, shared, 2026-12-06; docs/devices.md says why these):
#   every estimator, both read paths    render_reads (bit-identical storage vs texel)   124
#   splats with 32-bit atomics          render_atomics (64-bit parts skipped)            20
#   kernels needing missing features    device_features                                   1
#   reads chosen per texel limit, and   render_texel_limit (incl. a store grown past     39
#   the light-vertex store's growth     the limit), second_device (the real limit)
#   the compute basics, subgroups of 4  gpu_core, hash_grid                              25
#   the environment map                 render_environment (one filtered test)           43
#   lavapipe and SwiftShader agree,     second_device (both ICDs, per-pixel z-tests:     37
#   textures included                   vcm on gbs_b; pt on the textured glTF asset
#                                       tests/khronos/BoxTextured.gltf)
#   one render on both devices          render_devices (--devices, a per-pixel z-test)   17
# How the set was chosen: each fallback SwiftShader takes (32-bit splats, storage reads past
# its texel limit, no 64-bit kernels) and each kind of kernel (every estimator's passes, the
# compute primitives, textures, the environment map) runs once, at the lavapipe tests'
# sizes, with the test that costs least for it. Textures come from the cheapest such test:
# one 16x16 pt render of a textured glTF asset per device in second_device (which checks
# it against lavapipe, where render_textures checks textures against a CPU sampler);
# render_textures itself is left out for its cost on SwiftShader (one test alone > 1 min).
# The textured case made second_device's z-test 36 s instead of 19 (load 16, 2026-12-06).
# Tests needing what SwiftShader lacks print `skipped: ...`; they are counted at the end.
# Environment as `make test` sets it: VKVCM_TEST_KERNEL_CACHE; LVP_ICD and
# SWIFTSHADER_ICD override the ICD files.
set -euo pipefail
cd "$(dirname "$0")/.."
lvp=${LVP_ICD:-$(ls /usr/share/vulkan/icd.d/lvp_icd*.json | head -n1)}
ss=${SWIFTSHADER_ICD:-/opt/vkvcm/swiftshader/vk_swiftshader_icd.json}
[ -f "$ss" ] || { echo "test-swiftshader.sh: no SwiftShader at $ss (scripts/install-swiftshader.sh)" >&2; exit 1; }
skips=$(mktemp)
trap 'rm -f "$skips"' EXIT
export VKVCM_TEST_DEVICE=SwiftShader VKVCM_TEST_SKIP_LOG=$skips

mkdir -p target
log=target/test-swiftshader.log
: > "$log"
run() { # ICD files, then cargo test's arguments; a failure ends with its tests' panics
  local icds=$1
  shift
  VK_DRIVER_FILES=$icds VK_ICD_FILENAMES=$icds cargo test -q --workspace --features vkvcm/fault-injection "$@" \
    2>&1 | tee -a "$log" || { bash scripts/test-failures.sh "$log"; exit 1; }
}
start=$(date +%s)
run "$ss" --test render_reads --test render_atomics --test device_features --test render_texel_limit \
  --test gpu_core --test hash_grid -- --test-threads=2
run "$ss" --test render_environment -- --test-threads=2 --exact constant_map_renders_the_constant_background
# Both implementations in one process: the cross-check picks each by name.
run "$ss:$lvp" --test second_device --test render_devices -- --test-threads=2 --skip identical_devices
n=$(wc -l < "$skips")
echo "test-swiftshader.sh: passed in $(( $(date +%s) - start )) s; $n test(s) or parts skipped for what the device lacks:"
sed 's/^/  /' "$skips"
