#!/usr/bin/env bash
# The GPU scaling figures: `slayer bench --backend both` on plaster at 1M, 4M and 16M faces (or
# the sizes given), each run's table and JSON written to OUT_DIR, with the adapter list first.
# Meant for a machine with a hardware GPU (on lavapipe 16M faces takes hours).
#
#   tools/gpu_bench.sh OUT_DIR [FACES ...]
#
# SLAYER names a built binary (default target/release/slayer, built when missing); STROKES the
# strokes per scene (default 8: enough samples for ms/sample, minutes at 16M on the CPU path).
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:?usage: tools/gpu_bench.sh OUT_DIR [FACES ...]}
shift
sizes=("$@")
[ ${#sizes[@]} -gt 0 ] || sizes=(1000000 4000000 16000000)
bin=${SLAYER:-target/release/slayer}
[ -x "$bin" ] || cargo build --release --quiet
mkdir -p "$out"
"$bin" adapters | tee "$out/adapters.txt"
for faces in "${sizes[@]}"; do
    echo "tools/gpu_bench.sh: plaster at $faces faces"
    "$bin" bench --scene plaster --triangles "$faces" --backend both --strokes "${STROKES:-8}" \
        --json "$out/plaster_$faces.json" 2>&1 | tee "$out/plaster_$faces.txt"
done
