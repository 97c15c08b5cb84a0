#!/usr/bin/env bash
# Regenerates golden traces (golden/*.csv) explicitly: the only way they change. ctest never runs
# this; it runs `lexdyn-harness golden check` (label regression). docs/cases.md, "Golden traces".
#
# Usage: harness/scripts/golden-update.sh [-b BUILD_DIR] [-j JOBS] [-m MANIFEST] [ID ...]
#   ID: CASE.METHOD or CASE (see `lexdyn-harness golden list`); none: every golden of the manifest.
#   defaults: build/, 2 jobs, golden/manifest.yaml.
# Afterwards re-run cmake in BUILD_DIR (done here) so that ctest registers new golden files, then
# review `git diff --stat golden/` and run `ctest -L regression`.
# Exit codes (harness/scripts/exit-codes.sh): the worst of the `golden update` runs: 130/143
# interrupted, 2 bad input, 3 a run failure, 0 every golden written.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
BUILD="$ROOT/build"
JOBS=2
MANIFEST="$ROOT/golden/manifest.yaml"
lexdyn_options "[-b BUILD_DIR] [-j JOBS] [-m MANIFEST] [ID ...]" b=BUILD j=JOBS m=MANIFEST -- "$@"
lexdyn_harness golden-update " (cmake --build $BUILD)"

IDS="$(lexdyn_golden_list "$MANIFEST" "${LEXDYN_OPERANDS[@]}" | cut -d' ' -f1)"
echo "golden-update: $(echo "$IDS" | wc -l) golden(s), $JOBS at a time" >&2
CODES="$(mktemp)"
export HARNESS MANIFEST CODES
# One process per golden (each writes its own file atomically); a failing run stops nothing else.
echo "$IDS" | xargs -P "$JOBS" -I{} bash -c '"$HARNESS" golden update --manifest "$MANIFEST" --only "$0"; echo $? >> "$CODES"' {} || true
status=0
while read -r c; do status=$(lexdyn_worse "$status" "$c"); done < "$CODES"
rm -f "$CODES"
if [ -f "$BUILD/CMakeCache.txt" ]; then cmake "$BUILD" > /dev/null; fi
exit "$status"
