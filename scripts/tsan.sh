#!/usr/bin/env bash
# The test suite under ThreadSanitizer (issue #5): builds build-tsan/ and runs every test with
# 2 threads or more where the test asks for them. Any report fails the run (exit status 66).
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${BUILD_TSAN:-build-tsan}
cmake -S . -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DBOUNCE_SANITIZE=thread -DBOUNCE_BUILD_BENCH=OFF -DBOUNCE_BUILD_PYTHON=OFF >/dev/null
cmake --build "$BUILD" -j "$(nproc)"
export TSAN_OPTIONS="suppressions=$PWD/tests/tsan.supp halt_on_error=1 second_deadlock_stack=1"
ctest --test-dir "$BUILD" --output-on-failure -j "$(nproc)" --timeout 900
