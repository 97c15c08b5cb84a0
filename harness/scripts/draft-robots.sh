#!/usr/bin/env bash
# Re-drafts the data files and cases of the repository's robots that come in through
# `lexdyn-harness robot init` (docs/model.md, "Bringing your own robot"), as a user would:
#   cases/g1_like/     from models/g1_like/urdf/g1_like.urdf and its SRDF
#   cases/panda_like/  from models/panda_like/urdf/panda_like.urdf and its SRDF
#   cases/quadruped_like/ from models/quadruped_like/urdf/quadruped_like.urdf and its SRDF
# Each folder is replaced. Afterwards regenerate their goldens (golden-update.sh g1_like_stand ...)
# and review `git diff cases/`.
#
# Usage: harness/scripts/draft-robots.sh [-b BUILD_DIR]
# Exit codes (harness/scripts/exit-codes.sh): 0 every robot drafted, 2 bad input, 3 a failure.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
BUILD="$ROOT/build"
lexdyn_options "[-b BUILD_DIR]" b=BUILD -- "$@"
lexdyn_harness draft-robots " (cmake --build $BUILD)"
cd "$ROOT"
for robot in g1_like panda_like quadruped_like; do
  rm -rf "cases/$robot"
  "$HARNESS" robot init "models/$robot/urdf/$robot.urdf" --srdf "models/$robot/srdf/$robot.srdf" --out "cases/$robot"
done
