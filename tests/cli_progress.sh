#!/bin/sh
# Every long job reports progress on stderr; off a terminal, as lines "DONE/TOTAL UNIT"
# ending with TOTAL/TOTAL: render, each bench (bench convergence's reference too).
# Usage: cli_progress.sh TRAC0R_BINARY SCRATCH_DIR
set -u
. "$(dirname "$0")/common.sh"
cli_begin "$1" "$2"

# expect_progress TOTAL UNIT ARGS...: `trac0r ARGS` succeeds and its stderr has a line
# with "1/TOTAL UNIT" or more, and one with "TOTAL/TOTAL UNIT".
expect_progress() {
    total=$1
    unit=$2
    shift 2
    "$BIN" "$@" >out.txt 2>err.txt || fail "trac0r $*: exit $?: $(cat err.txt)"
    grep -q " $total/$total $unit" err.txt || fail "trac0r $*: no final '$total/$total $unit' line: $(cat err.txt)"
    n=$(grep -c "/$total $unit" err.txt)
    [ "$n" -ge 1 ] || fail "trac0r $*: no progress lines"
}

expect_progress 5 spp render --width 16 --height 12 --spp 5 --out r.pfm
expect_progress 4 frames bench frame --width 16 --height 12 --frames 3
expect_progress 4 steps bench complexity --width 16 --height 12 --frames 1 --max-level 1 \
    --accels flat,bvh --out cx
expect_progress 6 runs bench rays --width 8 --height 8 --runs 1 --accels bvh --scene builtin:cornell
expect_progress 64 spp bench convergence --sizes 16x12 --budget 0.2 --reference-spp 64 \
    --methods pt --out conv
grep -q "reference" err.txt || fail "bench convergence: the reference's progress is not named"

cli_end cli_progress
