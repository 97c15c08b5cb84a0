#!/usr/bin/env bash
# Runs the fuzz targets (tests/fuzz: one per parser) for a while (docs/architecture.md,
# "Fuzzing"). Every target must accept its input or refuse it with an input error; a crash, a hang,
# another exception or (libFuzzer) an AddressSanitizer report is a finding.
#
# Usage: harness/scripts/fuzz.sh [-m MINUTES] [-e libfuzzer|mutate] [-o OUT_DIR] [-s SEED] [TARGET ...]
#   MINUTES  total time, split evenly over the targets (default 10); targets run one at a time at
#            nice 19 (the machine is shared)
#   -e       libfuzzer (default when clang++-14 is installed): coverage-guided, every library
#            instrumented with AddressSanitizer; configures and builds build-fuzz/ (clang) when
#            needed. mutate: the seeded mutation runner of the normal build (build/bin).
#   OUT_DIR  out/fuzz; per target OUT_DIR/<target>/{corpus,findings,log.txt} (corpus: inputs
#            libFuzzer found interesting, seeded from tests/fuzz/corpus/<target>)
#   SEED     the engine's seed (default 1): the same seed, binary and time give the same inputs
#   TARGET   case, urdf, problem, trace, manifest, ... (default: every target of the build)
# A finding is kept as OUT_DIR/<target>/findings/*; once the bug is fixed, copy it into
# tests/fuzz/corpus/<target>/ (ctest `fuzz.<target>` replays that directory).
# A libFuzzer timeout that does not reproduce when replayed alone (a stall of a loaded machine)
# is kept as findings/stall-* and not counted; the fuzzing goes on after every finding.
# Exit codes: 0 no finding; 1 findings (listed); 2 usage or build failure; 130 / 143 interrupted.
set -uo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
MINUTES=10
ENGINE=""
OUT="$ROOT/out/fuzz"
SEED=1
TIMEOUT=10   # seconds per input before libFuzzer calls it a hang
USAGE="[-m MINUTES] [-e libfuzzer|mutate] [-o OUT_DIR] [-s SEED] [TARGET ...]"
usage() { echo "usage: $0 $USAGE" >&2; exit 2; }
lexdyn_options "$USAGE" m=MINUTES e=ENGINE o=OUT s=SEED -- "$@"
set -- "${LEXDYN_OPERANDS[@]}"
[[ "$MINUTES" =~ ^[0-9]+([.][0-9]+)?$ ]] || { echo "fuzz: -m expects minutes, found '$MINUTES'" >&2; exit 2; }
[[ "$SEED" =~ ^[0-9]+$ ]] || { echo "fuzz: -s expects a non-negative integer, found '$SEED'" >&2; exit 2; }
if [ -z "$ENGINE" ]; then
  if command -v clang++-14 > /dev/null; then ENGINE=libfuzzer; else ENGINE=mutate; fi
fi
interrupted=0
trap 'interrupted=130' INT
trap 'interrupted=143' TERM

if [ "$ENGINE" = libfuzzer ]; then
  BUILD="$ROOT/build-fuzz"
  if [ ! -f "$BUILD/CMakeCache.txt" ]; then
    echo "fuzz: configuring $BUILD (clang++-14, libFuzzer, AddressSanitizer)" >&2
    CC=clang-14 CXX=clang++-14 cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=Release -DLEXDYN_BUILD_FUZZERS=ON \
      > "$BUILD.configure.log" 2>&1 || { cat "$BUILD.configure.log" >&2; exit 2; }
  fi
elif [ "$ENGINE" = mutate ]; then
  BUILD="$ROOT/build"
  [ -f "$BUILD/CMakeCache.txt" ] || { echo "fuzz: $BUILD is not configured (harness/scripts/build.sh)" >&2; exit 2; }
else
  usage
