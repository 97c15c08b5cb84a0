# Sourced by the scripts that wrap lexdyn's tools: the one exit-code convention
# (docs/architecture.md, "Errors and exit codes") for a script that runs several of them.
#   0 pass; 1 a check, comparison or golden failed; 2 bad input; 3 run failure;
#   130 / 143 interrupted by SIGINT / SIGTERM.
# lexdyn_code CODE: a tool's exit status as one of these (a status the tools never give, e.g. a
# crash's 128 + SIGSEGV, is a run failure).
lexdyn_code() {
  case "$1" in
    0|1|2|3|130|143) echo "$1" ;;
    *) echo 3 ;;
  esac
}
# lexdyn_worse A B: the code that wins when a script's runs end with A and B: an interruption,
# then bad input, then a run failure, then a failed check, then a pass.
lexdyn_worse() {
  local a b r
  a=$(lexdyn_code "$1")
  b=$(lexdyn_code "$2")
  for r in 130 143 2 3 1; do
    if [ "$a" = "$r" ] || [ "$b" = "$r" ]; then echo "$r"; return; fi
  done
  echo 0
}
