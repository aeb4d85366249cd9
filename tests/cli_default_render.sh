#!/bin/sh
# `trac0r render` without --spp: adaptive sampling up to 64 spp, then the offline
# denoiser. The image is deterministic for a seed (any thread count), the summary says what
# stopped it, --no-denoise writes the adaptive render alone (which is then not the
# denoised one), and a stated --spp keeps the fixed count without denoising.
# Usage: cli_default_render.sh TRAC0R_BINARY SCRATCH_DIR
set -u
. "$(dirname "$0")/common.sh"
cli_begin "$1" "$2"

P="render --width 32 --height 24 --seed 4"
"$BIN" $P --threads 1 --out d1.pfm 2>err1.txt || fail "default render: $(cat err1.txt)"
"$BIN" $P --threads 2 --out d2.pfm 2>err2.txt || fail "default render: $(cat err2.txt)"
cmp -s d1.pfm d2.pfm || fail "default renders with 1 and 2 threads differ"
grep -q " spp (of 64, " err1.txt || fail "summary without the cap: $(cat err1.txt)"
grep -Eq "noise threshold reached|cap reached" err1.txt || fail "summary without a reason: $(cat err1.txt)"
"$BIN" $P --no-denoise --out n.pfm 2>/dev/null || fail "--no-denoise render failed"
cmp -s n.pfm d1.pfm && fail "--no-denoise wrote the denoised image"
# The adaptive render alone is the explicit --noise-threshold 0.01 render up to 64 spp.
"$BIN" $P --spp 64 --noise-threshold 0.01 --out a.pfm 2>/dev/null || fail "adaptive render failed"
cmp -s n.pfm a.pfm || fail "--no-denoise is not --spp 64 --noise-threshold 0.01"
# A stated --spp: exactly that many samples, not denoised.
"$BIN" $P --spp 4 --out s.pfm 2>err.txt || fail "--spp 4: $(cat err.txt)"
grep -q " 4 spp, " err.txt || fail "--spp 4 summary: $(cat err.txt)"
rm -f ./*.pfm ./*.txt
cli_end cli_default_render
