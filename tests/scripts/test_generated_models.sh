#!/bin/bash
# The generated robot files are what their generator writes today (models/*/README.md: "do not edit
# by hand"), and the generator refuses a bad upper-body scale.
set -u
src=$(cd "$(dirname "$0")/../.." && pwd)
gen="$src/models/hrp2kai_like/generate_urdf.py"
fail=0
check() {  # FILE ARGS...: the generator's output with ARGS equals FILE
  local file=$1
  shift
  if ! /usr/bin/python3 "$gen" "$@" | cmp -s - "$src/$file"; then
    echo "FAIL: $file differs from 'generate_urdf.py $*' (regenerate it)"
    fail=1
  else
    echo "ok   $file"
  fi
}
check models/hrp2kai_like/hrp2kai_like.urdf
check models/hrp2kai_like/hrp2kai_like.srdf --srdf
check models/hrp2kai_heavy/hrp2kai_heavy.urdf --heavy
check models/hrp2kai_weak/hrp2kai_weak.urdf --weak-upper-body
# A scale changes only the upper body's effort limits: 2 x the weak robot's shoulder roll.
if ! /usr/bin/python3 "$gen" --weak-upper-body 2 | grep -A6 'joint name="RARM_JOINT1"' | grep -q 'effort="44.64"'; then
  echo "FAIL: --weak-upper-body 2 does not write RARM_JOINT1's effort as 44.64"
  fail=1
fi
for bad in 0 -1 x inf 1e-9; do
  if out=$(/usr/bin/python3 "$gen" --weak-upper-body "$bad" 2>&1); then
    echo "FAIL: --weak-upper-body $bad was accepted"
    fail=1
  elif [ -n "$(echo "$out" | grep -v 'usage\|must be > 0')" ]; then
    echo "FAIL: --weak-upper-body $bad: unexpected message: $out"
    fail=1
  fi
done
exit $fail
