#!/usr/bin/env bash
# Installs SwiftShader, Google's CPU Vulkan implementation, into a fixed folder
# (default /opt/vkvcm/swiftshader; SWIFTSHADER_DIR overrides), for the second set of
# tests that `make test` runs on a device with other limits than lavapipe's (no
# shaderInt64, no 64-bit atomics, 65536 texels per texel buffer, subgroups of 4;
# docs/devices.md). Debian 12 packages it only inside chromium-common, so the package is
# downloaded (not installed: nothing of Chromium is configured) and the ICD's two files
# are taken out of it. Idempotent: does nothing when the ICD is already there. As root.
set -euo pipefail

dir=${SWIFTSHADER_DIR:-/opt/vkvcm/swiftshader}
icd=$dir/vk_swiftshader_icd.json
if [ -f "$icd" ] && [ -f "$dir/libvk_swiftshader.so" ]; then
  echo "install-swiftshader.sh: SwiftShader already in $dir"
  exit 0
fi

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# apt downloads as the user _apt where it can write (else it warns and runs as root).
chown _apt "$tmp" 2>/dev/null || true
cd "$tmp"
# apt-get download needs the package lists; update them only when the package is unknown.
apt-cache show chromium-common >/dev/null 2>&1 || apt-get update -q
apt-get download chromium-common >/dev/null
dpkg -x chromium-common_*.deb root
src=root/usr/lib/chromium
[ -f "$src/libvk_swiftshader.so" ] && [ -f "$src/vk_swiftshader_icd.json" ] || {
  echo "install-swiftshader.sh: chromium-common holds no SwiftShader ICD" >&2
  exit 1
}
mkdir -p "$dir"
cp "$src/libvk_swiftshader.so" "$src/vk_swiftshader_icd.json" "$dir/"
echo "install-swiftshader.sh: SwiftShader ($(dpkg-deb -f chromium-common_*.deb Version)) in $dir"
