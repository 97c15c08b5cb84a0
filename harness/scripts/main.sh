#!/usr/bin/env bash
# Sets up, builds and runs the main job.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
cd "$ROOT"
harness/scripts/install-deps.sh
harness/scripts/build.sh
harness/scripts/exp1.sh "$@"
