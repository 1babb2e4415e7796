#!/usr/bin/env bash
# Installs Intel Open Image Denoise for `vkvcm denoise` (docs/denoising.md): the `pyoidn`
# wheel from PyPI ships the OIDN library with its command-line program oidnDenoise, which
# vkvcm runs; Debian 12 packages no OIDN, and the `oidn` crate needs the library installed.
# Installed without its Python dependencies (only the program is used) into
# /opt/vkvcm/pyoidn, where vkvcm looks for it (or set VKVCM_OIDN_DENOISE). About 90 MB to
# download, 180 MB installed. `make test` runs it (tests/cli_denoise.rs denoises a render);
# a second run installs nothing.
set -euo pipefail
prefix=${OIDN_PREFIX:-/opt/vkvcm/pyoidn}
version=2.5.1.0
if [ ! -x "$prefix/pyoidn/oidn/bin/oidnDenoise" ]; then
  python3 -m pip install --quiet --no-deps --target "$prefix" "pyoidn==$version"
fi
"$prefix/pyoidn/oidn/bin/oidnDenoise" --list_devices
echo "oidnDenoise: $prefix/pyoidn/oidn/bin/oidnDenoise"
