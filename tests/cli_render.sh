#!/bin/sh
# Drives `trac0r render` and `trac0r bench` from the outside: bad input must give one
# clear line naming the option and value, exit status 2 and no file; good input must
# give a complete image and no leftovers.
# Usage: cli_render.sh TRAC0R_BINARY SCRATCH_DIR
set -u
. "$(dirname "$0")/common.sh"
cli_begin "$1" "$2"

R="render --width 8 --height 6 --spp 1 --out x.png"
expect_usage_error "'--bogus'" $R --bogus
# A near miss names the option meant; a built-in scene's too.
expect_usage_error "did you mean '--width'" $R --widht 320
expect_usage_error "did you mean '--noise-threshold'" $R --noise-treshold 0.1
expect_usage_error "did you mean 'cornell-mirror'" $R builtin:cornell-miror
# Extras for any scene: an environment, a sun and a ground; malformed ones are refused.
"$BIN" render --width 16 --height 12 --spp 1 --env 0.2,0.3,0.5 --sun 1,2,1 --ground \
    --out extras.png 2>err.txt && [ -s extras.png ] || fail "render with extras: $(cat err.txt)"
rm -f extras.png err.txt
expect_usage_error "--sun" $R --sun 0,0,0
expect_usage_error "--sun" $R --sun 1,2
expect_usage_error "--env" $R --env 1,-1,1
expect_usage_error "--env" $R --env no-such-sky.hdr
# One side alone keeps the shape of the command's own default size (bench realtime's
# 320x240 and render's 800x600 are both 4:3).
"$BIN" bench realtime --width 64 --frames 2 --reference-spp 2 --methods off --out rt \
    >rt.txt 2>&1 || fail "bench realtime --width 64: $(cat rt.txt)"
grep -q "64x48" rt.txt || fail "bench realtime --width 64 is not 64x48: $(head -3 rt.txt)"
rm -f rt.txt rt.csv rt.png
# A black image is written, and said to be black; a lit one draws no warning.
"$BIN" render --width 16 --height 12 --spp 2 --exposure -20 --out dark.png 2>err.txt ||
    fail "render --exposure -20: exit $?"
[ -s dark.png ] && grep -q "warning: dark.png" err.txt || fail "black image not noted: $(cat err.txt)"
"$BIN" render --width 16 --height 12 --spp 2 --out lit.png 2>err.txt || fail "render: exit $?"
grep -q "warning" err.txt && fail "lit image noted: $(cat err.txt)"
rm -f dark.png lit.png err.txt
expect_usage_error "--width: expected an integer in 1..16384, got 'abc'" $R --width abc
expect_usage_error "--width: expected an integer in 1..16384, got '0'" $R --width 0
expect_usage_error "got '-5'" $R --width -5
expect_usage_error "--height: expected an integer in 1..16384, got '100000'" $R --height 100000
expect_usage_error "--height: expected an integer" $R --height 99999999999999999999999
expect_usage_error "more than 67108864 pixels" $R --width 16384 --height 16384
expect_usage_error "--spp: expected an integer in 1..1000000, got '0'" $R --spp 0
expect_usage_error "--spp: expected an integer" $R --spp 1.5
expect_usage_error "--max-depth: expected an integer in 1..1024, got '0'" $R --max-depth 0
expect_usage_error "--threads: expected an integer in 0..1024, got '-1'" $R --threads -1
expect_usage_error "--seed: expected an integer" $R --seed -1
expect_usage_error "--seed: expected an integer" $R --seed 18446744073709551616
expect_usage_error "--exposure: expected a number in -20..20, got 'nan'" $R --exposure nan
expect_usage_error "--stride: expected an integer in 1..64, got '0'" $R --stride 0
expect_usage_error "--integrator: unknown integrator 'magic'" $R --integrator magic
expect_usage_error "--spp: missing value" $R --spp
expect_usage_error "--accel: unknown acceleration structure 'kd'" $R --accel kd
expect_usage_error "--out: 'x.jpg' has an unknown extension" $R --out x.jpg
expect_usage_error "--out: 'noext' has an unknown extension" $R --out noext
expect_usage_error "--out: missing/dir/x.png: cannot create file" $R --out missing/dir/x.png
touch afile
expect_usage_error "--out: afile/x.png: cannot create file" $R --out afile/x.png
rm -f afile
expect_usage_error "scene.json: cannot open: No such file or directory" $R --scene scene.json
expect_usage_error "unknown built-in scene 'nope'" $R --scene builtin:nope
expect_usage_error "unknown command 'paint'" paint
expect_usage_error "--frames: expected an integer in 1..100000, got '0'" bench frame --frames 0
if "$BIN" view --help >/dev/null 2>&1; then # builds with the viewer
    expect_usage_error "--animate: only in the interactive window" view --animate --frames 2 \
        --screenshot x.png
fi
expect_usage_error "unknown benchmark 'nope'" bench nope

# --help documents every option it accepts.
"$BIN" render --help >help.txt 2>&1 || fail "render --help exited non-zero"
for opt in --scene --width --height --spp --max-depth --seed --threads --integrator --out \
    --stride --exposure --accel; do
    grep -q -- "$opt" help.txt || fail "render --help does not mention $opt"
done
rm -f help.txt

# Good renders: a complete PNG and PFM with the right size, and no temporary files.
if "$BIN" render --width 16 --height 12 --spp 2 --out ok.png 2>err.txt; then
    sig=$(od -An -tx1 -N8 ok.png | tr -d ' \n')
    [ "$sig" = "89504e470d0a1a0a" ] || fail "ok.png is not a PNG (signature $sig)"
    grep -q "16x12, 2 spp" err.txt || fail "render summary line missing: $(cat err.txt)"
