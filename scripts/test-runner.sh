#!/usr/bin/env bash
# The runner of `make test`'s test binaries (cargo's target runner, set by the Makefile):
# runs each as given, and the binaries that compile many kernel variants and render
# little with each with lavapipe's LLVM optimisation passes off (GALLIVM_PERF=nopt, a
# Mesa option: the same kernels, compiled faster, run about half as fast). There the
# compiler is most of the time; elsewhere the renders are, and the passes stay on.
# docs/kernel-cache.md, "Tests", has the measurements.
set -euo pipefail
case "$(basename "$1")" in
    render_features-* | render_addresses-* | render_reads-*) export GALLIVM_PERF=nopt ;;
esac
exec "$@"
