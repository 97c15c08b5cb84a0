#!/usr/bin/env bash
# Runs exp1, exp2, exp3 and the point mass with each reading of eq. 87-89 (docs/controller.md,
# "Readings of eq. 87-89"), with the cases' alpha I* (newton_identity_weight 1e-4) and without
# it (alpha = 0, the paper's experiments), then tabulates them (second_order_table.py).
# Usage: second-order-runs.sh [-b BUILD] [-o OUT] [-j JOBS] [-a "1e-4 0"] [CASE ...]   (default: all four)
# -r "bfgs:gauss_newton ah:add_jtj": only these readings (method:reading).
# -a: the alphas of the experiment cases (1e-4: the cases' own value); the point mass runs as
# committed (damping rows) and with damping 0.
# Output: OUT/<case>.<method>.<reading>.a<alpha>/{trace.csv,summary.json,log.txt}, OUT/table.md.
set -uo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
BUILD="$ROOT/build"
OUT="$ROOT/out/second-order"
JOBS=2
ALPHAS="1e-4 0"
ONLY=""
lexdyn_options "[-b BUILD] [-o OUT] [-j JOBS] [-a \"ALPHAS\"] [-r \"METHOD:READING ...\"] [CASE ...]" \
  b=BUILD o=OUT j=JOBS a=ALPHAS r=ONLY -- "$@"
set -- ${LEXDYN_OPERANDS[@]+"${LEXDYN_OPERANDS[@]}"}
CASES=("$@")
[ ${#CASES[@]} -eq 0 ] && CASES=(exp1 exp2 exp3 pointmass-damping)
HARNESS="$BUILD/bin/lexdyn-harness"
mkdir -p "$OUT"

# method reading --set arguments
READINGS=(
  "bfgs current_multipliers"
  "bfgs full_difference controller.params.bfgs_secant=full_difference"
  "bfgs gauss_newton controller.params.bfgs_secant=gauss_newton"
  "bfgs scale_one controller.params.multiplier_scale=one"
  "ah analytic"
  "ah add_jtj controller.params.ah_add_jtj=true"
  "ah scale_one controller.params.multiplier_scale=one"
)

jobs_list=()
for c in "${CASES[@]}"; do
  read -r -a alphas <<<"$ALPHAS"
  [ "$c" = pointmass-damping ] && alphas=("case" "nodamping")
  for r in "${READINGS[@]}"; do
    read -r method reading extra <<<"$r"
    if [ -n "$ONLY" ] && [[ " $ONLY " != *" $method:$reading "* ]]; then continue; fi
    for a in "${alphas[@]}"; do
      args=(--method "$method")
      [ -n "${extra:-}" ] && args+=(--set "$extra")
      case "$a" in
        1e-4 | case) ;;
        nodamping) args+=(--set controller.params.damping=0) ;;
        *) args+=(--set "controller.params.newton_identity_weight=$a") ;;
      esac
      jobs_list+=("$c|$method|$reading|$a|${args[*]}")
    done
  done
done

run_one() {
  IFS='|' read -r c method reading a args <<<"$1"
  local dir="$OUT/$c.$method.$reading.a$a"
  mkdir -p "$dir"
  # shellcheck disable=SC2086
  "$HARNESS" run "$ROOT/cases/$c.yaml" --out "$dir" $args --quiet >"$dir/log.txt" 2>&1
  echo $? >"$dir/exit_code"
  echo "done $c $method $reading alpha=$a exit $(cat "$dir/exit_code")"
}

running=0
for j in "${jobs_list[@]}"; do
  run_one "$j" &
  running=$((running + 1))
  if [ "$running" -ge "$JOBS" ]; then
    wait -n
    running=$((running - 1))
  fi
done
wait
/usr/bin/python3 "$ROOT/harness/scripts/second_order_table.py" "$OUT" >"$OUT/table.md"
cat "$OUT/table.md"
