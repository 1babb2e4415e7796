#!/usr/bin/env bash
# Installs what vkvcm needs on a fresh Debian 12 (bookworm) machine, as root.
# Idempotent: a second run installs nothing new. SwiftShader, the second Vulkan
# implementation of the tests, is installed by install-swiftshader.sh. See docs/toolchain.md (1, 2) for why
# Mesa comes from bookworm-backports (lavapipe's storage-buffer reads are ~9x faster).
set -euo pipefail

if [ "$(id -u)" -ne 0 ]; then
  echo "setup-debian.sh: must run as root (apt-get install)" >&2
  exit 1
fi

export DEBIAN_FRONTEND=noninteractive
src=/etc/apt/sources.list.d/debian.sources
bp=/etc/apt/sources.list.d/vkvcm-backports.sources

if ! grep -rqs 'bookworm-backports' /etc/apt/sources.list.d/ /etc/apt/sources.list 2>/dev/null; then
  # Same URI and key as the machine's existing bookworm entry (read, not hard-coded).
  uri=$(awk '/^URIs:/{u=$2} /^Suites:/ && / bookworm( |$)/{print u; exit}' "$src" 2>/dev/null || true)
  key=$(awk '/^Signed-By:/{print $2; exit}' "$src" 2>/dev/null || true)
  if [ -z "$uri" ]; then
    uri=$(grep -hoE '^deb +[^ ]+' /etc/apt/sources.list 2>/dev/null | awk '{print $2; exit}')
  fi
  [ -n "$uri" ] || { echo "setup-debian.sh: cannot find the bookworm apt URI" >&2; exit 1; }
  {
    echo "Types: deb"
    echo "URIs: $uri"
    echo "Suites: bookworm-backports"
    echo "Components: main"
    [ -n "$key" ] && echo "Signed-By: $key"
  } > "$bp"
fi

pkgs="libvulkan1 libvulkan-dev vulkan-tools vulkan-validationlayers glslang-tools glslc libshaderc-dev spirv-tools g++"
# slurm-wlm and munge: the one-node Slurm cluster of scripts/test-slurm.sh (docs/distributed.md).
pkgs="$pkgs slurm-wlm munge"
need=0
for p in $pkgs; do dpkg -s "$p" >/dev/null 2>&1 || need=1; done
mesa_ver=$(dpkg-query -W -f='${Version}' mesa-vulkan-drivers 2>/dev/null || true)
case "$mesa_ver" in 25.*) ;; *) need=1 ;; esac

if [ "$need" = 1 ]; then
  apt-get update -q
  apt-get install -y -q --no-install-recommends $pkgs
  apt-get install -y -q --no-install-recommends -t bookworm-backports mesa-vulkan-drivers
fi
# The second Vulkan implementation the tests run on (Makefile, test-swiftshader).
bash "$(dirname "$0")/install-swiftshader.sh"
echo "setup-debian.sh: Vulkan toolchain ready (mesa-vulkan-drivers $(dpkg-query -W -f='${Version}' mesa-vulkan-drivers))"
