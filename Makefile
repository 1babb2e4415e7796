# vkvcm: the two set-up commands of README.md.
#   make render  - install what is missing (Debian 12, as root), build, render the default scene
#   make test    - install what is missing, build, run the whole test suite (validation on)
#                  on lavapipe, a set on SwiftShader, gpu-check --quick, and the Slurm test
#   make gpu-check - on a machine with a GPU: devices, the statistical tests, a benchmark
#                  matrix at 1920x1080 (scripts/gpu-check.sh; about ten minutes)
# Tests run on lavapipe unless VKVCM_TEST_DEVICE names another device.

SHELL := /bin/bash

LVP_ICD := $(firstword $(wildcard /usr/share/vulkan/icd.d/lvp_icd.x86_64.json /usr/share/vulkan/icd.d/lvp_icd.json))

.PHONY: setup build render test test-swiftshader gpu-check clippy fmt

setup:
	bash scripts/setup-debian.sh

build: setup
	cargo build --release

render: build
	mkdir -p out
	./target/release/vkvcm render --width 512 --height 512 --iterations 16 -o out/default.exr --png out/default.png

# Tests force lavapipe so results do not depend on the machine's GPU. The suite shares a
# kernel cache of its own, emptied first, so each kernel variant is compiled once per run
# (GpuOptions::for_tests). It covers the workspace (the renderer and tools/) with the
# fault-injection feature, which the tests of device loss and device limits need, and runs
# every test binary even after a failure, so that one CI run names every failing test.
# Without incremental compilation (here and in the SwiftShader set, which reuses the build):
# a fresh clone builds once, and its incremental state (3.5 GB) would only fill the disk.
# Test binaries run through scripts/test-runner.sh, which compiles the kernels of the few
# that build many variants and render little with each without LLVM's optimisation passes
# (docs/kernel-cache.md, "Tests"). When a test fails, scripts/test-failures.sh prints each
# failed test and its panic last (from target/test-lavapipe.log, the whole output), so that
# the end of a CI log names them.
TEST_KERNEL_CACHE := $(CURDIR)/target/test-kernel-cache
TEST_RUNNER := --config "target.'cfg(all())'.runner='$(CURDIR)/scripts/test-runner.sh'"
test test-swiftshader: export CARGO_INCREMENTAL := 0

#
# Then a set of the tests on SwiftShader, a second Vulkan implementation with other limits
# (scripts/test-swiftshader.sh says which and why), and the GPU check's quick mode on
# lavapipe with the binary the tests built, so that it cannot rot; last, with that binary,
# the Slurm job array and merge of docs/distributed.md on a one-node Slurm cluster
# (scripts/test-slurm.sh).
test: setup
	bash scripts/setup-oidn.sh
	rm -rf $(TEST_KERNEL_CACHE)
	mkdir -p target
	set -o pipefail; VK_DRIVER_FILES=$(LVP_ICD) VK_ICD_FILENAMES=$(LVP_ICD) VKVCM_TEST_KERNEL_CACHE=$(TEST_KERNEL_CACHE) \
		cargo test $(TEST_RUNNER) --workspace --features vkvcm/fault-injection --no-fail-fast -- --test-threads=2 \
		2>&1 | tee target/test-lavapipe.log || { bash scripts/test-failures.sh target/test-lavapipe.log; exit 1; }
	$(MAKE) --no-print-directory test-swiftshader
	rm -rf target/gpu-check-quick
	VK_DRIVER_FILES=$(LVP_ICD) VK_ICD_FILENAMES=$(LVP_ICD) VKVCM=target/debug/vkvcm VKVCM_CACHE_DIR=$(TEST_KERNEL_CACHE) \
		bash scripts/gpu-check.sh --quick target/gpu-check-quick
	VK_DRIVER_FILES=$(LVP_ICD) VK_ICD_FILENAMES=$(LVP_ICD) VKVCM=target/debug/vkvcm VKVCM_CACHE_DIR=$(TEST_KERNEL_CACHE) \
		bash scripts/test-slurm.sh

test-swiftshader:
	LVP_ICD=$(LVP_ICD) VKVCM_TEST_KERNEL_CACHE=$(TEST_KERNEL_CACHE) bash scripts/test-swiftshader.sh

gpu-check:
	bash scripts/gpu-check.sh

clippy:
	cargo clippy --workspace --all-targets -- -D warnings
	cargo clippy --workspace --all-targets --all-features -- -D warnings

fmt:
	cargo fmt --check
