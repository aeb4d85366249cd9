#!/bin/sh
# The hostile-input corpus (tests/data/hostile/): scene files, model files and images as
# an attacker or an unlucky user would hand them to trac0r. Every input gets a time limit,
# and must end in a refusal (exit status 1 or 2, one line on stderr naming the input),
# never a crash, a hang, a sanitizer report (the sanitize preset runs this too) or an
# output file. New kinds of hostile input go into the corpus, not into this script.
# Usage: cli_hostile.sh TRAC0R_BINARY SCRATCH_DIR
set -u
. "$(dirname "$0")/common.sh"
SRC=$(cd "$(dirname "$0")/.." && pwd)
H=$SRC/tests/data/hostile
cli_begin "$1" "$2"
LIMIT=20
[ -n "${ASAN_OPTIONS:-}" ] && LIMIT=60

# refused WHAT RC: RC is a refusal (1 or 2), the message is one line, nothing written.
refused() {
    case $2 in
    1 | 2) ;;
    124) fail "$1: still running after $LIMIT s" ;;
    *) fail "$1: exit $2, expected 1 or 2: $(head -c 400 err.txt)" ;;
    esac
    [ "$(wc -l <err.txt)" -eq 1 ] || fail "$1: expected one stderr line: $(head -c 400 err.txt)"
    left=$(ls -A | grep -v -e '^err.txt$' -e '^out.txt$' -e '^ref.pfm$' -e '^s.json$' -e '^models.txt$' -e '^many_values.json$')
    [ -z "$left" ] || fail "$1: left files: $left"
}

count=0
# Scene files: render refuses each; info may describe one (a warning is enough), but must
# not crash or hang either.
big=$PWD/many_values.json
awk 'BEGIN { printf "{\"shapes\": ["; for (i = 0; i < 2200000; ++i) printf "0,"; print "0]}" }' \
    >"$big"
for f in "$H"/scenes/*.json "$big"; do
    timeout $LIMIT "$BIN" render "$f" --width 8 --height 8 --spp 1 --out out.pfm >out.txt 2>err.txt
    refused "render $f" $?
    timeout $LIMIT "$BIN" info "$f" >out.txt 2>err.txt
    rc=$?
    [ "$rc" -le 2 ] || fail "info $f: exit $rc: $(head -c 400 err.txt)"
    count=$((count + 1))
done
rm -f "$big"

# Model files, each named by a scene file of its own.
find "$H/models" -type f \( -name '*.obj' -o -name '*.ply' -o -name '*.gltf' -o -name '*.glb' \
    -o -name '*.stl' \) | sort >models.txt
while read -r m; do
    printf '{"camera": {"position": [0, 0, -3], "look_at": [0, 0, 0], "fov": 60},
 "materials": {"lamp": {"type": "emitter", "color": [1, 1, 1], "emittance": 1}},
 "shapes": [{"type": "plane", "material": "lamp"}],
 "meshes": [{"path": "%s"}]}\n' "$m" >s.json
    timeout $LIMIT "$BIN" info s.json >out.txt 2>err.txt
    refused "model $m" $?
    count=$((count + 1))
done <models.txt
rm -f models.txt s.json

# Images given to compare, as the image and as the reference.
"$BIN" render --width 8 --height 8 --spp 1 --out ref.pfm >/dev/null 2>&1 || fail "no reference"
for f in "$H"/images/*; do
    timeout $LIMIT "$BIN" compare "$f" ref.pfm >out.txt 2>err.txt
    refused "compare $f" $?
    timeout $LIMIT "$BIN" compare ref.pfm "$f" >out.txt 2>err.txt
    refused "compare (reference) $f" $?
    count=$((count + 1))
done
rm -f ref.pfm out.txt err.txt
[ "$count" -ge 25 ] || fail "only $count corpus inputs ran"
echo "cli_hostile: $count inputs"
cli_end cli_hostile
