#!/bin/sh
# Builds the libFuzzer targets with clang into build/fuzz/, separate from the gcc builds:
# trac0r's sources they use are compiled with -fsanitize=fuzzer,address,undefined (the
# libraries - cJSON, Assimp, libpng - are not instrumented).
#   fuzz_scene_json  the JSON scene loader; mesh files are not opened
#   fuzz_mesh        the mesh import path: mesh.c and mesh_guard.c into Assimp (by hand:
#                    Assimp 5.2.5 itself crashes on inputs it finds, see fuzz_mesh.c)
#   fuzz_mesh_guard  the same target's declared-size checks alone (what CI runs)
#   fuzz_image       the image readers of `compare` (PNG, PFM and EXR)
#   fuzz_texture     texture and environment-map decoding (src/scene/texture.c and
#                    image_codec.c: libpng, libjpeg, the HDR reader, stb_image's TGA and BMP)
#   fuzz_checkpoint  the checkpoint reader of --resume (src/session/checkpoint.c)
# The wide BVH's per-ISA traversals need per-file flags and are left out: without
# TR_WBVH_HAVE_X86 the library has the scalar one alone.
# Usage: fuzz/build.sh   (CC defaults to clang)
set -eu
cd "$(dirname "$0")/.."
CC=${CC:-clang}
OUT=build/fuzz
mkdir -p "$OUT"
FLAGS="-std=c11 -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all
    -fno-omit-frame-pointer -ffp-contract=off -Wall -Wextra -Wno-unknown-pragmas -Iinclude -Isrc"
SCENE="src/scene/json.c src/scene/scene.c src/scene/shape.c src/scene/camera.c
    src/scene/lights.c src/scene/light_change.c src/accel/bvh.c src/accel/wbvh.c src/accel/wbvh_scalar.c src/accel/tlas.c src/scene/instance.c src/scene/punctual.c src/scene/ggx_ms.c
    src/accel/embree.c src/util/error.c src/util/registry.c src/util/clock.c src/util/parse.c src/util/bigmem.c src/scene/material_registry.c
    src/util/infile.c src/scene/texture.c src/scene/image_codec.c src/scene/envmap.c src/scene/sun.c src/scene/light_tree.c"
# shellcheck disable=SC2046,SC2086
"$CC" $FLAGS $(pkg-config --cflags libcjson) fuzz/fuzz_scene_json.c $SCENE \
    $(pkg-config --libs libcjson libpng) -ljpeg -lm -o "$OUT/fuzz_scene_json"
# shellcheck disable=SC2046,SC2086
"$CC" $FLAGS -DTR_MESH_IMPORT_IN_PROCESS $(pkg-config --cflags libcjson assimp) fuzz/fuzz_mesh.c $SCENE \
    src/scene/mesh.c src/scene/mesh_guard.c \
    $(pkg-config --libs libcjson assimp libpng) -ljpeg -lm -o "$OUT/fuzz_mesh"
# shellcheck disable=SC2046,SC2086
"$CC" $FLAGS -DTR_FUZZ_GUARD_ONLY -DTR_MESH_IMPORT_IN_PROCESS $(pkg-config --cflags libcjson assimp) fuzz/fuzz_mesh.c $SCENE \
    src/scene/mesh.c src/scene/mesh_guard.c \
    $(pkg-config --libs libcjson assimp libpng) -ljpeg -lm -o "$OUT/fuzz_mesh_guard"
# shellcheck disable=SC2046,SC2086
"$CC" $FLAGS $(pkg-config --cflags libpng OpenEXR) fuzz/fuzz_image.c src/io/image.c src/io/exr.c src/util/infile.c \
    src/io/outfile.c src/film/film.c src/post/tonemap.c src/util/error.c \
    $(pkg-config --libs libpng) -lOpenEXRCore-3_1 -lm -o "$OUT/fuzz_image"
# shellcheck disable=SC2046,SC2086
"$CC" $FLAGS fuzz/fuzz_texture.c src/scene/texture.c src/scene/image_codec.c src/scene/scene.c \
    src/scene/shape.c src/scene/lights.c src/scene/light_change.c src/accel/bvh.c src/accel/wbvh.c src/accel/wbvh_scalar.c src/accel/tlas.c src/scene/instance.c src/scene/punctual.c src/scene/ggx_ms.c \
    src/accel/embree.c src/util/error.c src/util/registry.c src/util/clock.c src/util/parse.c src/util/bigmem.c src/scene/material_registry.c \
    src/util/infile.c src/scene/light_tree.c src/scene/sun.c $(pkg-config --libs libpng) -ljpeg -lm -o "$OUT/fuzz_texture"
# shellcheck disable=SC2046,SC2086
"$CC" $FLAGS fuzz/fuzz_checkpoint.c src/session/checkpoint.c src/film/film.c src/io/outfile.c \
    src/util/error.c -lm -o "$OUT/fuzz_checkpoint"
echo "built $OUT/fuzz_scene_json $OUT/fuzz_mesh $OUT/fuzz_mesh_guard $OUT/fuzz_image $OUT/fuzz_texture $OUT/fuzz_checkpoint"
