#!/bin/sh
# Checkpoints and interrupted renders: a render killed with SIGKILL and resumed from its
# last checkpoint gives the bits of the uninterrupted one; a checkpoint of another scene
# or other options, or of an older format version, is refused (exit 2); SIGINT leaves a complete image of the samples so
# far, a checkpoint that resumes to the same bits, and no temporary file; a time-limited
# render's checkpoint resumes too.
# Usage: cli_checkpoint.sh TRAC0R_BINARY SCRATCH_DIR
set -u
. "$(dirname "$0")/common.sh"
cli_begin "$1" "$2"

R="render --width 64 --height 48 --threads 1 --passes albedo,depth,variance"
SPP=400

# wait_for FILE: until FILE exists (at most ~20 s).
wait_for() {
    n=0
    while [ ! -s "$1" ] && [ $n -lt 1000 ]; do
        sleep 0.02
        n=$((n + 1))
    done
}

"$BIN" $R --spp $SPP --out full.pfm 2>err.txt || fail "uninterrupted render: $(cat err.txt)"

# SIGKILL after the first checkpoints: nothing can be cleaned up, the last complete
# checkpoint must be enough.
"$BIN" $R --spp $SPP --out killed.pfm --checkpoint ck --checkpoint-interval 0 2>/dev/null &
pid=$!
wait_for ck
sleep 0.05
kill -KILL $pid
wait $pid
[ -e killed.pfm ] && fail "the render finished before SIGKILL: the test proves nothing"
"$BIN" $R --resume ck --out resumed.pfm 2>err.txt || fail "resume: $(cat err.txt)"
cmp -s full.pfm resumed.pfm || fail "resumed render differs from the uninterrupted one"
cmp -s full.depth.pfm resumed.depth.pfm || fail "resumed depth pass differs"
cmp -s full.albedo.pfm resumed.albedo.pfm || fail "resumed albedo pass differs"
cmp -s full.variance.pfm resumed.variance.pfm || fail "resumed variance pass differs"
rm -f ck.tmp.* err.txt # SIGKILL may leave the checkpoint being written

# Another scene, other options, a damaged file: refused with exit 2 and nothing written.
expect_usage_error "--resume" render builtin:cornell-mirror --width 64 --height 48 \
    --passes albedo,depth,variance --resume ck --out other.pfm
expect_usage_error "seed" $R --seed 7 --resume ck --out other.pfm
expect_usage_error "sampler" $R --sampler random --resume ck --out other.pfm
# The light selection the scene ends up with is what counts: the box's lamp takes the power
# table unless a tree is asked for (asking for power renders the same image).
expect_usage_error "light-sampling" $R --light-sampling tree --resume ck --out other.pfm
expect_usage_error "roulette-start" $R --roulette-start 2 --resume ck --out other.pfm
expect_usage_error "passes" render --width 64 --height 48 --resume ck --out other.pfm
expect_usage_error "--spp" $R --resume ck --spp 1 --out other.pfm
head -c 1000 ck >damaged
expect_usage_error "--resume" $R --resume damaged --out other.pfm
# Format version 1 (before the variance pass): refused as such, not as damage.
cp ck old
printf '\001\000\000\000' | dd of=old bs=1 seek=8 conv=notrunc 2>/dev/null
expect_usage_error "version 1" $R --resume old --out other.pfm
printf 'not a checkpoint' >junk
expect_usage_error "--resume" $R --resume junk --out other.pfm
expect_usage_error "--checkpoint-interval" $R --checkpoint ck --checkpoint-interval -1
expect_usage_error "--checkpoint: nodir/ck" $R --checkpoint nodir/ck

# A time limit no pass fits in stops after the first pass; its checkpoint resumes to the
# uninterrupted image.
"$BIN" $R --spp $SPP --time-limit 0.000001 --checkpoint ckt --out t1.pfm 2>err.txt ||
    fail "--time-limit with --checkpoint: $(cat err.txt)"
"$BIN" $R --spp 1 --out one.pfm 2>/dev/null || fail "1 spp render"
cmp -s one.pfm t1.pfm || fail "--time-limit with --checkpoint: not the image of its one pass"
"$BIN" $R --resume ckt --spp $SPP --out t2.pfm 2>err.txt || fail "resume after a time limit: $(cat err.txt)"
cmp -s full.pfm t2.pfm || fail "a time-limited render resumed differs from the uninterrupted one"
rm -f err.txt
expect_usage_error "--noise-threshold" $R --noise-threshold 0.1 --checkpoint ckn --out n.pfm

# SIGINT: the pass under way ends, image and checkpoint are written, exit 128+2.
"$BIN" $R --spp 1000000 --out int.pfm --checkpoint ck2 2>err.txt &
pid=$!
wait_for err.txt # the first progress line: a sample is done
kill -INT $pid
wait $pid
rc=$?
[ $rc -eq 130 ] || fail "SIGINT: exit $rc, expected 130: $(cat err.txt)"
"$BIN" compare int.pfm int.pfm >/dev/null 2>&1 || fail "SIGINT: int.pfm is not a complete image"
[ -s int.albedo.pfm ] || fail "SIGINT: the albedo pass was not written"
ls ./*.tmp.* >/dev/null 2>&1 && fail "SIGINT left temporary files: $(ls ./*.tmp.*)"
"$BIN" $R --resume ck2 --spp $SPP --out resumed2.pfm 2>err.txt || fail "resume after SIGINT: $(cat err.txt)"
cmp -s full.pfm resumed2.pfm || fail "render resumed after SIGINT differs from the uninterrupted one"

# A second signal does not wait for the pass (of a second or more here): the default
# action ends the process at once, and no image is written.
"$BIN" render --width 1024 --height 768 --threads 1 --spp 1000000 --out twice.pfm 2>err.txt &
pid=$!
wait_for err.txt
kill -TERM $pid
sleep 0.1
kill -TERM $pid
wait $pid
rc=$?
[ $rc -eq 143 ] || fail "two SIGTERMs: exit $rc, expected 143"
[ -e twice.pfm ] && fail "two SIGTERMs: the image was still written"

cli_end cli_checkpoint
