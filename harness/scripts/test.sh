#!/usr/bin/env bash
# Sets up, builds and runs the whole test suite with ctest (what CI runs).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
lexdyn_help_option "[extra ctest args]" "$@"
cd "$ROOT"
harness/scripts/install-deps.sh
harness/scripts/build.sh
cd build
# Exit codes: 0 every test passed, 1 a test failed (ctest's own status is 8).
ctest --output-on-failure -j "${LEXDYN_JOBS:-$(nproc)}" "$@" || exit 1
