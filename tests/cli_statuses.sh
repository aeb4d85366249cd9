#!/bin/sh
# Usage errors found once the scene is known still exit with status 2 and one line naming
# the file and the option: --resume of a missing file, a directory, a FIFO (refused, not
# waited on) or a dangling link; bdpt and vcm with a camera that has an aperture (they
# render the sun and the sky, which they once refused); a model file on which Assimp loops for ever (its import runs in a
# child process under a CPU-time limit, here 2 s).
# Usage: cli_statuses.sh TRAC0R_BINARY SCRATCH_DIR
set -u
. "$(dirname "$0")/common.sh"
SRC=$(cd "$(dirname "$0")/.." && pwd)
cli_begin "$1" "$2"

R="render --width 8 --height 8 --spp 1 --out r.png"
mkdir ckdir
mkfifo ckfifo
ln -s nowhere cklink
for ck in missing ckdir ckfifo cklink; do
    timeout 60 "$BIN" $R --resume $ck >/dev/null 2>err.txt
    rc=$?
    [ $rc -eq 2 ] || fail "--resume $ck: exit $rc, expected 2: $(cat err.txt)"
    grep -qF -- "--resume" err.txt || fail "--resume $ck: the message names no option: $(cat err.txt)"
    grep -qF "$ck" err.txt || fail "--resume $ck: the message names no file: $(cat err.txt)"
    [ -e r.png ] && fail "--resume $ck: wrote an image"
done

cat >lit.json <<'EOT'
{"version": 1,
 "camera": {"position": [0, 1, 3], "look_at": [0, 0, 0], "fov": 50},
 "materials": {"white": {"type": "diffuse", "color": [0.8, 0.8, 0.8]}},
 "shapes": [{"type": "quad", "material": "white",
             "vertices": [[-1, 0, -1], [1, 0, -1], [1, 0, 1], [-1, 0, 1]]}],
 "sun": {"direction": [0, 1, 0.2]},
 "environment": {"color": [0.2, 0.3, 0.5]}}
EOT
sed 's/"fov": 50}/"fov": 50, "aperture_radius": 0.05}/' lit.json >lens.json
for integ in bdpt vcm; do
    "$BIN" $R --scene lit.json --integrator $integ >/dev/null 2>err.txt
    rc=$?
    [ $rc -eq 0 ] || fail "$integ with a sun and a sky: exit $rc, expected 0: $(cat err.txt)"
    [ -s r.png ] || fail "$integ with a sun and a sky: no image"
    rm -f r.png
    "$BIN" $R --scene lens.json --integrator $integ >/dev/null 2>err.txt
    rc=$?
    [ $rc -eq 2 ] || fail "$integ with an aperture: exit $rc, expected 2: $(cat err.txt)"
    [ "$(wc -l <err.txt)" -eq 1 ] || fail "$integ with an aperture: not one line: $(cat err.txt)"
    grep -qF "lens.json" err.txt || fail "$integ: the message names no file: $(cat err.txt)"
    grep -qF "aperture_radius" err.txt || fail "$integ: the message names no key: $(cat err.txt)"
    [ -e r.png ] && fail "$integ with an aperture: wrote an image"
done

cp "$SRC/tests/data/hostile/importer/ply_loop.ply" loop.ply || fail "no ply_loop.ply"
TRAC0R_IMPORT_CPU_SECONDS=2 timeout 120 "$BIN" $R --scene loop.ply >/dev/null 2>err.txt
rc=$?
[ $rc -eq 2 ] || fail "a model Assimp loops on: exit $rc, expected 2: $(cat err.txt)"
[ "$(wc -l <err.txt)" -eq 1 ] || fail "a model Assimp loops on: not one line: $(cat err.txt)"
grep -qF "loop.ply" err.txt || fail "a model Assimp loops on: the message names no file: $(cat err.txt)"

cli_end cli_statuses
