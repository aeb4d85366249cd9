#!/bin/sh
# Scene files through the trac0r binary: every bad file in tests/data/bad/ gives one line
# naming the file and the line:column or JSON path at fault, exit status 2 and no output
# file, for `render` and `info`; the scene files in scenes/ load and render; the
# thesis's scene file renders bit-identical to the built-in scene; a file's render
# defaults apply unless the command line overrides them.
# Usage: cli_scene.sh TRAC0R_BINARY SCRATCH_DIR
set -u
. "$(dirname "$0")/common.sh"
SRC=$(cd "$(dirname "$0")/.." && pwd)
BAD=$SRC/tests/data/bad
GOOD=$SRC/tests/data/good
cli_begin "$1" "$2"

# expect_bad FILE NEEDLE [EXTRA ARGS]: render and info both exit 2 with one stderr line
# that names the file and contains NEEDLE; render writes nothing.
expect_bad() {
    file=$BAD/$1
    needle=$2
    shift 2
    "$BIN" render "$file" --width 8 --height 6 --spp 1 --out out.pfm "$@" >stdout.txt 2>err.txt
    rc=$?
    [ "$rc" -eq 2 ] || fail "render $file: exit $rc, expected 2: $(cat err.txt)"
    [ "$(wc -l <err.txt)" -eq 1 ] || fail "render $file: expected one stderr line: $(cat err.txt)"
    grep -qF -- "$file" err.txt || fail "render $file: message does not name the file: $(cat err.txt)"
    grep -qF -- "$needle" err.txt || fail "render $file: stderr lacks '$needle': $(cat err.txt)"
    [ ! -e out.pfm ] || fail "render $file: wrote out.pfm"
    leftovers=$(ls -A | grep -v -e '^stdout.txt$' -e '^err.txt$')
    [ -z "$leftovers" ] || fail "render $file: left files behind: $leftovers"
    rm -f stdout.txt err.txt
}

# expect_bad_info FILE NEEDLE: the same for `trac0r info`.
expect_bad_info() {
    file=$BAD/$1
    "$BIN" info "$file" >stdout.txt 2>err.txt
    rc=$?
    [ "$rc" -eq 2 ] || fail "info $file: exit $rc, expected 2"
    [ "$(wc -l <err.txt)" -eq 1 ] || fail "info $file: expected one stderr line: $(cat err.txt)"
    grep -qF -- "$2" err.txt || fail "info $file: stderr lacks '$2': $(cat err.txt)"
    [ ! -s stdout.txt ] || fail "info $file: printed to stdout"
    rm -f stdout.txt err.txt
}

check() {
    expect_bad "$@"
    expect_bad_info "$@"
}

