#!/usr/bin/env bash
# Fuzzes the glTF importer with cargo-fuzz for a bounded time (not run by CI; CI runs the
# stable mutation test tests/scene_malformed.rs). Usage: scripts/fuzz.sh [SECONDS=60]
# Installs the nightly toolchain and cargo-fuzz when missing. Seeds: tests/malformed/.
# Crashing inputs land in fuzz/artifacts/gltf_load/.
set -euo pipefail
seconds="${1:-60}"
cd "$(dirname "$0")/.."
rustup toolchain list | grep -q '^nightly' || rustup toolchain install nightly --profile minimal
cargo +nightly fuzz --version >/dev/null 2>&1 || cargo install cargo-fuzz --locked
corpus=fuzz/corpus/gltf_load
mkdir -p "$corpus"
cp tests/malformed/*.gltf tests/malformed/*.glb scenes/*.gltf "$corpus"/
cargo +nightly fuzz run gltf_load "$corpus" -- -max_total_time="$seconds" -max_len=65536 -rss_limit_mb=2048
