#!/usr/bin/env bash
# Installs lexdyn from BUILD_DIR into a fresh prefix under WORK and checks what a user of
# find_package(lexdyn) gets:
#   1. only public headers: nothing under a detail/ directory, no header of the library's internals;
#   2. every installed header compiles on its own (nothing it needs was left out);
#   3. a consumer project (consumer/) configures with find_package(lexdyn), builds, and runs: it
#      solves a two-level problem and runs controller ticks on the point mass;
#   4. the lexdyn Python package is installed (LEXDYN_PYTHON_INSTALL_DIR, every module of
#      python/lexdyn, and the compiled lexdyn._core unless LEXDYN_BUILD_PYTHON_BINDINGS is off)
#      and, imported from there, reads a golden trace and solves a problem.
# Usage: install_test.sh BUILD_DIR SOURCE_DIR CXX WORK
set -euo pipefail
BUILD="$1"; SRC="$2"; CXX="$3"; WORK="$4"
rm -rf "$WORK"
mkdir -p "$WORK"
PREFIX="$WORK/prefix"
cmake --install "$BUILD" --prefix "$PREFIX" > "$WORK/install.log"
INC="$PREFIX/include"
[ -d "$INC/lexdyn" ] || { echo "install_test: no headers under $INC/lexdyn" >&2; exit 1; }

# 1. Only public headers.
bad=$(cd "$INC" && find lexdyn -path '*/detail/*' -o -name 'hls_factorization.hpp' -o -name 'yaml_strict.hpp' -o -name 'input_text.hpp' | sort)
if [ -n "$bad" ]; then echo "install_test: internal headers installed:" >&2; echo "$bad" >&2; exit 1; fi
mapfile -t headers < <(cd "$INC" && find lexdyn -name '*.hpp' | sort)
echo "install_test: ${#headers[@]} headers installed"
[ ${#headers[@]} -ge 10 ] || { echo "install_test: too few headers installed" >&2; exit 1; }

# 2. Each header on its own, against the installed tree and Eigen only (two at a time).
printf '%s\n' "${headers[@]}" > "$WORK/headers.txt"
export INC CXX WORK
compile_one() {
  local h="$1" log
  log="$WORK/header-$(echo "$h" | tr '/' '_').log"
  if ! printf '#include <%s>\n#include <%s>\nint main() { return 0; }\n' "$h" "$h" |
      "$CXX" -std=c++17 -fsyntax-only -Wall -Wextra -Werror -I"$INC" -I/usr/include/eigen3 -x c++ - > "$log" 2>&1; then
    echo "install_test: $h does not compile on its own:" >&2
    head -20 "$log" >&2
    return 1
  fi
}
export -f compile_one
xargs -a "$WORK/headers.txt" -P 2 -I{} bash -c 'compile_one "$@"' _ {}
echo "install_test: every installed header compiles on its own (included twice)"

# 3. A consumer project.
cmake -S "$SRC/tests/packaging/consumer" -B "$WORK/consumer" -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$PREFIX" \
  -DCMAKE_CXX_COMPILER="$CXX" > "$WORK/consumer-configure.log" 2>&1 || { cat "$WORK/consumer-configure.log" >&2; exit 1; }
cmake --build "$WORK/consumer" -j 2 > "$WORK/consumer-build.log" 2>&1 || { tail -40 "$WORK/consumer-build.log" >&2; exit 1; }
"$WORK/consumer/lexdyn_consumer" "$SRC/models/point_mass/point_mass.urdf" "$SRC/models/point_mass/point_mass.yaml"

# 4. The Python package.
PYDIR="$(sed -n 's/^LEXDYN_PYTHON_INSTALL_DIR:[A-Z]*=//p' "$BUILD/CMakeCache.txt")"
case "$PYDIR" in /*) ;; *) PYDIR="$PREFIX/$PYDIR" ;; esac
for f in "$SRC"/python/lexdyn/*.py; do
  [ -f "$PYDIR/lexdyn/$(basename "$f")" ] || { echo "install_test: $PYDIR/lexdyn/$(basename "$f") not installed" >&2; exit 1; }
done
BINDINGS="$(sed -n 's/^LEXDYN_BUILD_PYTHON_BINDINGS:[A-Z]*=//p' "$BUILD/CMakeCache.txt")"
case "$BINDINGS" in OFF|off|0|FALSE|false|NO|no) BINDINGS=0 ;; *) BINDINGS=1 ;; esac
if [ "$BINDINGS" = 1 ] && ! ls "$PYDIR"/lexdyn/_core.*so > /dev/null 2>&1; then
  echo "install_test: $PYDIR/lexdyn/_core.*.so (the compiled module) not installed" >&2; exit 1
fi
golden="$(ls "$SRC"/golden/*.csv | head -1)"
(cd "$WORK" && env PYTHONPATH="$PYDIR" /usr/bin/python3 -c '
import os, sys
import lexdyn
where = os.path.dirname(os.path.abspath(lexdyn.__file__))
assert where == os.path.join(sys.argv[1], "lexdyn"), where
tr = lexdyn.read_trace(sys.argv[2])
assert tr.rows > 0 and tr.names[0] == "t" and tr.ended, sys.argv[2]
print(f"install_test: lexdyn (Python) imported from {where}: {os.path.basename(sys.argv[2])} {tr.rows} rows")
if sys.argv[3] == "1":
    assert lexdyn.BINDINGS and os.path.dirname(os.path.abspath(lexdyn._core.__file__)) == where, "lexdyn._core"
    r = lexdyn.solve(lexdyn.Problem(2, [([[1.0, 1.0]], [1.0], [1.0]), ([[1.0, -1.0]], [0.0], [0.0])]))
    assert r.status == "solved" and list(r.x) == [0.5, 0.5], (r.status, r.x)
    print(f"install_test: lexdyn._core imported from {where}: a two-level problem solved")
' "$PYDIR" "$golden" "$BINDINGS")
