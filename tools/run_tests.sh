#!/usr/bin/env bash
# The test command: installs what is missing, builds, runs the whole CTest
# suite (unit, verification, regression, MPI and bad-input tests).
set -euo pipefail
top=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
bash "$top/tools/install_deps.sh"
bash "$top/tools/build.sh"
cd "$top/build"
ctest --output-on-failure --timeout 900 -j "$(nproc)" "$@"
