#!/bin/sh
# Model files straight from the command line: `trac0r render` and `trac0r
# info` build a scene around a model in any format Assimp reads (Debian's
# assimp-testmodels): glTF 2.0 binary with its embedded texture, Collada with its camera,
# OBJ with textures beside it; --up z turns a model upright; --camera picks a camera or
# frames the model; a missing model, bad --up/--scale values and a camera the file lacks
# are one-line errors with exit status 2; the textured demo scene renders.
# Usage: cli_model.sh TRAC0R_BINARY SCRATCH_DIR
set -u
. "$(dirname "$0")/common.sh"
SRC=$(cd "$(dirname "$0")/.." && pwd)
cli_begin "$1" "$2"
M=/usr/share/assimp/models

for model in glTF2/BoxTextured-glTF-Binary/BoxTextured.glb Collada/duck.dae OBJ/spider.obj; do
    "$BIN" render "$M/$model" --width 32 --height 24 --spp 2 --out m.pfm 2>err.txt ||
        fail "render $model: $(cat err.txt)"
    [ -s m.pfm ] || fail "render $model: no image"
    rm -f m.pfm err.txt
done

# info: the material mapping (type and maps) and per-part bounds.
"$BIN" info "$M/glTF2/BoxTextured-glTF-Binary/BoxTextured.glb" >info.txt 2>err.txt ||
    fail "info BoxTextured.glb: $(cat err.txt)"
grep -q "^material 0 *principled, .*maps: base" info.txt ||
    fail "info BoxTextured.glb: no principled material with a base map: $(cat info.txt)"
grep -q "^part 0 .*bounds (-0.5, -0.5, -0.5) .. (0.5, 0.5, 0.5)" info.txt ||
    fail "info BoxTextured.glb: part bounds: $(cat info.txt)"
# --up z turns +z into +y: the duck's z extent becomes its y extent.
"$BIN" info "$M/Collada/duck.dae" >y.txt 2>/dev/null || fail "info duck.dae"
"$BIN" info "$M/Collada/duck.dae" --up z >z.txt 2>/dev/null || fail "info duck.dae --up z"
yb=$(grep '^bounds:' y.txt)
zb=$(grep '^bounds:' z.txt)
[ -n "$yb" ] && [ "$yb" != "$zb" ] || fail "--up z left the bounds as they were: $yb / $zb"
"$BIN" info "$M/Collada/duck.dae" --scale 2 >s.txt 2>/dev/null || fail "info duck.dae --scale 2"
[ "$(grep '^bounds:' s.txt)" != "$yb" ] || fail "--scale 2 left the bounds as they were"
rm -f info.txt err.txt y.txt z.txt s.txt

# The textured demo scene (scenes/textured-demo.json) with the models linked beside it:
# its textures, maps and materials load, and it renders.
mkdir demo
cp "$SRC/scenes/textured-demo.json" demo/
cp -r "$SRC/scenes/textures" demo/
ln -s "$M" demo/assimp-models
"$BIN" info demo/textured-demo.json >info.txt 2>&1 || fail "info textured-demo.json: $(cat info.txt)"
grep -q "^material 0 *principled, .*maps: base" info.txt || fail "demo floor: $(cat info.txt)"
grep -q "maps: base" info.txt && [ "$(grep -c 'maps: base' info.txt)" -ge 3 ] ||
    fail "demo: expected the floor's, the box's and the spider's maps: $(cat info.txt)"
"$BIN" render demo/textured-demo.json --width 16 --height 9 --spp 1 --out demo.png 2>err.txt ||
    fail "render textured-demo.json: $(cat err.txt)"
[ -s demo.png ] || fail "textured-demo.json: no image"
rm -rf demo demo.png info.txt err.txt

# A model's camera by name or number, or the framing one; one it lacks is an error.
"$BIN" info "$M/Collada/duck.dae" >cam.txt 2>/dev/null || fail "info duck.dae"
"$BIN" info "$M/Collada/duck.dae" --camera 0 >cam0.txt 2>/dev/null || fail "info --camera 0"
"$BIN" info "$M/Collada/duck.dae" --camera frame >frame.txt 2>/dev/null || fail "--camera frame"
[ "$(grep '^camera:' cam.txt)" = "$(grep '^camera:' cam0.txt)" ] || fail "--camera 0 is the first"
[ "$(grep '^camera:' cam.txt)" != "$(grep '^camera:' frame.txt)" ] || fail "--camera frame"
rm -f cam.txt cam0.txt frame.txt
expect_usage_error "duck.dae" render "$M/Collada/duck.dae" --camera 3 --out x.pfm
expect_usage_error "--camera" render "$M/Collada/duck.dae" --camera "" --out x.pfm
expect_usage_error "no-such-model.glb" render no-such-model.glb --width 8 --height 6 --out x.pfm
expect_usage_error "--up" render "$M/Collada/duck.dae" --up x --out x.pfm
expect_usage_error "--scale" render "$M/Collada/duck.dae" --scale 0 --out x.pfm
cli_end cli_model
