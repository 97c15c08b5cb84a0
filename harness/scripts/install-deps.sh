#!/usr/bin/env bash
# Installs every Debian package lexdyn needs. Idempotent: only missing packages are
# installed, and apt is not touched at all when nothing is missing.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
lexdyn_help_option "" "$@"

PACKAGES=(
  build-essential cmake ccache pkg-config
  libeigen3-dev libsimbody-dev libsundials-dev liburdfdom-dev
  libyaml-cpp-dev libcli11-dev nlohmann-json3-dev
  libgtest-dev libgmock-dev librapidcheck-dev libbenchmark-dev
  libgmp-dev
  # Meshes of robot descriptions (robot init, robot check; docs/model.md).
  libassimp-dev
  python3-numpy python3-matplotlib
  # The Python package's compiled module lexdyn._core (docs/python.md, "Bindings"), its
  # DataFrames and its tests (ctest python.*).
  pybind11-dev python3-pybind11 python3-dev python3-pandas python3-pytest
  # Sweeps on Slurm (docs/sweeps.md) and their test's own single-node cluster.
  slurm-wlm munge
  # The nightly report (docs/report.md): its scripts, its 3D replay and its browser test.
  python3-yaml python3-pil libjs-three chromium
  # Instruction profiles of a run (harness/scripts/profile-tick.sh, docs/performance.md).
  valgrind
  # The C++ style check (.clang-format; ctest test format_check).
  clang-format-14
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PACKAGES[@]} packages present"
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
$SUDO apt-get update -q
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
