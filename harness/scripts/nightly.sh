#!/usr/bin/env bash
# The nightly job (docs/report.md): build, the ctest suite (golden checks included), every
# case x method of golden/manifest.yaml at full length, the sweeps of the nightly configuration,
# then the report (harness/scripts/report.py) and one record appended to the history file.
#
# Usage: harness/scripts/nightly.sh [--out DIR] [--history FILE] [-j JOBS] [--config FILE]
#                                   [--build-dir DIR] [--only ID,...] [--duration S]
#                                   [--no-build] [--no-ctest]
#   --out DIR       this night's directory (default out/nightly/<UTC date>); running again with
#                   the same DIR resumes: a run whose summary.json exists (and is not
#                   "interrupted") is done, a stored ctest result and sweep output are kept.
#                   Locked while the job runs (DIR/.lexdyn.lock): a second job on DIR exits 2
#   --history FILE  JSON Lines history (default out/nightly/history.jsonl)
#   -j JOBS         runs at a time (default LEXDYN_JOBS or the number of cores)
#   --config FILE   nightly configuration (default harness/nightly.yaml): the sweeps
#   --only IDS      only these runs (CASE.METHOD or CASE, as `lexdyn-harness golden list --only`)
#   --duration S    cut every run at S seconds of simulated time (tests; not a nightly)
#   --no-build, --no-ctest  skip those steps
# Writes DIR/{nightly.json, runs.txt, <id>/{trace.csv,summary.json,log.txt}, compare/<case>.json,
# ctest/{junit.xml,log.txt}, sweeps/<name>/, report/index.html}.
# Exit codes: 0 every run completed and every check, comparison, golden and test passed; 1 a
# check, comparison, golden or test failed; 2 bad input (options, configuration, a resumed
# directory of another commit, DIR in use by another job; the report's bad input); 3 a run
# stopped early (integrator or controller failure, no summary) or a step failed (build, report);
# 130 / 143 interrupted by SIGINT / SIGTERM (what was done is kept; run the same command again
# to resume).
set -uo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
OUT=""
HISTORY=""
JOBS="${LEXDYN_JOBS:-$(nproc)}"
CONFIG="$ROOT/harness/nightly.yaml"
BUILD="$ROOT/build"
ONLY=""
DURATION=""
DO_BUILD=1
DO_CTEST=1
PY=/usr/bin/python3

usage() { sed -n '2,26p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//' >&2; }
die() { echo "nightly: error: $*" >&2; exit 2; }
say() { echo "[nightly $(date -u +%H:%M:%S)] $*" >&2; }

while [ $# -gt 0 ]; do
  case "$1" in
    --out) OUT="${2:?}"; shift 2 ;;
    --history) HISTORY="${2:?}"; shift 2 ;;
    -j) JOBS="${2:?}"; shift 2 ;;
    --config) CONFIG="${2:?}"; shift 2 ;;
    --build-dir) BUILD="${2:?}"; shift 2 ;;
    --only) ONLY="${2:?}"; shift 2 ;;
    --duration) DURATION="${2:?}"; shift 2 ;;
    --no-build) DO_BUILD=0; shift ;;
    --no-ctest) DO_CTEST=0; shift ;;
    -h|--help) usage; exit 0 ;;
    *) usage; die "unknown option '$1'" ;;
  esac
done
[[ "$JOBS" =~ ^[1-9][0-9]*$ ]] || die "-j: expected a positive integer, found '$JOBS'"
[ -z "$DURATION" ] || [[ "$DURATION" =~ ^[0-9]*\.?[0-9]+$ ]] || die "--duration: expected seconds, found '$DURATION'"
[ -f "$CONFIG" ] || die "--config: $CONFIG: no such file"
OUT="${OUT:-$ROOT/out/nightly/$(date -u +%Y-%m-%d)}"
HISTORY="${HISTORY:-$ROOT/out/nightly/history.jsonl}"
# A path through a file is bad input (2); a refusal of the system (permissions, a full or
# read-only file system) a run failure (3).
if ! err="$(mkdir -p "$OUT" 2>&1)"; then
  case "$err" in
    *"File exists"*|*"Not a directory"*) die "$OUT: cannot create the output folder: ${err##*: }" ;;
    *) echo "nightly: error: $OUT: cannot create the output folder: ${err##*: }" >&2; exit 3 ;;
  esac