# JSON syntax: FILE:LINE:COLUMN.
check syntax.json "syntax.json:3:28: JSON syntax error at the end of the line, after '[0, 0, 0],,'"
check nul_byte.json "nul_byte.json:2:13: JSON syntax error: a NUL byte"
check nan.json "nan.json:2:65: JSON syntax error near 'NaN}'"
check empty.json "empty.json:1:1: JSON syntax error at the end of the file"
check trailing.json "trailing.json:2:1: JSON syntax error: text after the top-level value"
check not_object.json "expected a JSON object at the top level, got an array"
# Wrong types, unknown and duplicate keys, missing fields.
check wrong_type.json ": camera.fov: expected a vertical field of view in (0, 180) degrees, got a string"
check wrong_type_vec.json ": camera.position[1]: expected a number, got a string"
check unknown_key.json ": camera.postion: unknown key (did you mean 'position'?)"
check unknown_key_far.json ": zzzzzz: unknown key (expected one of: version, description, render, camera, materials, shapes, meshes, environment, sun, lights, prototypes, instances)"
check duplicate_key.json ": camera.position: duplicate key"
check missing_field.json ": camera.position: missing (expected [x, y, z])"
check missing_camera.json ": camera: missing (expected an object)"
check missing_ior.json ": materials.glass.ior: missing (expected a number in [1, 10])"
check version.json ": version: expected 1"
# Materials and references to them.
check duplicate_material.json ": materials.a: duplicate material name"
check ior_range.json ": materials.glass.ior: expected a number in [1, 10], got 0.5"
check material_type.json ": materials.glass.type: unknown material type 'glas' (did you mean 'glass'?)"
check material_key.json ": materials.white.roughness: unknown key (expected one of: type, color, texture,"
check color_range.json ": materials.white.color[1]: expected a number in [0, 1], got 1.5"
check undefined_material.json ": shapes[0].material: undefined material 'whit' (did you mean 'white'?)"
check mesh_material.json ": meshes[0].material: undefined material 'lamb' (did you mean 'lamp'?)"
check shape_type.json ": shapes[0].type: unknown shape type 'bx' (did you mean 'box'?)"
# Coordinates, sizes, the camera.
check inf_coord.json ": shapes[0].position[1]: expected a finite number with |x| <= 1e+07, got inf"
check huge_coord.json ": shapes[0].position[0]: expected a finite number with |x| <= 1e+07, got 2e+07"
check huge_after_transform.json ": shapes[0]: a vertex lands at (1.4e+07, -5e+06, -5e+06), outside the bound |x| <= 1e+07"
check zero_size.json ": shapes[0].scale[1]: expected a positive number, got 0"
check negative_size.json ": shapes[0].scale: expected a positive number up to 1e+07, got -2"
check degenerate_quad.json ": shapes[2].vertices: the corners span a triangle of zero area"
check fov_180.json ": camera.fov: expected a vertical field of view in (0, 180) degrees, got 180"
check fov_zero.json ": camera.fov: expected a vertical field of view in (0, 180) degrees, got 0"
check look_at_position.json ": camera.look_at: must differ from camera.position"
check look_and_direction.json ": camera: expected exactly one of 'look_at' and 'direction', got both"
check handedness.json ": camera.handedness: expected \"left\" or \"right\", got 'up'"
# Triangle budget.
check subdivisions.json ": shapes[2].subdivisions: expected an integer in 0..9 (20*4^N triangles), got 10"
check budget.json ": shapes[5]: the scene would have more than 16777216 triangles"
check no_shapes.json ": the scene has no triangles"
# Render defaults.
check accel.json ": render.accel: unknown acceleration structure 'bhv' (expected bvh, flat, embree or bvh2; did you mean 'bvh'?)"
check integrator.json ": render.integrator: unknown integrator 'magic' (available: pt, naive, bdpt, vcm)"
# Meshes.
check missing_mesh.json ": meshes[0].path: cannot open '$BAD/no-such-model.obj': No such file or directory"
check unreadable_mesh.json ": meshes[0].path: cannot open '$BAD/.': not a regular file (a directory)"
check assimp_fails.json ": meshes[0].path: Assimp cannot read '$BAD/garbage.ply'"
check nan_mesh.json ": meshes[0].path: '$BAD/nan_vertex.obj': mesh vertex 2 has a non-finite coordinate"
check huge_mesh.json ": meshes[0]: a vertex lands at (1e+30, 1, 0), outside the bound |x| <= 1e+07"
# Textures: unreadable or undecodable images and bad keys are errors.
check texture_missing.json ": materials.tex.texture: $BAD/../texture/no-such-texture.png: cannot open"
check texture_truncated.json ": materials.tex.texture: '$BAD/../texture/truncated.png'"
check texture_zero.json ": materials.tex.texture: '$BAD/../texture/zero.png'"
check texture_huge.json ": materials.tex.texture: '$BAD/../texture/huge.png'"
check texture_not_image.json ": materials.tex.texture: '$BAD/../texture/not_image.png'"
check texture_wrap.json ": materials.tex.texture.wrap: unknown wrap mode 'mirror'"
"$BIN" render "$GOOD/textured_quad.json" --width 8 --height 4 --spp 1 --out tq.pfm 2>err.txt ||
    fail "render textured_quad.json: $(cat err.txt)"
rm -f tq.pfm err.txt
check up_parallel.json ": camera: camera up vector is parallel to the view direction"
# A good mesh: its dropped faces are a warning on stderr, the render goes on.
"$BIN" render "$GOOD/mesh.json" --width 8 --height 6 --spp 1 --out mesh.pfm 2>err.txt ||
    fail "render mesh.json: $(cat err.txt)"
grep -qF "warning: $GOOD/mesh.json: meshes[0] (../mesh/tri.obj): 2 degenerate faces dropped" err.txt ||
    fail "mesh.json: no warning about dropped faces: $(cat err.txt)"
[ -s mesh.pfm ] || fail "mesh.json: no image"
"$BIN" info "$GOOD/mesh.json" >info.txt 2>&1 || fail "info mesh.json: $(cat info.txt)"
grep -qF "triangles:  19 (5 from 1 mesh file in 4 parts, 2 degenerate faces dropped)" info.txt ||
    fail "info mesh.json: $(cat info.txt)"
