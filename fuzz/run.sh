#!/bin/sh
# Builds and runs the fuzzers for a bounded time in all (default 60 s): a third of it for
# the scene loader (seeded with scenes/*.json and tests/data/**/*.json), a sixth each for
# the mesh import path (tests/data/mesh and the hostile models), the image readers (the
# hostile images), texture decoding (tests/data/texture) and the checkpoint reader (a
# checkpoint the release build writes, when it is there). Exits non-zero on any
# crash, leak, timeout, sanitizer report or memory use over the limit (libFuzzer stops
# and leaves crash-* / oom-* files in build/fuzz/).
# Usage: fuzz/run.sh [SECONDS]
set -eu
cd "$(dirname "$0")/.."
SECONDS_LIMIT=${1:-60}
fuzz/build.sh
OUT=build/fuzz
rm -rf "$OUT/corpus" "$OUT/corpus_mesh" "$OUT/corpus_image"
mkdir -p "$OUT/corpus" "$OUT/corpus_mesh" "$OUT/corpus_image"
for f in $(find scenes tests/data -name '*.json'); do
    cp "$f" "$OUT/corpus/$(echo "$f" | tr / _)"
done
# The mesh and image targets read a type byte before the file (see fuzz_mesh.c and
# fuzz_image.c): the index of the extension in their lists.
seed() { # FILE BYTE DIR
    { printf "\\$(printf %03o "$2")"; cat "$1"; } >"$3/$(echo "$1" | tr / _)"
}
for f in $(find tests/data/mesh tests/data/hostile/models tests/data/bad -type f); do
    case $f in
    *.obj) seed "$f" 0 "$OUT/corpus_mesh" ;;
    *.ply) seed "$f" 1 "$OUT/corpus_mesh" ;;
    *.gltf) seed "$f" 2 "$OUT/corpus_mesh" ;;
    *.glb) seed "$f" 3 "$OUT/corpus_mesh" ;;
    *.stl) seed "$f" 4 "$OUT/corpus_mesh" ;;
    esac
done
# An EXR seed, when the release build is there to write one (byte 2: the EXR reader).
if [ -x build/release/trac0r ] &&
    build/release/trac0r render --width 4 --height 3 --spp 1 --passes all \
        --out "$OUT/seed.exr" 2>/dev/null; then
    seed "$OUT/seed.exr" 2 "$OUT/corpus_image"
fi
for f in $(find tests/data/hostile/images -type f); do
    case $f in
    *.pfm) seed "$f" 0 "$OUT/corpus_image" ;;
    *.png) seed "$f" 1 "$OUT/corpus_image" ;;
    esac
done
rm -rf "$OUT/corpus_checkpoint"
mkdir -p "$OUT/corpus_checkpoint"
if [ -x build/release/trac0r ]; then
    build/release/trac0r render --width 5 --height 3 --spp 2 --passes all \
        --checkpoint "$OUT/corpus_checkpoint/seed.ck" --out "$OUT/seed-ck.pfm" 2>/dev/null || true
fi
rm -rf "$OUT/corpus_texture"
mkdir -p "$OUT/corpus_texture"
cp tests/data/texture/*.png tests/data/texture/*.tga tests/data/texture/*.hdr \
    tests/data/texture/*.jpg tests/data/texture/*.bmp "$OUT/corpus_texture/"
# The mesh target through Assimp only when asked (TRAC0R_FUZZ_ASSIMP=1): Assimp 5.2.5
# crashes on what it finds (fuzz/fuzz_mesh.c); otherwise trac0r's declared-size checks.
MESH_TARGET=fuzz_mesh_guard
if [ -n "${TRAC0R_FUZZ_ASSIMP:-}" ]; then
    MESH_TARGET=fuzz_mesh
fi
cd "$OUT"
./fuzz_scene_json -max_total_time=$((SECONDS_LIMIT / 3)) -print_final_stats=1 -max_len=16384 \
    -timeout=10 -rss_limit_mb=2048 -dict=../../fuzz/scene.dict corpus
# Assimp's own leak on some hostile glTF files (tests/lsan-assimp.supp) is not ours.
LSAN_OPTIONS=suppressions=../../tests/lsan-assimp.supp:print_suppressions=0 \
    ./"$MESH_TARGET" -max_total_time=$((SECONDS_LIMIT / 6)) -print_final_stats=1 -max_len=65536 \
    -timeout=10 -rss_limit_mb=2048 corpus_mesh
./fuzz_image -max_total_time=$((SECONDS_LIMIT / 6)) -print_final_stats=1 -max_len=65536 \
    -timeout=10 -rss_limit_mb=2048 corpus_image
./fuzz_texture -max_total_time=$((SECONDS_LIMIT / 6)) -print_final_stats=1 -max_len=65536 \
    -timeout=10 -rss_limit_mb=2048 corpus_texture
./fuzz_checkpoint -max_total_time=$((SECONDS_LIMIT / 6)) -print_final_stats=1 -max_len=65536 \
    -timeout=10 -rss_limit_mb=2048 corpus_checkpoint
