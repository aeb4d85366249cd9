#!/bin/sh
# `--out x.exr`: an EXR written by trac0r, read back by readers that are not trac0r's -
# exrheader for its channels and size, exr_dump (OpenEXR's C++ library) for its pixels -
# holds the pixels and passes of the PFM files of the same render, bit for bit in float,
# and Imath's half rounding of them in half. compare reads EXR too.
# Usage: exr_check.sh TRAC0R_BINARY SCRATCH_DIR EXR_DUMP EXRHEADER
set -u
. "$(dirname "$0")/common.sh"
cli_begin "$1" "$2"
DUMP=$3
EXRHEADER=$4

R="render --width 40 --height 30 --spp 4 --threads 1"
"$BIN" $R --passes all --out ref.pfm 2>err.txt || fail "PFM render: $(cat err.txt)"
"$BIN" $R --passes all --out f.exr 2>err.txt || fail "EXR render: $(cat err.txt)"
"$BIN" $R --passes all --out h.exr --exr-type half 2>err.txt || fail "half EXR render: $(cat err.txt)"
[ -e f.albedo.pfm ] && fail "an EXR render wrote its passes as PFM files too"

"$EXRHEADER" f.exr >hdr.txt 2>&1 || fail "exrheader cannot read f.exr: $(cat hdr.txt)"
for ch in R G B albedo.R albedo.G albedo.B normal.X normal.Y normal.Z depth.Z variance.R \
    variance.G variance.B; do
    grep -q "^ *$ch, 32-bit floating-point" hdr.txt || fail "f.exr: no float channel $ch"
done
grep -q "^ *id, 32-bit unsigned integer" hdr.txt || fail "f.exr: no integer channel id"
grep -q "dataWindow.*(0 0) - (39 29)" hdr.txt || fail "f.exr: data window is not 40x30"
"$EXRHEADER" h.exr >hdrh.txt 2>&1 || fail "exrheader cannot read h.exr"
grep -q "^ *R, 16-bit floating-point" hdrh.txt || fail "h.exr: R is not half"
"$BIN" $R --out plain.exr 2>/dev/null
"$EXRHEADER" plain.exr | grep -q "albedo" && fail "plain.exr has passes nobody asked for"

# Pixels, as OpenEXR's own library reads them.
for layer in "" albedo normal depth variance; do
    name=${layer:-rgb}
    ref=ref.pfm
    [ -n "$layer" ] && ref=ref.$layer.pfm
    "$DUMP" f.exr "$layer" "f.$name.pfm" || fail "exr_dump f.exr layer '$layer'"
    cmp -s "f.$name.pfm" "$ref" || fail "f.exr layer '$name' differs from $ref"
    "$DUMP" h.exr "$layer" "h.$name.pfm" || fail "exr_dump h.exr layer '$layer'"
    "$DUMP" --half "$ref" "want.$name.pfm" || fail "exr_dump --half $ref"
    cmp -s "h.$name.pfm" "want.$name.pfm" || fail "h.exr layer '$name' is not $ref rounded to half"
done

# --denoise filters R, G, B only: the variance layer stays that of the rendered estimate.
"$BIN" $R --passes variance --denoise --out d.exr 2>err.txt || fail "denoised EXR: $(cat err.txt)"
"$DUMP" d.exr variance d.variance.pfm || fail "exr_dump d.exr layer 'variance'"
cmp -s d.variance.pfm ref.variance.pfm || fail "d.exr: --denoise changed the variance layer"
"$DUMP" d.exr "" d.rgb.pfm || fail "exr_dump d.exr"
cmp -s d.rgb.pfm ref.pfm && fail "d.exr: --denoise left R, G, B unfiltered"

# compare reads EXR: the float file equals the PFM, the half one is close but not equal.
"$BIN" compare f.exr ref.pfm >cmp.txt 2>&1 || fail "compare f.exr: $(cat cmp.txt)"
grep -q "^rmse 0$" cmp.txt || fail "compare f.exr ref.pfm: $(cat cmp.txt)"
"$BIN" compare h.exr ref.pfm >cmp.txt 2>&1 || fail "compare h.exr: $(cat cmp.txt)"
grep -q "^rmse 0$" cmp.txt && fail "compare h.exr ref.pfm: a half file equals the float one"
rm -f err.txt cmp.txt
printf 'v/2\001junk' >bad.exr
expect_usage_error "bad.exr" compare bad.exr ref.pfm
expect_usage_error "--exr-type: expected half or float" $R --out x.exr --exr-type double

cli_end cli_exr
