#!/usr/bin/env bash
# Builds rotorid twice and runs every test: a Release build, then a Debug build of our code with
# -fsanitize=address,undefined. Exits non-zero on the first failure.
set -euo pipefail
cd "$(dirname "$0")/.."
JOBS=${JOBS:-$(nproc)}

cmake -S . -B build/release -DCMAKE_BUILD_TYPE=Release
cmake --build build/release -j"$JOBS"
ctest --test-dir build/release --output-on-failure -j"$JOBS" --timeout 900

cmake -S . -B build/asan -DCMAKE_BUILD_TYPE=Debug -DROTORID_SANITIZE=ON -DROTORID_BUILD_BENCHMARKS=OFF
cmake --build build/asan -j"$JOBS"
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ctest --test-dir build/asan --output-on-failure -j"$JOBS" --timeout 1800
