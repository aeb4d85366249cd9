#!/bin/sh
# Builds and runs the scene loader's fuzzer for a bounded time (default 60 s), seeded
# with scenes/*.json and tests/data/**/*.json. Exits non-zero on any crash, leak,
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
cd "$OUT"
./fuzz_scene_json -max_total_time="$SECONDS_LIMIT" -print_final_stats=1 -max_len=16384 \
    -timeout=10 -rss_limit_mb=2048 -dict=../../fuzz/scene.dict corpus
