#!/usr/bin/env bash
# Configures (Release) and builds lexdyn into build/. Usage: build.sh [extra cmake args]
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
lexdyn_help_option "[extra cmake args]" "$@"
cd "$ROOT"
JOBS="${LEXDYN_JOBS:-$(nproc)}"
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release "$@" > build.configure.log 2>&1 || { cat build.configure.log; exit 1; }
cmake --build build -j "$JOBS"
