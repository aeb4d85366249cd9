#!/bin/sh
# Output targets are checked before any work: the image, its pass files and the checkpoint
# must be distinct files (the same path, or another path to it, is refused with status 2),
# and a pass file's target that is a directory or FIFO is refused with status 2 before
# rendering, leaving nothing written. A SIGTERM that arrives while the files are being
# written lets them be finished whole and gives status 128+15.
# Usage: cli_outputs.sh TRAC0R_BINARY SCRATCH_DIR
set -u
. "$(dirname "$0")/common.sh"
cli_begin "$1" "$2"

R="render --width 32 --height 24 --spp 1 --threads 1"

expect_usage_error "name one file" $R --out o.png --checkpoint o.png
expect_usage_error "name one file" $R --out o.png --checkpoint ./o.png
expect_usage_error "name one file" $R --out o.pfm --passes albedo --checkpoint o.albedo.pfm
mkdir o.albedo.pfm
expect_usage_error "o.albedo.pfm" $R --out o.pfm --passes albedo
rmdir o.albedo.pfm
mkfifo o.depth.pfm
expect_usage_error "o.depth.pfm" $R --out o.pfm --passes depth
rm -f o.depth.pfm

# SIGTERM once the image is in place and the pass files are still to come.
"$BIN" render --width 1024 --height 1024 --spp 1 --stride 8 --passes all --out big.pfm \
    2>err.txt &
pid=$!
n=0
while [ ! -e big.pfm ] && [ $n -lt 200000 ]; do
    n=$((n + 1))
done
if kill -TERM $pid 2>/dev/null; then
    wait $pid
    rc=$?
    if [ -e big.variance.pfm ] || [ $rc -ne 0 ]; then
        [ $rc -eq 143 ] || fail "SIGTERM while writing: exit $rc, expected 143: $(cat err.txt)"
        size=$(wc -c <big.pfm)
        for p in albedo normal depth id variance; do
            [ -e big.$p.pfm ] || fail "SIGTERM while writing: big.$p.pfm missing"
            [ "$(wc -c 2>/dev/null <big.$p.pfm)" = "$size" ] ||
                fail "SIGTERM while writing: big.$p.pfm is not whole"
        done
    fi
else
    wait $pid
    echo "cli_outputs: the render finished before SIGTERM; that check proves nothing this time"
fi
ls | grep -q '\.tmp\.' && fail "temporary files left: $(ls)"

cli_end cli_outputs
