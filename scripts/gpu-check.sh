#!/usr/bin/env bash
# A GPU run ready to go (`make gpu-check`): on a machine with a GPU, in about ten
# minutes, lists the Vulkan devices, runs the statistical tests that matter on the GPU,
# and renders the benchmark matrix: every estimator at 1920x1080 on the four reference
# scenes and one textured glTF asset (tests/khronos/BoxTextured.gltf, white sky), each
# for 4 s of wall-clock time after its set-up. Writes one folder:
#   devices.txt        `vkvcm devices`
#   tests.log          the tests' output (their pass/fail is in the summary)
#   json/SCENE-ALGO.json  `--profile-json`: samples/s, rays/s, GPU ms per iteration,
#                      per stage and per kernel, paths per invocation, reads
#   logs/SCENE-ALGO.log   `--verbose`: the choices made and every buffer's size
#   summary.md         one table of the matrix and the tests' result
#
#   scripts/gpu-check.sh [--quick] [OUT_DIR]     (default OUT_DIR: gpu-check-DATE)
#
# --quick: 32x24 pixels, 2 iterations, gbs_s and the glTF asset only, one small test
# binary (gpu_core): runs on lavapipe (190 s measured on the shared, loaded 2-core machine;
# the aim is a minute, not yet reached), so
# `make test` runs it and the script cannot rot.
# Environment: VKVCM (the binary; default: a release build, built first; --quick:
# target/debug/vkvcm as `make test` built it), DEVICE (a device index or name for the
# renders and VKVCM_TEST_DEVICE; default: vkvcm's own choice, a GPU before a CPU),
# SECONDS_PER_RENDER (4), TEST_TIMEOUT (300 s).
set -euo pipefail
cd "$(dirname "$0")/.."
quick=0
if [ "${1:-}" = "--quick" ]; then quick=1; shift; fi
out=${1:-gpu-check-$(date -u +%Y%m%d-%H%M%S)}
mkdir -p "$out/json" "$out/logs" "$out/renders"
out=$(cd "$out" && pwd) # absolute: the tests' kernel cache lies in it
started=$(date +%s)

features=(--workspace --features vkvcm/fault-injection)
if [ "$quick" = 1 ]; then
  vkvcm=${VKVCM:-target/debug/vkvcm}
  size=(--width 32 --height 24) budget=(-i 2) tests=(--test gpu_core)
else
  if [ -z "${VKVCM:-}" ]; then cargo build --release -q; fi
  vkvcm=${VKVCM:-target/release/vkvcm}
  size=(--width 1920 --height 1080) budget=(-t "${SECONDS_PER_RENDER:-4}")
  # The statistical tests: estimators against each other and Mitsuba, the read and
  # splat paths, the texel limits, and the device's own cross-check with lavapipe
  # where both are there.
  tests=(--test render_pt --test render_bidir --test render_vcm --test render_lvc --test render_reads
    --test render_atomics --test render_texel_limit --test render_textures --test render_environment
    --test second_device)
fi
[ -x "$vkvcm" ] || { echo "gpu-check.sh: no vkvcm binary at $vkvcm" >&2; exit 1; }
device=()
if [ -n "${DEVICE:-}" ]; then device=(--device "$DEVICE"); export VKVCM_TEST_DEVICE=$DEVICE; fi

"$vkvcm" devices > "$out/devices.txt" 2>&1
chosen=$(grep -m1 -E '^[0-9]+:' "$out/devices.txt" || true)

# Tests: their own kernel cache in the folder, so that nothing of an earlier run is used.
echo "gpu-check.sh: tests ($(printf '%s ' "${tests[@]}"))"
if VKVCM_TEST_KERNEL_CACHE=$out/test-kernel-cache timeout "${TEST_TIMEOUT:-300}" \
  cargo test -q "${features[@]}" "${tests[@]}" -- --test-threads=2 > "$out/tests.log" 2>&1; then
  tests_result="passed"
else
  tests_result="FAILED (exit $?; see tests.log)"
fi
rm -rf "$out/test-kernel-cache"

# A number from the pretty-printed profile JSON (one key per line).
field() {
  local v
  v=$(sed -n "s/^ *\"$2\": *\\([0-9.eE+-]*\\),*$/\\1/p" "$1" | head -n1)
  echo "${v:-nan}"
}
text() { sed -n "s/^ *\"$2\": *\"\\([^\"]*\\)\",*$/\\1/p" "$1" | head -n1; }
# Device memory in vkvcm's buffers when the render starts (the plan's total, --verbose);
# a light-vertex store grown later adds to it (its final capacity is in the log).
buffers_mib() { awk '$1 == "total" {print $2; exit}' "$1"; }

{
  echo "# gpu-check $(date -u +%Y-%m-%dT%H:%MZ)"
  echo
  echo "- device: ${chosen:-?} (all devices: devices.txt)"
  echo "- vkvcm: $(git rev-parse --short HEAD 2>/dev/null || echo '?'), $vkvcm"
  echo "- tests: $tests_result"
  echo "- frame: ${size[*]}, budget ${budget[*]} per render (after set-up)"
  echo
  echo "| scene | estimator | samples/s | rays/s | GPU ms / iteration | buffers MiB | reads | paths / invocation | iterations |"
  echo "|---|---|---:|---:|---:|---:|---|---:|---:|"
} > "$out/summary.md"

failed=0
scenes=(gbs_s glm_c gbs_p gbs_b tests/khronos/BoxTextured.gltf)
# Quick: one reference scene and the glTF asset, enough to run every step of the script.
if [ "$quick" = 1 ]; then scenes=(gbs_s tests/khronos/BoxTextured.gltf); fi
for scene in "${scenes[@]}"; do
  stem=$(basename "$scene" .gltf)
  for algo in el pt lt bpt ppm bpm vcm; do
    json=$out/json/$stem-$algo.json log=$out/logs/$stem-$algo.log
    if "$vkvcm" render "$scene" -a "$algo" "${size[@]}" "${budget[@]}" "${device[@]}" --verbose \
      -o "$out/renders/$stem-$algo.exr" --profile-json "$json" > "$log" 2>&1; then
      printf '| %s | %s | %.4g | %.4g | %.4g | %s | %s | %s | %s |\n' "$stem" "$algo" \
        "$(field "$json" samples_per_second)" "$(field "$json" rays_per_second)" \
        "$(field "$json" gpu_ms_per_iteration)" "$(buffers_mib "$log")" "$(text "$json" reads)" \
        "$(field "$json" paths_per_invocation)" "$(field "$json" iterations)" >> "$out/summary.md"
    else
      failed=$((failed + 1))
      echo "| $stem | $algo | failed: $(tail -n1 "$log" | tr '|' '/') | | | | | | |" >> "$out/summary.md"
    fi
  done
done
rm -rf "$out/renders"
{
  echo
  echo "Per stage and per kernel: json/. Choices and buffer sizes: logs/. $failed render(s) failed;"
  echo "$(( $(date +%s) - started )) s in all."
} >> "$out/summary.md"
echo "gpu-check.sh: wrote $out/summary.md ($failed render(s) failed, tests $tests_result)"
[ "$failed" = 0 ] && [ "$tests_result" = passed ]
