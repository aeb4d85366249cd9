#!/bin/sh
# Drives `trac0r compare` and `trac0r bench convergence`: metrics on hand-made PFM
# images against values computed by hand, the error image, and bad input (exit 2, one
# line naming the file or option, nothing written).
# Usage: cli_compare.sh TRAC0R_BINARY SCRATCH_DIR
set -u
. "$(dirname "$0")/common.sh"
cli_begin "$1" "$2"

# Little-endian float32 bytes: 0 = 00000000, 0.5 = 3f000000, 1 = 3f800000, 2 = 40000000.
Z='\000\000\000\000'
HALF='\000\000\000\077'
ONE='\000\000\200\077'
TWO='\000\000\000\100'
# A: (0.5, 0.5, 0.5) (2, 0, 0)    B: (0, 0, 0) (1, 0, 0)    2x1 pixels each.
printf "PF\n2 1\n-1.0\n$HALF$HALF$HALF$TWO$Z$Z" >a.pfm
printf "PF\n2 1\n-1.0\n$Z$Z$Z$ONE$Z$Z" >b.pfm
printf "PF\n1 1\n-1.0\n$Z$Z$Z" >small.pfm
printf "PF\n2 1\n-1.0\n$Z" >truncated.pfm

# Clamped to [0,1] the 2 becomes 1, so the squared differences are 0.25 x 3 and 0 x 3:
# MSE = 0.125, RMSE = sqrt(0.125) = 0.353553, PSNR = 10 log10(8) = 9.031 dB,
# relMSE = (3 * 0.25 / 0.01) / 6 = 12.5.
if "$BIN" compare a.pfm b.pfm >out.txt 2>err.txt; then
    grep -qx "rmse 0.353553" out.txt || fail "rmse: $(cat out.txt)"
    grep -qx "relmse 12.5" out.txt || fail "relmse: $(cat out.txt)"
    grep -qx "psnr 9.031 dB" out.txt || fail "psnr: $(cat out.txt)"
    grep -qx "size 2x1" out.txt || fail "size: $(cat out.txt)"
else
    fail "compare a.pfm b.pfm failed: $(cat err.txt)"
fi
"$BIN" compare b.pfm b.pfm >out.txt 2>&1 || fail "compare b b failed"
grep -qx "psnr inf dB" out.txt || fail "identical images: $(cat out.txt)"
grep -qx "rmse 0" out.txt || fail "identical images: $(cat out.txt)"

# The error image: a complete PNG of the same size.
if "$BIN" compare a.pfm b.pfm --error-image err.png >out.txt 2>err.txt; then
    sig=$(od -An -tx1 -N8 err.png | tr -d ' \n')
    [ "$sig" = "89504e470d0a1a0a" ] || fail "err.png is not a PNG"
    grep -q "white = 0.5" out.txt || fail "error image scale: $(cat out.txt)"
else
    fail "--error-image failed: $(cat err.txt)"
fi
"$BIN" compare a.pfm b.pfm --error-image err.pfm >/dev/null 2>&1 || fail "--error-image .pfm"
size=$(wc -c <err.pfm)
[ "$size" -eq $((12 + 2 * 3 * 4)) ] || fail "err.pfm has $size bytes"
rm -f err.png err.pfm out.txt err.txt

# Rendered images: PNG input is decoded from sRGB; a PNG of a PFM compares close to it.
"$BIN" render --width 16 --height 12 --spp 4 --out r.pfm 2>/dev/null || fail "render r.pfm"
"$BIN" render --width 16 --height 12 --spp 4 --out r.png 2>/dev/null || fail "render r.png"
"$BIN" compare r.png r.pfm >out.txt 2>&1 || fail "compare png pfm: $(cat out.txt)"
psnr=$(sed -n 's/^psnr \([0-9.]*\) dB$/\1/p' out.txt)
[ -n "$psnr" ] && awk "BEGIN { exit !($psnr > 40) }" ||
    fail "8-bit PNG against its own float image: psnr '$psnr' (expected > 40 dB)"
rm -f out.txt

expect_usage_error "small.pfm is 1x1 but b.pfm is 2x1" compare small.pfm b.pfm
expect_usage_error "missing.pfm: cannot open" compare missing.pfm b.pfm
expect_usage_error "truncated.pfm" compare truncated.pfm b.pfm
expect_usage_error "unknown image format" compare a.txt b.pfm
expect_usage_error "expected two images" compare a.pfm
expect_usage_error "unexpected argument 'c.pfm'" compare a.pfm b.pfm c.pfm
expect_usage_error "--error-image: 'e.jpg' has an unknown extension" compare a.pfm b.pfm \
    --error-image e.jpg
expect_usage_error "unknown option '--bogus'" compare a.pfm b.pfm --bogus

# bench convergence, tiny: every method measured, CSV written, table printed.
if "$BIN" bench convergence --sizes 16x12 --budget 0.2 --reference-spp 8 --out conv \
    >out.txt 2>err.txt; then
    head -1 conv.csv | grep -qx "method,width,height,spp,seconds,rmse,relmse,psnr_raw,psnr" ||
        fail "conv.csv header: $(head -1 conv.csv)"
    grep -q "^naive,16,12," conv.csv || fail "conv.csv has no naive rows"
    grep -q "^pt,16,12," conv.csv || fail "conv.csv has no pt rows"
    grep -q "^bdpt,16,12," conv.csv || fail "conv.csv has no bdpt rows"
    grep -q "time pt / time bdpt" out.txt || fail "no bdpt speed-up line: $(cat out.txt)"
    grep -q "^16x12 *naive" out.txt || fail "no table row for naive: $(cat out.txt)"
    grep -q "40 dB" out.txt || fail "no 40 dB column: $(cat out.txt)"
else
    fail "bench convergence failed: $(cat err.txt)"
fi
rm -f conv.csv conv.png out.txt err.txt
expect_usage_error "--sizes: expected" bench convergence --sizes 0x5
expect_usage_error "--methods: unknown integrator 'fast'" bench convergence --methods naive,fast
expect_usage_error "--reference: needs exactly one size" bench convergence --reference b.pfm
expect_usage_error "--reference: b.pfm is 2x1, not 16x12" bench convergence --sizes 16x12 \
    --reference b.pfm
expect_usage_error "--budget: expected a number" bench convergence --budget 0
expect_usage_error "--width: not an option of this benchmark" bench convergence --width 5
# naive cannot render a scene lit by a point light (no next-event estimation): refused
# before the reference is rendered (exit 2, nothing written), not as a render failure
# after it (exit 1).
cat >point.json <<'EOF'
{"camera": {"position": [0, 0.3, -1.2], "look_at": [0, 0.3, 0], "fov": 60},
 "materials": {"white": {"type": "diffuse", "color": [0.7, 0.7, 0.7]}},
 "shapes": [{"type": "box", "position": [0, 0, 0], "scale": [0.5, 0.5, 0.5], "material": "white"}],
 "lights": [{"type": "point", "position": [0, 1, -1], "intensity": 2}]}
EOF
expect_usage_error "naive" bench convergence point.json --sizes 16x12 --methods pt,naive \
    --budget 0.2 --reference-spp 8 --out pointconv
rm -f point.json

cli_end cli_compare