fi
OUT="$(cd "$OUT" && pwd)"
HARNESS="$BUILD/bin/lexdyn-harness"

# ------------------------------------------------------------------ the folder's lock
# One lock format for every lexdyn tool (docs/report.md, "Locks"): OUT/.lexdyn.lock, flocked
# for the job's lifetime, holding "pid=P started=T host=H command=C". A job that died holds no
# flock: its file is taken over. The file is never removed. The runs, the report and the sweeps
# lock their own subfolders; the background commands below do not inherit this one (each gets
# {LOCK_FD}>&-), so it ends with the job.
lock_holder() {  # "pid P, C, started T on H" from a lock file's line, or "holder unknown"
  local line="" text
  IFS= read -r line < "$1" 2>/dev/null
  if [[ "$line" =~ ^pid=([0-9]+)(\ started=([^ ]*))?(\ host=([^ ]*))?(\ command=(.*))?$ ]]; then
    text="pid ${BASH_REMATCH[1]}"
    [ -n "${BASH_REMATCH[7]}" ] && text+=", ${BASH_REMATCH[7]}"
    [ -n "${BASH_REMATCH[3]}" ] && text+=", started ${BASH_REMATCH[3]}"
    [ -n "${BASH_REMATCH[5]}" ] && text+=" on ${BASH_REMATCH[5]}"
    echo "$text"
  else
    echo "holder unknown"
  fi
}
{ exec {LOCK_FD}<>"$OUT/.lexdyn.lock"; } 2>/dev/null \
  || { echo "nightly: error: $OUT/.lexdyn.lock: cannot open the lock file" >&2; exit 3; }
if ! flock -n -x "$LOCK_FD"; then
  die "$OUT: in use by another lexdyn job ($(lock_holder "$OUT/.lexdyn.lock")); wait for it to end or give another --out"
fi
# Best effort: the lock is the flock; the line only names its holder in others' messages.
{ truncate -s 0 "$OUT/.lexdyn.lock" \
    && printf 'pid=%s started=%s host=%s command=nightly.sh\n' "$$" "$(date -u +%Y-%m-%dT%H:%M:%SZ)" "$(hostname)" \
       >> "$OUT/.lexdyn.lock"; } 2>/dev/null

# ------------------------------------------------------------------ signals: keep what was done
RUNNING=()          # pids of the runs in flight
declare -A RUN_OF   # pid -> run id
INTERRUPTED=0
on_signal() {
  INTERRUPTED=$1
  say "interrupted: stopping ${#RUNNING[@]} run(s) (each keeps its trace); run the same command again to resume"
  for p in "${RUNNING[@]}"; do kill -TERM "$p" 2>/dev/null; done
}
trap 'on_signal 130' INT
trap 'on_signal 143' TERM
# One second between polls. Bash runs a trap only once a foreground command returns, but a
# `wait` returns at once on a signal: the runs in flight are told to stop immediately, not
# after the sleep (a short run could otherwise complete in that second and not be marked).
pause() {
  sleep 1 {LOCK_FD}>&- &
  wait $! 2>/dev/null || true
}
stop_if_interrupted() {
  if [ "$INTERRUPTED" -ne 0 ]; then
    for p in "${RUNNING[@]}"; do wait "$p" 2>/dev/null; done
    exit "$INTERRUPTED"
  fi
}

# ------------------------------------------------------------------ configuration (the sweeps)
SWEEPS="$("$PY" - "$CONFIG" <<'EOF'
import sys, yaml
path = sys.argv[1]
try:
    doc = yaml.safe_load(open(path)) or {}
except yaml.YAMLError as e:
    sys.exit(f"nightly: error: {path}: expected YAML ({e})")
if not isinstance(doc, dict):
    sys.exit(f"nightly: error: {path}: expected a mapping at the top level")
for k in doc:
    if k not in ("format", "sweeps"):
        sys.exit(f"nightly: error: {path}: {k}: unknown key (expected format, sweeps)")
if doc.get("format") != "lexdyn-nightly/1":
    sys.exit(f"nightly: error: {path}: format: expected 'lexdyn-nightly/1', found {doc.get('format')!r}")
