# Sourced by the scripts of harness/scripts: the repository's root, the exit-code convention
# (harness/scripts/exit-codes.sh) and what the scripts share: option parsing, the lexdyn-harness
# of a build directory, the runs of a golden manifest and the cases' method comparisons.
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../../.." && pwd)"
source "$ROOT/harness/scripts/exit-codes.sh"
# The Python scripts the scripts run import the lexdyn package of this checkout (python/lexdyn;
# docs/python.md, "Where Python finds the package").
export PYTHONPATH="$ROOT/python${PYTHONPATH:+:$PYTHONPATH}"

# lexdyn_options USAGE LETTER=VARIABLE ... -- "$@": reads the options -LETTER VALUE into their
# variables (the ones not given keep their defaults); LETTER=VARIABLE+ collects every value of a
# repeated option, each followed by a newline. An unknown option or one without its value
# prints "usage: SCRIPT USAGE" and exits 2. -h or --help prints the usage line and the script's
# header comment and exits 0. The operands are left in LEXDYN_OPERANDS.
lexdyn_options() {
  local usage="$1" spec="" opt OPTIND=1
  local -A variable=()
  shift
  while [ "$1" != "--" ]; do
    variable[${1%%=*}]="${1#*=}"
    spec+="${1%%=*}:"
    shift
  done
  shift
  lexdyn_help_option "$usage" "$@"
  while getopts "$spec" opt; do
    [ "$opt" != "?" ] || { echo "usage: $0 $usage" >&2; exit 2; }
    local name="${variable[$opt]}"
    if [ "${name%+}" != "$name" ]; then
      name="${name%+}"
      printf -v "$name" '%s%s\n' "${!name}" "$OPTARG"
    else
      printf -v "$name" '%s' "$OPTARG"
    fi
  done
  LEXDYN_OPERANDS=("${@:OPTIND}")
}

# lexdyn_help USAGE: "usage: SCRIPT USAGE", then the script's header comment (the comment lines
# after the #! line, up to the first line that is not a comment).
lexdyn_help() {
  echo "usage: $0 $1"
  echo
  sed -n '2,${/^#/!q;s/^# \{0,1\}//;p}' "$0"
}

# lexdyn_help_option USAGE "$@": with -h or --help among the arguments (before a --), prints
# lexdyn_help USAGE and exits 0.
lexdyn_help_option() {
  local usage="$1" a
  shift
  for a in "$@"; do
    case "$a" in
      -h | --help) lexdyn_help "$usage"; exit 0 ;;
      --) return 0 ;;
    esac
  done
}

# lexdyn_positive_count PREFIX WHAT VALUE: exits 2 with "PREFIX: expected a positive number of
# WHAT, found 'VALUE'" unless VALUE is a positive integer.
lexdyn_positive_count() {
  [[ "$3" =~ ^[1-9][0-9]*$ ]] || { echo "$1: expected a positive number of $2, found '$3'" >&2; exit 2; }
}

# lexdyn_harness NAME [HINT]: HARNESS, the lexdyn-harness of $BUILD; exits 2 with
# "NAME: ... not built[HINT]" when it is not there.
lexdyn_harness() {
  HARNESS="$BUILD/bin/lexdyn-harness"
  [ -x "$HARNESS" ] || { echo "$1: $HARNESS not built${2:-}" >&2; exit 2; }
}

# lexdyn_cases [CASE ...]: CASES, the case files given, or the default pair (cases/stand.yaml and
# cases/squat_sway.yaml).
lexdyn_cases() {
  CASES=("$@")
  if [ ${#CASES[@]} -eq 0 ]; then CASES=("$ROOT/cases/stand.yaml" "$ROOT/cases/squat_sway.yaml"); fi
}

# lexdyn_golden_list MANIFEST [ID ...]: the runs of the golden manifest (all, or the IDs
# CASE.METHOD or CASE), one a line: ID CASE_FILE METHOD.
lexdyn_golden_list() {
  local manifest="$1" only=()
  shift
  if [ $# -gt 0 ]; then only=(--only "$(IFS=,; echo "$*")"); fi
  "$HARNESS" golden list --manifest "$manifest" "${only[@]}"
}

# lexdyn_each_comparison RUNS OUT FUNCTION: for every case of RUNS (lines ID CASE_FILE METHOD)
# that has method comparisons and at least two traces OUT/<id>/trace.csv, calls
# FUNCTION NAME CASE_FILE TRACE ... (NAME: the case file's name without .yaml).
lexdyn_each_comparison() {
  local runs="$1" out="$2" fn="$3" case_file id cf m traces
  cut -d' ' -f2 "$runs" | sort -u | while read -r case_file; do
    grep -q '^comparisons:' "$case_file" || continue
    traces=()
    while read -r id cf m; do
      [ "$cf" = "$case_file" ] && [ -f "$out/$id/trace.csv" ] && traces+=("$out/$id/trace.csv")
    done < "$runs"
    [ ${#traces[@]} -ge 2 ] || continue
    "$fn" "$(basename "$case_file" .yaml)" "$case_file" "${traces[@]}"
  done
}
