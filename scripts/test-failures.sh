#!/usr/bin/env bash
# Usage: test-failures.sh LOG
# Prints, from the output of `cargo test` in LOG, each failed test with the first lines of
# its panic, and each test binary that did not exit (a crash, a signal). `make test` runs
# it last when a test step fails, so that the end of a CI log, often all that is kept of
# it, names what failed and why; cargo itself lists failures in the middle of the output.
set -euo pipefail
log=${1:?usage: test-failures.sh LOG}
echo "== failed tests (from $log) =="
awk '
    /^     Running / { binary = $2 }
    # A failed test: cargo prints "---- NAME stdout ----" and its captured output.
    /^---- .* stdout ----$/ { name = $2; shown = 0; printing = 1; print (binary ? binary ": " : "") name; next }
    printing && (/^failures:$/ || /^---- / || /^[Ss]tack backtrace:$/) { printing = 0 }
    printing && shown < 5 && NF > 0 && !/^note: run with/ { print "    " $0; shown++ }
    # A binary that crashed or was killed prints no test result.
    /process didn.t exit successfully/ { print; }
    /^test result: FAILED/ { print (binary ? binary ": " : "") $0 }
' "$log" | cut -c1-400
