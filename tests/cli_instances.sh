#!/bin/sh
# Instances in scene files through the trac0r binary: a scene placing prototypes (a
# shape group, a prototype nested in another, matrices and position/orientation/scale)
# renders with every acceleration structure (bvh traces the two-level structure, the
# others the instances' triangles flattened) and `info` counts the placed triangles;
# bad placements - a singular or short matrix, a matrix beside a position, an unknown
# prototype, a cycle of prototypes, an error inside a prototype - exit 2 with one line
# naming the file and the key at fault, and write nothing.
# Usage: cli_instances.sh TRAC0R_BINARY SCRATCH_DIR
set -u
. "$(dirname "$0")/common.sh"
cli_begin "$1" "$2"

# scene FILE PROTOTYPES INSTANCES: a small room with the given "prototypes" and
# "instances" members.
scene() {
    cat >"$1" <<JSON
{
  "camera": {"position": [0, 1.6, 4], "look_at": [0, 0.4, 0], "fov": 45},
  "materials": {"white": {"type": "diffuse", "color": [0.8, 0.8, 0.8]},
                "red": {"type": "diffuse", "color": [0.8, 0.2, 0.2]},
                "lamp": {"type": "emitter", "color": [1, 1, 1], "emittance": 8}},
  "shapes": [
    {"type": "plane", "scale": [8, 1, 8], "material": "white"},
    {"type": "plane", "position": [0, 3, 0], "orientation": [180, 0, 0], "scale": [1.5, 1, 1.5],
     "material": "lamp"}
  ],
  "prototypes": $2,
  "instances": $3
}
JSON
}

PROTOS='{"ball": {"shapes": [{"type": "icosphere", "smooth": true, "subdivisions": 1, "scale": 0.3, "material": "red"},
                             {"type": "box", "position": [0, -0.3, 0], "scale": 0.2, "material": "white"}]},
         "pair": {"instances": [{"prototype": "ball", "position": [-0.35, 0, 0]},
                                {"prototype": "ball", "position": [0.35, 0, 0]}]}}'
scene good.json "$PROTOS" '[{"prototype": "pair", "position": [0, 0.3, 0]},
    {"prototype": "ball", "matrix": [1, 0, 0, 0, 0, 2, 0, 1.2, 0, 0, 1, -1]},
    {"prototype": "pair", "position": [0, 0.3, -1.5], "orientation": [0, 45, 0], "scale": 0.7}]'
for accel in bvh bvh2 flat; do
    "$BIN" render good.json --accel $accel --width 16 --height 12 --spp 1 --out $accel.pfm 2>err.txt ||
        fail "render --accel $accel: $(cat err.txt)"
    [ -s $accel.pfm ] || fail "render --accel $accel: no image"
done
# 2 x 2 + 5 placements x (80 + 12) triangles.
"$BIN" info good.json >info.txt 2>&1 || fail "info good.json: $(cat info.txt)"
grep -qF "triangles:  464" info.txt || fail "info good.json: $(cat info.txt)"
rm -f ./*.pfm err.txt info.txt

# bad FILE NEEDLE: render exits 2 with one stderr line naming the file and NEEDLE.
bad() {
    "$BIN" render "$1" --width 8 --height 6 --spp 1 --out out.pfm >stdout.txt 2>err.txt
    rc=$?
    [ "$rc" -eq 2 ] || fail "render $1: exit $rc, expected 2: $(cat err.txt)"
    [ "$(wc -l <err.txt)" -eq 1 ] || fail "render $1: expected one stderr line: $(cat err.txt)"
    grep -qF -- "$1: $2" err.txt || fail "render $1: stderr lacks '$1: $2': $(cat err.txt)"
    [ ! -e out.pfm ] || fail "render $1: wrote out.pfm"
    rm -f stdout.txt err.txt
}
scene singular.json "$PROTOS" '[{"prototype": "ball", "matrix": [1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 0]}]'
bad singular.json "instances[0].matrix: instance 0: the matrix is singular"
scene flat.json "$PROTOS" '[{"prototype": "ball"}, {"prototype": "ball", "matrix": [1, 2, 3, 0, 2, 4, 6, 0, 0, 0, 1, 0]}]'
bad flat.json "instances[1].matrix: instance 1: the matrix is singular"
scene short.json "$PROTOS" '[{"prototype": "ball", "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]}]'
bad short.json "instances[0].matrix: expected 12 numbers"
scene huge.json "$PROTOS" '[{"prototype": "ball", "matrix": [1e999, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0]}]'
bad huge.json "instances[0].matrix: expected 12 numbers"
scene both.json "$PROTOS" '[{"prototype": "ball", "position": [0, 1, 0], "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0]}]'
bad both.json "instances[0].matrix: expected either 'matrix' or position/orientation/scale"
scene unknown.json "$PROTOS" '[{"prototype": "bal"}]'
bad unknown.json "instances[0].prototype: undefined prototype 'bal' (did you mean 'ball'?)"
scene cycle.json '{"a": {"instances": [{"prototype": "b"}]}, "b": {"instances": [{"prototype": "a"}]}}' \
    '[{"prototype": "a"}]'
bad cycle.json "prototypes.a.prototypes.b.instances[0].prototype: prototype 'a' contains itself"
scene self.json '{"a": {"shapes": [{"type": "box", "material": "red"}], "instances": [{"prototype": "a"}]}}' '[]'
bad self.json "prototypes.a.instances[0].prototype: prototype 'a' contains itself"
scene inner.json '{"a": {"shapes": [{"type": "box", "material": "whit"}]}}' '[{"prototype": "a"}]'
bad inner.json "prototypes.a.shapes[0].material: undefined material 'whit'"
scene empty.json '{"a": {}}' '[{"prototype": "a"}]'
bad empty.json "prototypes.a: expected 'shapes', 'meshes' or 'instances' with triangles"
scene zero_scale.json "$PROTOS" '[{"prototype": "ball", "scale": [1, 0, 1]}]'
bad zero_scale.json "instances[0].scale[1]: expected a positive number"
scene far.json "$PROTOS" '[{"prototype": "ball", "matrix": [1e7, 0, 0, 1e7, 0, 1, 0, 0, 0, 0, 1, 0]}]'
bad far.json "instances[0]: a vertex lands at"

cli_end cli_instances