fi
TARGETS=("$@")
if [ ${#TARGETS[@]} -eq 0 ]; then
  mapfile -t TARGETS < <(grep -v '^$' "$BUILD/fuzz-targets.txt")
fi
[ ${#TARGETS[@]} -gt 0 ] || { echo "fuzz: no targets (is $BUILD/fuzz-targets.txt there?)" >&2; exit 2; }
for t in "${TARGETS[@]}"; do
  grep -qx "$t" "$BUILD/fuzz-targets.txt" || { echo "fuzz: unknown target '$t' (targets: $(tr '\n' ' ' < "$BUILD/fuzz-targets.txt"))" >&2; exit 2; }
done
mkdir -p "$(dirname "$OUT")" || exit 2
echo "fuzz: building ${TARGETS[*]} in $BUILD" >&2
nice -n 19 cmake --build "$BUILD" -j "${LEXDYN_JOBS:-2}" --target "${TARGETS[@]/#/lexdyn-fuzz-}" > "$OUT.build.log" 2>&1 \
  || { mkdir -p "$(dirname "$OUT")"; tail -30 "$OUT.build.log" >&2; exit 2; }
SECONDS_EACH=$(awk -v m="$MINUTES" -v n="${#TARGETS[@]}" 'BEGIN { s = int(m * 60 / n); print (s < 1 ? 1 : s) }')
echo "fuzz: engine $ENGINE, ${#TARGETS[@]} target(s), $SECONDS_EACH s each, seed $SEED, output in $OUT" >&2

total=0
for t in "${TARGETS[@]}"; do
  [ "$interrupted" -ne 0 ] && break
  dir="$OUT/$t"
  mkdir -p "$dir/corpus" "$dir/findings"
  bin="$BUILD/bin/lexdyn-fuzz-$t"
  seeds="$ROOT/tests/fuzz/corpus/$t"
  start=$(date +%s)
  if [ "$ENGINE" = libfuzzer ]; then
    # libFuzzer stops at its first finding: keep it and go on (next seed) until the time is up.
    # A timeout is replayed once on its own: when the replay finishes well within the limit, it
    # was a stall of a loaded machine (e.g. the sanitizer returning memory to the system), not
    # a hang of the parser: it is kept as findings/stall-* and not counted.
    run_seed=$SEED
    : > "$dir/log.txt"
    while [ "$interrupted" -eq 0 ]; do
      left=$(( SECONDS_EACH - ($(date +%s) - start) ))
      [ "$left" -le 0 ] && break
      nice -n 19 "$bin" -seed="$run_seed" -max_total_time="$left" -timeout="$TIMEOUT" -rss_limit_mb=2048 -max_len=65536 \
        -print_final_stats=1 -artifact_prefix="$dir/findings/" "$dir/corpus" "$seeds" >> "$dir/log.txt" 2>&1
      status=$?
      [ "$status" -eq 0 ] && break
      for f in "$dir"/findings/timeout-*; do
        [ -f "$f" ] || continue
        t0=$(date +%s.%N)
        if timeout "$TIMEOUT" "$bin" "$f" > /dev/null 2>&1; then
          t1=$(date +%s.%N)
          mv "$f" "$dir/findings/stall-${f##*/timeout-}"
          echo "  timeout not reproduced: the replay took $(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.2f", b - a }') s (limit $TIMEOUT s); kept as stall-*" >> "$dir/log.txt"
        fi
      done
      run_seed=$((run_seed + 1))
    done
  else
    # The runner stops at a crash or a hang (the input is in findings/current.bin): keep it and
    # go on with the next seed until the time is up.
    run_seed=$SEED
    : > "$dir/log.txt"
    while [ "$interrupted" -eq 0 ]; do
      left=$(( SECONDS_EACH - ($(date +%s) - start) ))
      [ "$left" -le 0 ] && break
      nice -n 19 "$bin" --seconds "$left" --seed "$run_seed" --out "$dir/findings" "$seeds" >> "$dir/log.txt" 2>&1
      status=$?
      if [ "$status" -ge 128 ] && [ -f "$dir/findings/current.bin" ]; then
        mv "$dir/findings/current.bin" "$dir/findings/crash-seed$run_seed-status$status.bin"
        echo "  crash or hang (exit status $status) with seed $run_seed" >> "$dir/log.txt"
      fi
      [ "$status" -lt 128 ] && break
      run_seed=$((run_seed + 1))
    done
  fi
  found=$(find "$dir/findings" -maxdepth 1 -type f \( -name 'crash-*' -o -name 'timeout-*' -o -name 'oom-*' -o -name 'leak-*' -o -name 'finding-*' \) | wc -l)
  total=$((total + found))
  summary=$(grep -E "^stat::number_of_executed_units|^mutation runner" "$dir/log.txt" | tail -1)
  echo "fuzz: $t: $((  $(date +%s) - start )) s, $found finding(s); ${summary:-see $dir/log.txt}" >&2
done
[ "$interrupted" -ne 0 ] && { echo "fuzz: interrupted" >&2; exit "$interrupted"; }
if [ "$total" -gt 0 ]; then
  echo "fuzz: $total finding(s):" >&2
  find "$OUT" -path '*/findings/*' -type f \( -name 'crash-*' -o -name 'timeout-*' -o -name 'oom-*' -o -name 'leak-*' -o -name 'finding-*' \) >&2
  exit 1
fi
exit 0
