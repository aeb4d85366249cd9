#!/bin/sh
# Builds the libFuzzer targets for the JSON scene loader and for image decoding with clang into build/fuzz/,
# separate from the gcc builds: the loader's sources and the scene code it uses are
# compiled with -fsanitize=fuzzer,address,undefined. Mesh import is left out (the
# target never opens mesh files), and so are the wide BVH's per-ISA traversals, which need
# per-file flags: without TR_WBVH_HAVE_X86 the library has the scalar one alone.
# Usage: fuzz/build.sh   (CC defaults to clang)
set -eu
cd "$(dirname "$0")/.."
CC=${CC:-clang}
OUT=build/fuzz
mkdir -p "$OUT"
# shellcheck disable=SC2046
"$CC" -std=c11 -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all \
    -fno-omit-frame-pointer -ffp-contract=off -Wall -Wextra -Wno-unknown-pragmas \
    -Iinclude -Isrc $(pkg-config --cflags libcjson) \
    fuzz/fuzz_scene_json.c src/scene/json.c src/scene/scene.c src/scene/shape.c \
    src/scene/camera.c src/scene/lights.c src/accel/bvh.c src/accel/wbvh.c \
    src/accel/wbvh_scalar.c src/accel/embree.c src/util/error.c src/util/registry.c \
    src/scene/material_registry.c src/scene/texture.c src/scene/envmap.c \
    $(pkg-config --libs libcjson) -lm -o "$OUT/fuzz_scene_json"
echo "built $OUT/fuzz_scene_json"
# Image decoding (textures, environment maps): texture.c and the error code it uses.
"$CC" -std=c11 -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all \
    -fno-omit-frame-pointer -ffp-contract=off -Wall -Wextra -Wno-unknown-pragmas \
    -Iinclude -Isrc fuzz/fuzz_image.c src/scene/texture.c src/scene/scene.c src/scene/shape.c \
    src/scene/lights.c src/accel/bvh.c src/accel/wbvh.c src/accel/wbvh_scalar.c \
    src/accel/embree.c src/util/error.c src/util/registry.c src/scene/material_registry.c \
    -lm -o "$OUT/fuzz_image"
echo "built $OUT/fuzz_image"
