#!/usr/bin/env bash
# profile-tick.sh: a short exp1 run under callgrind gives the parts' table (every part found in
# the profile, none negative, the controller's and the simulator's main parts nonzero); a case
# without a controller gives a zero controller; bad input exits 2, a run without a summary 3.
# Usage: test_profile_tick.sh BUILD_DIR
set -u
source "$(dirname "${BASH_SOURCE[0]}")/test_lib.sh"
BUILD="$1"
# value PART FILE: the instructions per tick (thousands) of the table's line for PART.
value() { grep -F -- "$1" "$2" | grep ' k ' | head -1 | awk '{for (i = 1; i <= NF; ++i) if ($(i + 1) == "k") { print $i; exit }}'; }
positive() { awk -v v="$1" 'BEGIN { exit !(v > 0) }'; }
S="$ROOT/harness/scripts/profile-tick.sh"

"$S" -b "$BUILD" -m bfgs -d 0.2 -o "$TMP/exp1" "$ROOT/cases/exp1.yaml" > "$TMP/exp1.txt" 2>&1
code=$?
cat "$TMP/exp1.txt"
check "exp1: exit 0" [ "$code" -eq 0 ]
check "exp1: 40 ticks" grep -q '^case .*exp1.yaml: 40 ticks' "$TMP/exp1.txt"
check "exp1: 17 parts" [ "$(grep -c ' G .* k ' "$TMP/exp1.txt")" -eq 17 ]
check "exp1: no negative part" [ -z "$(grep ' G .* k ' "$TMP/exp1.txt" | grep -- ' -[0-9]')" ]
for part in "controller tick" "solver: level factorisations" "model (kinematics" "simulator step" \
            "right-hand sides: Simbody's state" "right-hand sides: forward dynamics" "observation at the tick" "trace writing"; do
  check "exp1: '$part' > 0" positive "$(value "$part" "$TMP/exp1.txt")"
done
check "exp1: -o keeps the profile and the run" test -s "$TMP/exp1/callgrind.out" -a -f "$TMP/exp1/run/summary.json"

"$S" -b "$BUILD" -d 0.2 "$ROOT/cases/stand.yaml" > "$TMP/stand.txt" 2>&1
code=$?
cat "$TMP/stand.txt"
check "stand: exit 0" [ "$code" -eq 0 ]
check "stand: no controller" [ "$(value "controller tick" "$TMP/stand.txt")" = "0.0" ]
check "stand: simulator step > 0" positive "$(value "simulator step" "$TMP/stand.txt")"

"$S" -b "$BUILD" "$TMP/missing.yaml" > /dev/null 2>&1
check "missing case file: exit 2" [ $? -eq 2 ]
"$S" -b "$BUILD" "$ROOT/cases/stand.yaml" "$ROOT/cases/exp1.yaml" > /dev/null 2>&1
check "two cases: exit 2" [ $? -eq 2 ]
"$S" -x 1 "$ROOT/cases/stand.yaml" > /dev/null 2>&1
check "unknown option: exit 2" [ $? -eq 2 ]
mkdir -p "$TMP/broken/bin"
printf '#!/usr/bin/env bash\nexit 3\n' > "$TMP/broken/bin/lexdyn-harness"
chmod +x "$TMP/broken/bin/lexdyn-harness"
"$S" -b "$TMP/broken" "$ROOT/cases/stand.yaml" > /dev/null 2>&1
check "a run without a summary: exit 3" [ $? -eq 3 ]
exit "$fail"
