# Sourced by the shell tests of tests/scripts: ROOT (the repository), TMP (a directory removed on
# exit), fail (0 until a check fails) and check WHAT CONDITION... (runs the condition, prints
# "ok: WHAT" or "FAIL: WHAT" and sets fail=1 on a failure). A test ends with `exit "$fail"`.
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
TMP="$(mktemp -d)"
trap 'rm -rf "$TMP"' EXIT
fail=0
check() {
  local what="$1"
  shift
  if "$@"; then echo "ok: $what"; else echo "FAIL: $what"; fail=1; fi
}