else
    fail "a good render failed: $(cat err.txt)"
fi
if "$BIN" render --width 16 --height 12 --spp 2 --out ok.pfm 2>/dev/null; then
    head=$(head -c 14 ok.pfm | tr '\n' ' ')
    [ "$head" = "PF 16 12 -1.0 " ] || fail "ok.pfm header is '$head'"
    size=$(wc -c <ok.pfm)
    [ "$size" -eq $((14 + 16 * 12 * 3 * 4)) ] || fail "ok.pfm has $size bytes"
else
    fail "a good PFM render failed"
fi
# Every acceleration structure renders the same image for the same seed (ties aside,
# which the unit tests bound; this scene has none at this size). The naive integrator's
# radiance depends only on which triangles are hit, so its images are bit-identical;
# pt's next-event estimates use hit distances, which Embree rounds differently.
for accel in flat embree bvh2; do
    "$BIN" render --width 16 --height 12 --spp 2 --integrator naive --accel $accel \
        --out $accel.pfm 2>/dev/null || fail "--accel $accel render failed"
    "$BIN" render --width 16 --height 12 --spp 2 --integrator naive --accel bvh --out bvh.pfm \
        2>/dev/null
    cmp -s $accel.pfm bvh.pfm || fail "--accel $accel and --accel bvh images differ"
    rm -f $accel.pfm bvh.pfm
done
leftovers=$(ls -A | grep -v -e '^ok.png$' -e '^ok.pfm$' -e '^err.txt$')
[ -z "$leftovers" ] || fail "temporary files left behind: $leftovers"

# bench frame --animate: the scene update is timed and named apart from the frame.
for accel in bvh embree flat; do
    "$BIN" bench frame --width 16 --height 12 --frames 3 --animate --accel $accel >bench.txt 2>&1 ||
        fail "bench frame --animate --accel $accel failed: $(cat bench.txt)"
    case $accel in bvh) kind=refit ;; embree) kind=rebuild ;; *) kind=none ;; esac
    grep -q "^scene update per frame ($kind): median [0-9.]* ms" bench.txt ||
        fail "bench frame --animate --accel $accel: $(cat bench.txt)"
    rm -f bench.txt
done

# --passes: one PFM per pass beside the image, of the image's size; bad lists are usage
# errors that write nothing.
rm -f err.txt
expect_usage_error "--passes: unknown pass 'bogus'" $R --passes bogus
expect_usage_error "--passes: 'albedo,' ends with a comma" $R --passes albedo,
"$BIN" render --width 8 --height 6 --spp 2 --out p.png --passes albedo,depth 2>/dev/null ||
    fail "render --passes albedo,depth failed"
for pass in albedo depth; do
    [ "$(head -c 2 p.$pass.pfm)" = "PF" ] || fail "p.$pass.pfm is not a colour PFM"
    [ "$(sed -n 2p p.$pass.pfm)" = "8 6" ] || fail "p.$pass.pfm is not 8x6"
done
[ ! -e p.normal.pfm ] && [ ! -e p.id.pfm ] || fail "passes written that were not asked for"
rm -f p.png p.albedo.pfm p.depth.pfm

# --sampler and --light-sampling take their names only; the random sampler
# renders another (equally valid) image than the Sobol points with the same seed.
expect_usage_error "'bogus'" $R --sampler bogus
expect_usage_error "'trees'" $R --light-sampling trees
"$BIN" render --width 8 --height 6 --spp 2 --out s.pfm --light-sampling tree 2>/dev/null ||
    fail "render --light-sampling tree failed"
"$BIN" render --width 8 --height 6 --spp 2 --out r.pfm --sampler random 2>/dev/null ||
    fail "render --sampler random failed"
cmp -s s.pfm r.pfm && fail "--sampler random rendered the Sobol sampler's image"
"$BIN" render --width 8 --height 6 --spp 2 --out d.pfm 2>/dev/null || fail "render failed"
"$BIN" render --width 8 --height 6 --spp 2 --out z.pfm --sampler zsobol 2>/dev/null ||
    fail "render --sampler zsobol failed"
cmp -s d.pfm z.pfm && fail "--sampler zsobol rendered the Sobol sampler's image"
rm -f s.pfm r.pfm d.pfm z.pfm

# --roulette-start takes 1..1024; 5 is the default's image bit for bit, and an earlier
# start (the real-time one) renders another image with the same seed.
expect_usage_error "'0'" $R --roulette-start 0
expect_usage_error "'1025'" $R --roulette-start 1025
"$BIN" render --width 8 --height 6 --spp 2 --out d.pfm 2>/dev/null || fail "render failed"
"$BIN" render --width 8 --height 6 --spp 2 --out r5.pfm --roulette-start 5 2>/dev/null ||
    fail "render --roulette-start 5 failed"
cmp -s d.pfm r5.pfm || fail "--roulette-start 5 is not the default's image"
"$BIN" render --width 8 --height 6 --spp 2 --out r2.pfm --roulette-start 2 2>/dev/null ||
    fail "render --roulette-start 2 failed"
cmp -s d.pfm r2.pfm && fail "--roulette-start 2 rendered the default's image"
rm -f d.pfm r5.pfm r2.pfm

# A file that exists already is replaced only by a complete image.
"$BIN" render --width 8 --height 6 --spp 1 --out ok.png --width 0 2>/dev/null
sig=$(od -An -tx1 -N8 ok.png | tr -d ' \n')
[ "$sig" = "89504e470d0a1a0a" ] || fail "a failed run damaged the existing ok.png"

cli_end cli_render
