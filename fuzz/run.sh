#!/bin/sh
# Builds and runs the scene loader's fuzzer for a bounded time (default 60 s), seeded
# with scenes/*.json and tests/data/**/*.json, and the image decoders' fuzzer with
# tests/data/texture/. Exits non-zero on any crash, leak,
# timeout or sanitizer report (libFuzzer stops and leaves crash-* files in build/fuzz/).
# Usage: fuzz/run.sh [SECONDS]
set -eu
cd "$(dirname "$0")/.."
SECONDS_LIMIT=${1:-60}
fuzz/build.sh
OUT=build/fuzz
rm -rf "$OUT/corpus"
mkdir -p "$OUT/corpus"
for f in $(find scenes tests/data -name '*.json'); do
    cp "$f" "$OUT/corpus/$(echo "$f" | tr / _)"
done
rm -rf "$OUT/image_corpus"
mkdir -p "$OUT/image_corpus"
cp tests/data/texture/*.png "$OUT/image_corpus/"
cd "$OUT"
# A third of the time to the image decoders, seeded with tests/data/texture/ (a good
# PNG, a truncated one, 0x0, a declared 10^5 x 10^5, not an image).
IMAGE_SECONDS=$((SECONDS_LIMIT / 3 > 0 ? SECONDS_LIMIT / 3 : 1))
./fuzz_image -max_total_time="$IMAGE_SECONDS" -print_final_stats=1 -max_len=65536 \
    -timeout=10 -rss_limit_mb=2048 image_corpus
SECONDS_LIMIT=$((SECONDS_LIMIT - IMAGE_SECONDS > 0 ? SECONDS_LIMIT - IMAGE_SECONDS : 1))
./fuzz_scene_json -max_total_time="$SECONDS_LIMIT" -print_final_stats=1 -max_len=16384 \
    -timeout=10 -rss_limit_mb=2048 -dict=../../fuzz/scene.dict corpus
