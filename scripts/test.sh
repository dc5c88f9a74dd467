#!/usr/bin/env bash
# The test command: set up, build with -Werror, run every Check suite and end-to-end test
# through CTest.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${BUILD_DIR:-build} scripts/setup.sh -DISPM_WERROR=ON
cd "${BUILD_DIR:-build}"
ctest --output-on-failure --timeout 900 "$@"
