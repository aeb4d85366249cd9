#!/bin/sh
# A newcomer's first render: models of several formats from Debian's assimp-testmodels,
# dropped on the command line with no other option, come out neither black nor white:
# the mean of the image (linear, clipped to [0, 1]) lies in 0.05..0.9, and it is not flat
# (its pixels spread by more than 0.01). Small renders: 48 pixels wide, 4 spp. The last
# four have lamps of their own (Collada and Blender falloffs, an FBX one).
# Usage: cli_model_sample.sh TRAC0R_BINARY SCRATCH_DIR
set -u
. "$(dirname "$0")/common.sh"
cli_begin "$1" "$2"
M=/usr/share/assimp/models
[ -d "$M" ] || {
    fail "$M is missing (scripts/install-deps installs assimp-testmodels)"
    exit 1
}
PY=/usr/bin/python3
for model in PLY/Wuson.ply STL/Spider_binary.stl STL/Wuson.stl OBJ/spider.obj \
    glTF2/BoxTextured-glTF-Binary/BoxTextured.glb AMF/test1.amf 3DS/fels.3ds AC/Wuson.ac \
    Collada/teapots.DAE Collada/duck.dae Collada/COLLADA.dae BLEND/BlenderDefault_269.blend \
    FBX/global_settings.fbx; do
    "$BIN" render "$M/$model" --width 48 --spp 4 --no-denoise --out m.pfm 2>err.txt ||
        fail "$model: exit $?: $(cat err.txt)"
    stats=$("$PY" -c '
import sys
import numpy as np
data = open("m.pfm", "rb").read()
head, dims, scale, pixels = data.split(b"\n", 3)
w, h = map(int, dims.split())
a = np.clip(np.frombuffer(pixels, dtype="<f4")[: w * h * 3], 0.0, 1.0)
print("%.4f %.4f" % (a.mean(), a.std()))')
    mean=${stats% *}
    spread=${stats#* }
    awk -v m="$mean" -v s="$spread" 'BEGIN { exit !(m >= 0.05 && m <= 0.9 && s > 0.01) }' ||
        fail "$model: mean $mean, spread $spread (wanted a mean in 0.05..0.9, a spread above 0.01)"
    rm -f m.pfm err.txt
done
cli_end cli_model_sample
