#!/usr/bin/env bash
# The sLayer paper's Fig. 5, told with slayer's layer tools: a plain surface, patches drawn on
# it, the bottom layer pushed up against them, the patches cut, the pieces lifted and the
# smallest deleted. Each step is a session file (with the whole history) and a PNG.
#
#   tools/story.sh [OUT_FOLDER] [TRIANGLES]     (default: slayer-story, 40000)
#
# Every tool prints its own time; at 640K triangles: tools/story.sh story-640k 640000
set -euo pipefail

out=${1:-slayer-story}
triangles=${2:-40000}
slayer=${SLAYER:-target/release/slayer}
if [[ ! -x $slayer ]]; then
    cargo build --release
fi
mkdir -p "$out"
cd "$out"
slayer=$(cd "$OLDPWD" && realpath "$slayer")

render() {
    "$slayer" render "$1.slayer" -o "$1.png" --size 800x600 --camera -25,40,0.8 --up z >/dev/null
}

# Closed outlines on the plane (it spans [0, 1]² at z = 0): three rounded patches.
outline() { # centre x, centre y, radius
    local points=""
    for k in $(seq 0 12); do
        points+=$(awk -v x="$1" -v y="$2" -v r="$3" -v k="$k" 'BEGIN {
            a = k / 12 * 6.2831853; s = 1 + 0.15 * cos(4 * a)
            printf "{\"position\": [%.5f, %.5f, 0]}", x + r * s * cos(a), y + r * s * sin(a) }')
        [[ $k -lt 12 ]] && points+=","
    done
    echo "{\"brush\": \"draw\", \"radius\": 0.05, \"strength\": 0.5, \"layers\": [0], \"samples\": [$points]}"
}
line() { # x0 y0 x1 y1 brush radius strength layers
    echo "{\"brush\": \"$5\", \"radius\": $6, \"strength\": $7, \"layers\": $8, \"samples\": [{\"position\": [$1, $2, 0]}, {\"position\": [$3, $4, 0]}]}"
}

echo "{\"version\": 1, \"strokes\": [$(outline 0.3 0.3 0.14), $(outline 0.7 0.32 0.12), $(outline 0.48 0.7 0.16)]}" >patches.json
echo "{\"version\": 1, \"strokes\": [$(line 0.2 0.3 0.4 0.3 draw 0.12 0.8 '["plane"]'), $(line 0.4 0.68 0.56 0.72 draw 0.14 0.8 '["plane"]')]}" >push.json
echo "{\"version\": 1, \"strokes\": [$(line 0.12 0.22 0.48 0.38 draw 0.05 0.5 '[1]'), $(line 0.58 0.2 0.82 0.44 draw 0.05 0.5 '[2]'), $(line 0.34 0.56 0.62 0.84 draw 0.05 0.5 '[3]')]}" >cuts.json
echo "{\"version\": 1, \"strokes\": [$(line 0.36 0.74 0.40 0.8 draw 0.09 1.0 '[3]'), $(line 0.30 0.22 0.36 0.18 draw 0.07 1.0 '[1]')]}" >lift.json

echo "1. a plain surface"
"$slayer" scene plane --triangles "$triangles" -o 1-plain.slayer
render 1-plain
echo "2. patches drawn on it (closed strokes, Coons patches lifted two edges)"
"$slayer" layer patch 1-plain.slayer -o 2-patches.slayer --strokes patches.json --layer plane --material paint
render 2-patches
echo "3. the bottom layer pushed up against the patches"
"$slayer" sculpt --input 2-patches.slayer --strokes push.json --output 3-pushed.slayer --backend cpu
render 3-pushed
echo "4. the patches cut"
"$slayer" layer cut 3-pushed.slayer -o 4-cut.slayer --strokes cuts.json --layers 1,2,3
render 4-cut
echo "5. pieces lifted, the smallest deleted"
"$slayer" sculpt --input 4-cut.slayer --strokes lift.json --output 5a-lifted.slayer --backend cpu
"$slayer" layer delete 5a-lifted.slayer -o 5-deleted.slayer --smallest 1
render 5-deleted
"$slayer" check 5-deleted.slayer | tail -4
"$slayer" history 5-deleted.slayer
