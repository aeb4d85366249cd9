#!/bin/sh
# `trac0r render --noise-threshold / --time-limit`: bad values are usage errors; the
# adaptive image is deterministic (any thread count) and is exactly the plain render of
# the sample counts its tiles stopped at (all at the first check with a threshold every
# tile meets, none with one no tile meets); a time-limited render ends with the complete
# image of a whole number of passes.
# Usage: cli_adaptive.sh TRAC0R_BINARY SCRATCH_DIR
set -u
. "$(dirname "$0")/common.sh"
cli_begin "$1" "$2"

R="render --width 8 --height 6 --spp 1 --out x.png"
expect_usage_error "--noise-threshold" $R --noise-threshold 2
expect_usage_error "--noise-threshold" $R --noise-threshold -0.1
expect_usage_error "--noise-threshold" $R --noise-threshold 0.01 --stride 2
expect_usage_error "--time-limit" $R --time-limit -1
expect_usage_error "--time-limit" $R --time-limit abc

P="render --width 24 --height 20 --seed 3"
# Every tile's error at 16 spp is far below 1e9...: the image is the 16-spp render.
"$BIN" $P --spp 64 --noise-threshold 1 --out all.pfm 2>/dev/null || fail "adaptive render failed"
"$BIN" $P --spp 16 --out plain16.pfm 2>/dev/null || fail "plain render failed"
# A threshold no tile meets: the full 40 samples everywhere.
"$BIN" $P --spp 40 --noise-threshold 1e-9 --threads 1 --out none1.pfm 2>/dev/null ||
    fail "adaptive render failed"
"$BIN" $P --spp 40 --noise-threshold 1e-9 --threads 2 --out none2.pfm 2>/dev/null ||
    fail "adaptive render failed"
"$BIN" $P --spp 40 --out plain40.pfm 2>/dev/null || fail "plain render failed"
cmp -s none1.pfm none2.pfm || fail "adaptive renders with 1 and 2 threads differ"
cmp -s none1.pfm plain40.pfm || fail "a threshold no tile meets changed the image"
# A threshold between: some tiles stop, and the image is neither plain render.
"$BIN" $P --spp 64 --noise-threshold 0.05 --threads 1 --out mid1.pfm 2>/dev/null ||
    fail "adaptive render failed"
"$BIN" $P --spp 64 --noise-threshold 0.05 --threads 2 --out mid2.pfm 2>/dev/null ||
    fail "adaptive render failed"
cmp -s mid1.pfm mid2.pfm || fail "adaptive renders with 1 and 2 threads differ"
"$BIN" $P --spp 64 --out plain64.pfm 2>/dev/null || fail "plain render failed"
cmp -s all.pfm plain16.pfm || fail "a threshold every tile meets: not the 16-spp image"
if cmp -s mid1.pfm plain64.pfm || cmp -s mid1.pfm plain16.pfm; then
    fail "threshold 0.05: no tile stopped, or all at the first check"
fi

# A time limit far below the samples asked for: it stops, and its image is a plain
# render of the passes it made (read from the summary line's "N spp (of M").
"$BIN" $P --spp 1000000 --time-limit 0.3 --out t.pfm 2>err.txt || fail "time-limited render failed"
n=$(sed -n 's/.* \([0-9][0-9]*\) spp (of 1000000.*/\1/p' err.txt)
if [ -z "$n" ] || [ "$n" -ge 1000000 ] || [ "$n" -lt 1 ]; then
    fail "time limit: passes '$n' ($(cat err.txt))"
else
    "$BIN" $P --spp "$n" --out tn.pfm 2>/dev/null || fail "plain render failed"
    cmp -s t.pfm tn.pfm || fail "time-limited image differs from the $n-spp render"
fi
rm -f ./*.pfm err.txt
cli_end cli_adaptive
