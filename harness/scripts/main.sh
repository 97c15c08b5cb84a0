#!/usr/bin/env bash
# Sets up, builds and runs the main job.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
case "${1:-}" in -h | --help) lexdyn_help "[options of exp1.sh]"; "$ROOT/harness/scripts/exp1.sh" --help; exit 0 ;; esac
cd "$ROOT"
harness/scripts/install-deps.sh
harness/scripts/build.sh
harness/scripts/exp1.sh "$@"
