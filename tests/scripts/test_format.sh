#!/bin/bash
# Every C++ source of the checkout is formatted as .clang-format says (clang-format 14, Debian's;
# harness/scripts/install-deps.sh installs it). To fix: clang-format-14 -i FILES.
set -u
src=$(cd "$(dirname "$0")/../.." && pwd)
cd "$src" || exit 1
if git rev-parse --is-inside-work-tree > /dev/null 2>&1; then
  mapfile -t files < <(git ls-files '*.cpp' '*.hpp')
else
  mapfile -t files < <(find lexdyn harness tests python -name '*.cpp' -o -name '*.hpp' | sort)
fi
if [ ${#files[@]} -lt 100 ]; then
  echo "FAIL: found only ${#files[@]} C++ files under $src"
  exit 1
fi
if ! out=$(clang-format-14 --dry-run --Werror "${files[@]}" 2>&1); then
  echo "$out" | grep -E '^[^ ].*: error:' | cut -d: -f1 | sort -u | sed 's/^/not formatted: /'
  echo "FAIL: run clang-format-14 -i on the files above (.clang-format)"
  exit 1
fi
echo "ok: ${#files[@]} C++ files formatted as .clang-format says"
