#!/usr/bin/env bash
# Set up (Debian 12: installs missing packages), build in build/, and run every test except the
# `bench` label. Extra arguments go to ctest, e.g. `tools/test.sh -L unit` or `tools/test.sh -R scene`.
# Benchmarks: ctest --test-dir build -L bench
set -euo pipefail

# shellcheck source=tools/setup.sh
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"

mesopen_install
mesopen_build

cd "$MESOPEN_ROOT"
# The sources are formatted by .clang-format: a difference fails the run (fix: `ninja -C build format`).
mapfile -t sources < <(find grid targets parallel fem coupling run tools tests -name '*.[ch]pp' | sort)
clang-format --dry-run --Werror "${sources[@]}"
# The default run must find tests: an empty run is a failure, not a pass.
no_tests=()
if [ "$#" -eq 0 ]; then
  no_tests=(--no-tests=error)
fi
ctest --test-dir build --output-on-failure --timeout 900 -j "$(nproc)" -LE bench "${no_tests[@]}" "$@"