sweeps = doc.get("sweeps") or []
if not isinstance(sweeps, list):
    sys.exit(f"nightly: error: {path}: sweeps: expected a list, found {type(sweeps).__name__}")
for i, s in enumerate(sweeps):
    where = f"{path}: sweeps[{i}]"
    if not isinstance(s, dict):
        sys.exit(f"nightly: error: {where}: expected {{file, points}}, found {s!r}")
    for k in s:
        if k not in ("file", "points", "name"):
            sys.exit(f"nightly: error: {where}.{k}: unknown key (expected file, points, name)")
    f, p = s.get("file"), s.get("points")
    if not isinstance(f, str) or not f:
        sys.exit(f"nightly: error: {where}.file: expected a sweep file, found {f!r}")
    if not isinstance(p, int) or isinstance(p, bool) or p <= 0:
        sys.exit(f"nightly: error: {where}.points: expected a positive integer, found {p!r}")
    name = s.get("name") or f.rsplit("/", 1)[-1].rsplit(".", 1)[0]
    print(name, f, p)
EOF
)" || exit 2

# ------------------------------------------------------------------ 1. build
if [ "$DO_BUILD" -eq 1 ]; then
  say "building into $BUILD (log: $OUT/build.log)"
  # In the foreground: Ctrl-C stops the build too; a SIGTERM to this script alone lets the
  # build finish first, then exits 143.
  if [ "$BUILD" = "$ROOT/build" ]; then
    LEXDYN_JOBS="$JOBS" "$ROOT/harness/scripts/build.sh" > "$OUT/build.log" 2>&1
  else
    { cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=Release && cmake --build "$BUILD" -j "$JOBS"; } > "$OUT/build.log" 2>&1
  fi
  status=$?
  stop_if_interrupted
  if [ $status -ne 0 ]; then tail -20 "$OUT/build.log" >&2; say "build failed (see $OUT/build.log)"; exit 3; fi
fi
[ -x "$HARNESS" ] || die "$HARNESS not built (run without --no-build, or give --build-dir)"

# ------------------------------------------------------------------ the night's identity
COMMIT="$(git -C "$ROOT" rev-parse HEAD 2>/dev/null || echo unknown)"
[ -n "$(git -C "$ROOT" status --porcelain --untracked-files=no 2>/dev/null)" ] && COMMIT="$COMMIT (with uncommitted changes)"
# The night's record (nightly.json) is lexdyn.history's: written and read through it.
if [ -f "$OUT/nightly.json" ]; then
  was="$("$PY" -c '
import sys, lexdyn.history as h
try:
    print(h.read_night(sys.argv[1])["commit"])
except h.FormatError as e:
    sys.exit(f"nightly: error: {e}")' "$OUT/nightly.json")" || die "$OUT/nightly.json is not a night this job can resume: give another --out"
  [ "$was" = "$COMMIT" ] || die "$OUT holds a night of commit $was, the checkout is at $COMMIT: give another --out"
  say "resuming the night in $OUT"
else
  "$PY" -c 'import sys, lexdyn.history as h; h.write_night(sys.argv[1], h.night_info(*sys.argv[2:]))' \
    "$OUT/nightly.json" "$COMMIT" "$JOBS" "$DURATION" || exit 3
fi

# ------------------------------------------------------------------ 2. ctest (goldens included)
if [ "$DO_CTEST" -eq 1 ]; then
  mkdir -p "$OUT/ctest"
  if [ -f "$OUT/ctest/junit.xml" ]; then
    say "ctest: done earlier ($OUT/ctest/junit.xml)"
  else
    say "ctest: the whole suite, $JOBS at a time (log: $OUT/ctest/log.txt)"
    (cd "$BUILD" && exec ctest -j "$JOBS" --output-junit "$OUT/ctest/junit.xml.partial") > "$OUT/ctest/log.txt" 2>&1 {LOCK_FD}>&- &
    RUNNING=($!)
    since=$SECONDS
    while kill -0 "${RUNNING[0]}" 2>/dev/null && [ "$INTERRUPTED" -eq 0 ]; do
      pause
      if [ $((SECONDS - since)) -ge 30 ]; then
        since=$SECONDS
        say "ctest: $(grep -a -o -E '^ *[0-9]+/[0-9]+ Test' "$OUT/ctest/log.txt" | tail -1 | tr -d ' ' | sed 's/Test$//') tests done"
      fi
    done
    wait "${RUNNING[0]}" 2>/dev/null
    RUNNING=()
    stop_if_interrupted
    if [ -f "$OUT/ctest/junit.xml.partial" ]; then
      mv "$OUT/ctest/junit.xml.partial" "$OUT/ctest/junit.xml"
      say "ctest: $(grep -E 'tests passed|tests failed' "$OUT/ctest/log.txt" | tail -1)"
    else
      say "ctest wrote no JUnit file (see $OUT/ctest/log.txt)"
    fi
  fi