grep -qF "emitters:   2 materials, 3 triangles" info.txt || fail "info mesh.json: $(cat info.txt)"
rm -f mesh.pfm err.txt info.txt
# No emitter: render refuses unless told, info warns.
expect_bad no_emitter.json ": the scene has no emitter, so the image would be black"
"$BIN" info "$BAD/no_emitter.json" >info.txt 2>&1 || fail "info no_emitter.json failed"
grep -qF "warning: the scene has no emitter" info.txt || fail "info no_emitter.json: no warning: $(cat info.txt)"
"$BIN" render "$BAD/no_emitter.json" --allow-dark --width 8 --height 6 --spp 1 --out dark.pfm 2>err.txt ||
    fail "render --allow-dark failed: $(cat err.txt)"
[ -s dark.pfm ] || fail "render --allow-dark wrote nothing"
"$BIN" render "$GOOD/dark_allowed.json" --width 8 --height 6 --spp 1 --out dark2.pfm 2>err.txt ||
    fail "render dark_allowed.json failed: $(cat err.txt)"
grep -q "no emitter" err.txt && fail "dark_allowed.json: unexpected warning: $(cat err.txt)"
rm -f info.txt err.txt dark.pfm dark2.pfm

# Render defaults from the file (24x16, 2 spp) unless the command line overrides them.
"$BIN" render "$GOOD/defaults.json" --out d.pfm 2>err.txt || fail "defaults.json: $(cat err.txt)"
[ "$(head -c 9 d.pfm | tail -c 6)" = "24 16
" ] || [ "$(sed -n 2p d.pfm)" = "24 16" ] || fail "defaults.json: image is not 24x16: $(sed -n 2p d.pfm)"
grep -qF "24x16, 2 spp" err.txt || fail "defaults.json: summary lacks '24x16, 2 spp': $(cat err.txt)"
grep -qF ", flat: " err.txt || fail "defaults.json: render.accel flat not applied: $(cat err.txt)"
"$BIN" render --width 10 --spp 1 "$GOOD/defaults.json" --accel bvh --out d.pfm 2>err.txt ||
    fail "defaults.json with overrides: $(cat err.txt)"
# --width alone keeps the file's 24x16 shape: 10 x 16 * 10 / 24 = 6.7 -> 7.
grep -qF "10x7, 1 spp" err.txt || fail "defaults.json: --width/--spp did not override: $(cat err.txt)"
grep -qF "bvh (" err.txt || fail "defaults.json: --accel did not override: $(cat err.txt)"
"$BIN" render --height 8 --spp 1 "$GOOD/defaults.json" --out d.pfm 2>err.txt ||
    fail "defaults.json --height 8: $(cat err.txt)"
grep -qF "12x8, 1 spp" err.txt || fail "defaults.json: --height alone lost the aspect: $(cat err.txt)"
"$BIN" render --width 40 --height 10 --spp 1 "$GOOD/defaults.json" --out d.pfm 2>err.txt ||
    fail "defaults.json 40x10: $(cat err.txt)"
grep -qF "40x10, 1 spp" err.txt || fail "defaults.json: both sides given not kept: $(cat err.txt)"
# A built-in scene's 800x600 default keeps its shape too.
"$BIN" render --width 40 --spp 1 --out d.pfm 2>err.txt || fail "--width 40: $(cat err.txt)"
grep -qF "40x30, 1 spp" err.txt || fail "builtin --width alone lost the aspect: $(cat err.txt)"
rm -f d.pfm err.txt

# The thesis's scene file renders bit-identical to the built-in scene, with either integrator
# (pt reads the lamp's two_sided flag) and with the file's own default integrator.
for run in "bvh naive" "flat naive" "bvh pt" "flat pt" "bvh"; do
    set -- $run
    accel=$1
    integ=${2:+--integrator $2}
    "$BIN" render --scene cornell --width 40 --height 30 --spp 3 --seed 7 --accel $accel $integ \
        --out builtin.pfm 2>/dev/null || fail "render builtin cornell failed"
    "$BIN" render "$SRC/scenes/cornell-thesis.json" --width 40 --height 30 --spp 3 --seed 7 \
        --accel $accel $integ --out file.pfm 2>/dev/null || fail "render cornell-thesis.json failed"
    cmp -s builtin.pfm file.pfm || fail "cornell-thesis.json ($run) differs from builtin:cornell"
    rm -f builtin.pfm file.pfm
done
# A bare built-in name still means the built-in scene.
"$BIN" render cornell --width 8 --height 6 --spp 1 --out bare.pfm 2>/dev/null || fail "render cornell failed"
rm -f bare.pfm
"$BIN" render nosuch --width 8 --height 6 --spp 1 --out bare.pfm 2>err.txt
[ $? -eq 2 ] && grep -qF "unknown built-in scene 'nosuch'" err.txt || fail "render nosuch: $(cat err.txt)"
[ ! -e bare.pfm ] || fail "render nosuch wrote an image"
rm -f err.txt

# info on the scenes in scenes/.
"$BIN" info "$SRC/scenes/cornell-thesis.json" >info.txt || fail "info cornell-thesis.json failed"
grep -qF "triangles:  676 " info.txt || fail "cornell-thesis: $(cat info.txt)"
grep -qF "emitters:   1 material, 2 triangles" info.txt || fail "cornell-thesis: $(cat info.txt)"
grep -qF "warnings:   0" info.txt || fail "cornell-thesis: $(cat info.txt)"
"$BIN" info "$SRC/scenes/cornell-classic.json" >info.txt || fail "info cornell-classic.json failed"
grep -qF "bounds:     (0, 0, 0) .. (556, 548.8, 559.2)" info.txt || fail "cornell-classic: $(cat info.txt)"
grep -qF "triangles:  32 " info.txt || fail "cornell-classic: $(cat info.txt)"
# The real-time bench's hard scenes load without warnings and render.
"$BIN" info "$SRC/scenes/lamps-pillars.json" >info.txt || fail "info lamps-pillars.json failed"
grep -qF "emitters:   48 materials, 96 triangles" info.txt || fail "lamps-pillars: $(cat info.txt)"
grep -qF "warnings:   0" info.txt || fail "lamps-pillars: $(cat info.txt)"
"$BIN" info "$SRC/scenes/window-room.json" >info.txt || fail "info window-room.json failed"
grep -qF "sun:" info.txt || fail "window-room: $(cat info.txt)"
grep -qF "warnings:   0" info.txt || fail "window-room: $(cat info.txt)"
for hard in lamps-pillars window-room; do
    "$BIN" render "$SRC/scenes/$hard.json" --width 16 --height 12 --spp 1 --out "$hard.pfm" \
        >/dev/null 2>&1 || fail "render $hard.json failed"
    [ -s "$hard.pfm" ] || fail "render $hard.json wrote no image"
    rm -f "$hard.pfm"
done
rm -f info.txt

# The scene with a model from Debian's assimp-testmodels (required: install-deps
# installs it): the scene names it relative to itself, so link the installed models
# next to a copy of the scene.
MODELS=/usr/share/assimp/models
[ -f "$MODELS/PLY/Wuson.ply" ] || fail "$MODELS/PLY/Wuson.ply missing (install assimp-testmodels)"
mkdir wuson
cp "$SRC/scenes/cornell-wuson.json" wuson/
# Without the link: status 2, and the way out names the directory the link belongs in
# (not --allow-dark: the scene is not dark, its model is missing).
"$BIN" render wuson/cornell-wuson.json --width 8 --height 6 --spp 1 --out nolink.png 2>err.txt
rc=$?
[ $rc -eq 2 ] && grep -qF "/usr/share/assimp/models wuson/assimp-models" err.txt &&
    ! grep -qF -- "--allow-dark" err.txt && [ ! -e nolink.png ] ||
    fail "cornell-wuson.json without the link: status $rc: $(cat err.txt)"
ln -s "$MODELS" wuson/assimp-models
"$BIN" info wuson/cornell-wuson.json >info.txt 2>&1 || fail "info cornell-wuson.json: $(cat info.txt)"
grep -qF "triangles:  3744 (3732 from 1 mesh file in 1 part" info.txt || fail "cornell-wuson: $(cat info.txt)"
grep -qF "normals:    3732 triangles with vertex normals" info.txt || fail "cornell-wuson: $(cat info.txt)"
"$BIN" render wuson/cornell-wuson.json --width 16 --height 12 --spp 1 --out wuson.png 2>err.txt ||
    fail "render cornell-wuson.json: $(cat err.txt)"
[ -s wuson.png ] || fail "cornell-wuson.json: no image"
rm -rf wuson wuson.png info.txt err.txt

# info's own command line.
"$BIN" info >/dev/null 2>err.txt
[ $? -eq 2 ] && grep -qF "missing SCENE" err.txt || fail "info without SCENE: $(cat err.txt)"
"$BIN" info "$SRC/scenes/cornell-thesis.json" --bogus >/dev/null 2>err.txt
[ $? -eq 2 ] && grep -qF "unknown option '--bogus'" err.txt || fail "info --bogus: $(cat err.txt)"
rm -f err.txt

cli_end cli_scene
