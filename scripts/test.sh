#!/usr/bin/env bash
# The test command of the README and of CI: build, then run the whole suite with ctest.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/build.sh
cd build
ctest --output-on-failure -j"$(nproc)" --timeout 900
