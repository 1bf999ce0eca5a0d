#!/usr/bin/env bash
# The mutation run of tests/fuzz.rs at any size: every file kind slayer reads, mangled N times
# (default 100000), each case timed, the peak memory bounded; prints the counts.
#   tools/fuzz.sh [N]
set -euo pipefail
cd "$(dirname "$0")/.."
SLAYER_FUZZ_CASES="${1:-100000}" cargo test --release --test fuzz -- --nocapture