fi

# ------------------------------------------------------------------ 3. every case x method, full length
ONLY_ARGS=()
[ -n "$ONLY" ] && ONLY_ARGS=(--only "$ONLY")
"$HARNESS" golden list "${ONLY_ARGS[@]}" > "$OUT/runs.txt.partial" || die "golden list failed (see above)"
mv "$OUT/runs.txt.partial" "$OUT/runs.txt"
TOTAL=$(wc -l < "$OUT/runs.txt")

is_done() {  # a run is done when its summary.json exists and says it was not interrupted
  [ -f "$1/summary.json" ] && ! grep -q '"status": "interrupted"' "$1/summary.json"
}
PENDING=()
while read -r id case_file method; do
  if is_done "$OUT/$id"; then continue; fi
  PENDING+=("$id $case_file $method")
done < "$OUT/runs.txt"
DONE=$((TOTAL - ${#PENDING[@]}))
say "runs: $TOTAL in all, $DONE done earlier, ${#PENDING[@]} to run, $JOBS at a time${DURATION:+ (cut at $DURATION s)}"

start_run() {
  local id="$1" case_file="$2" method="$3" dir="$OUT/$1"
  local args=(run "$case_file" --out "$dir")
  [ "$method" != "-" ] && args+=(--method "$method")
  [ -n "$DURATION" ] && args+=(--duration "$DURATION")
  mkdir -p "$dir"
  "$HARNESS" "${args[@]}" > "$dir/log.txt" 2>&1 {LOCK_FD}>&- &
  RUNNING+=($!)
  RUN_OF[$!]="$id"
  say "start $id"
}

progress_line() {  # the runs in flight and how far each is (the harness's own progress lines)
  local text="" p id last
  for p in "${RUNNING[@]}"; do
    id="${RUN_OF[$p]}"
    last="$(grep -a '] t = ' "$OUT/$id/log.txt" 2>/dev/null | tail -1 | sed 's/^\[[^]]*\] //')"
    text+="; $id ${last:-starting}"
  done
  say "runs: $DONE of $TOTAL done${text}"
}

next=0
last_progress=$SECONDS
while [ $next -lt ${#PENDING[@]} ] || [ ${#RUNNING[@]} -gt 0 ]; do
  stop_if_interrupted
  while [ $next -lt ${#PENDING[@]} ] && [ ${#RUNNING[@]} -lt "$JOBS" ]; do
    # shellcheck disable=SC2086
    start_run ${PENDING[$next]}
    next=$((next + 1))
  done
  pause
  still=()
  for p in "${RUNNING[@]}"; do
    if kill -0 "$p" 2>/dev/null; then still+=("$p"); continue; fi
    wait "$p"
    code=$?
    id="${RUN_OF[$p]}"
    DONE=$((DONE + 1))
    verdict="$(grep -a -m1 -E '^\[[^]]*\] [a-z_]+: ' "$OUT/$id/log.txt" | sed 's/^\[[^]]*\] //')"
    failed=$(grep -a -c '^  FAIL' "$OUT/$id/log.txt")
    say "done  $id ($DONE/$TOTAL): ${verdict:-no summary line, exit code $code}, $failed failed check(s)"
  done
  RUNNING=("${still[@]}")
  if [ $((SECONDS - last_progress)) -ge 30 ] && [ ${#RUNNING[@]} -gt 0 ]; then
    progress_line
    last_progress=$SECONDS
  fi
done
stop_if_interrupted

# ------------------------------------------------------------------ 4. the cases' method comparisons
mkdir -p "$OUT/compare"
compare_case() {  # NAME CASE_FILE TRACE ...
  local name="$1" case_file="$2"
  shift 2
  "$HARNESS" compare --case "$case_file" --json "$@" > "$OUT/compare/$name.json.partial" 2> "$OUT/compare/$name.txt"
  if grep -q '"checks"' "$OUT/compare/$name.json.partial"; then
    mv "$OUT/compare/$name.json.partial" "$OUT/compare/$name.json"
  else
    rm -f "$OUT/compare/$name.json.partial"
    say "compare $name: no result (see $OUT/compare/$name.txt)"
  fi
}
lexdyn_each_comparison "$OUT/runs.txt" "$OUT" compare_case

# ------------------------------------------------------------------ 5. sweeps
SWEEP_ARGS=()
if [ -z "$SWEEPS" ]; then
  say "sweeps: none in $CONFIG (the report's sweep section stays empty)"
else
  mkdir -p "$OUT/sweeps"
  while read -r name file points; do
    stop_if_interrupted
    dir="$OUT/sweeps/$name"
    if [ -f "$dir/summary.json" ]; then say "sweep $name: done earlier"; continue; fi
    say "sweep $name: $file, $points points, $JOBS at a time (log: $OUT/sweeps/$name.log)"
    # The failure database lives beside the history: every night replays the failures found before.
    "$HARNESS" sweep run "$ROOT/$file" --out "$dir" -j "$JOBS" --points "$points" \
      --db "$(dirname "$HISTORY")/sweep-failures/$name.jsonl" > "$OUT/sweeps/$name.log" 2>&1 {LOCK_FD}>&- &
    RUNNING=($!)
    RUN_OF[$!]="sweep $name"
    wait "${RUNNING[0]}"
    RUNNING=()
    stop_if_interrupted
    [ -f "$dir/summary.json" ] || say "sweep $name wrote no summary (see $OUT/sweeps/$name.log)"
  done <<< "$SWEEPS"
  SWEEP_ARGS=(--sweeps "$OUT/sweeps")
fi

# ------------------------------------------------------------------ 6. the report and the history
say "report: $OUT/report (history $HISTORY)"
# A damaged history line does not stop it: the report skips the line with a warning on the page.
"$PY" "$ROOT/harness/scripts/report.py" --runs "$OUT" "${SWEEP_ARGS[@]}" --history "$HISTORY" --append-history \
  --out "$OUT/report" >&2
rstatus=$?
stop_if_interrupted
if [ $rstatus -ne 0 ]; then
  # The report's own code: 2 bad input (its folder in use, a damaged summary), 3 anything else
  # (a full disk, an internal error); the previous report is left as it was.
  say "the report failed (exit code $rstatus)"
  code=$(lexdyn_code "$rstatus")
  case "$code" in 2|130|143) exit "$code" ;; *) exit 3 ;; esac
fi

# ------------------------------------------------------------------ exit code of the night
"$PY" - "$OUT" <<'EOF'
import json, os, sys, xml.etree.ElementTree as ET
out = sys.argv[1]
stopped, failed = [], []
for line in open(os.path.join(out, "runs.txt")):
    rid = line.split()[0]
    p = os.path.join(out, rid, "summary.json")
    if not os.path.isfile(p):
        stopped.append(f"{rid} (no summary)")
        continue
    s = json.load(open(p))
    if s.get("status") != "completed":
        stopped.append(f"{rid} ({s.get('status')})")
    failed += [f"{rid}: {c['name']}" for c in s.get("checks", []) if not c.get("passed")]
cdir = os.path.join(out, "compare")
for n in sorted(os.listdir(cdir)) if os.path.isdir(cdir) else []:
    if n.endswith(".json"):
        failed += [f"{n[:-5]}: {c['name']}" for c in json.load(open(os.path.join(cdir, n))).get("checks", []) if not c.get("passed")]
junit = os.path.join(out, "ctest", "junit.xml")
if os.path.isfile(junit):
    for tc in ET.parse(junit).getroot().iter("testcase"):
        if tc.find("failure") is not None or tc.get("status") == "fail":
            failed.append(f"ctest {tc.get('name')}")
print(f"[nightly] {len(stopped)} run(s) stopped early, {len(failed)} failed check(s), comparison(s), golden(s) or test(s)", file=sys.stderr)
sys.exit(3 if stopped else (1 if failed else 0))
EOF
code=$?
say "report: $OUT/report/index.html"
exit $code
