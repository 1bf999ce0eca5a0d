#!/usr/bin/env bash
# The GPU path on the adapter this machine has (meant for a hardware GPU; lavapipe works, slowly):
# the GPU tests, then the same strokes through `slayer bench` with each choice of GPU options
# beside the CPU path, one line per run (ms per sample; submissions, read-backs, and the CPU's
# milliseconds submitting and waiting, per sample). docs/gpu.md says what the options do.
#
#   tools/gpu-check.sh                  # builds with cargo first
#   tools/gpu-check.sh --prebuilt DIR   # a machine without Rust: DIR holds `slayer` and the
#                                       # test binaries gpu_parity, gpu_backend, streaming, render
#
# STROKES (default 8) sets the strokes per bench run; LOG (default target/gpu-check) the folder
# where every run's whole output is kept.
set -uo pipefail
cd "$(dirname "$0")/.."

tests=(gpu_parity gpu_backend streaming render)
declare -A test_bin
if [ "${1:-}" = "--prebuilt" ]; then
    bin=${2:?"--prebuilt needs a folder"}
    for t in "${tests[@]}"; do test_bin[$t]="$bin/$t"; done
else
    bin=target/release
    cargo build --release --quiet || exit 1
    while IFS=$'\t' read -r name path; do
        test_bin[$name]=$path
    done < <(cargo test --release --no-run --message-format=json "${tests[@]/#/--test=}" 2>/dev/null |
        grep -o '"target":{[^}]*"name":"[a-z_]*"[^}]*}.*"executable":"[^"]*"' |
        sed -E 's/.*"name":"([a-z_]+)".*"executable":"([^"]+)".*/\1\t\2/')
fi
log=${LOG:-target/gpu-check}
mkdir -p "$log"
strokes=${STROKES:-8}

"$bin/slayer" adapters
failed=0
for t in "${tests[@]}"; do
    [ -x "${test_bin[$t]:-}" ] || { echo "gpu-check: no test binary for $t" >&2; failed=1; continue; }
    "${test_bin[$t]}" >"$log/$t.txt" 2>&1 || failed=1
    echo "$t: $(grep -E '^test result' "$log/$t.txt" | tail -1)"
    grep -E "panicked at|^    [a-z_:]+$" "$log/$t.txt" | head -20
done

# One bench run: its table row and its GPU calls line, under the options it ran with.
bench() {
    local scene=$1 backend=$2; shift 2
    local out="$log/bench-$scene-$backend-${*:-defaults}.txt"
    out=${out// /_}
    env "$@" "$bin/slayer" bench --scene "$scene" --strokes "$strokes" --backend "$backend" \
        >"$out" 2>&1 || { echo "$scene $backend ${*:-defaults}: failed (see $out)"; return; }
    local row calls
    row=$(grep -E "^$scene +[0-9]+ +[0-9]{4,} " "$out" | head -1 | awk '{print $(NF-3)}')
    calls=$(grep -o "[0-9.]* submissions and [0-9.]* blocking read-backs per sample ([^)]*)" "$out")
    printf '%-8s %-4s %-45s %8s ms/sample  %s\n' "$scene" "$backend" "${*:-defaults}" "$row" "$calls"
}

# Fills the driver's shader cache first, so that no row below pays its first compile (lavapipe
# compiles at the first dispatch, seconds with a cold cache).
"$bin/slayer" bench --scene plaster --strokes 1 --backend gpu >/dev/null 2>&1
for scene in plaster plane; do
    bench "$scene" cpu
    bench "$scene" gpu
    bench "$scene" gpu SLAYER_GPU_RUN_AHEAD=0
    bench "$scene" gpu SLAYER_GPU_PROXIMITY=0
    bench "$scene" gpu SLAYER_GPU_AHEAD=0 SLAYER_GPU_RUN_AHEAD=0
done
exit $failed
