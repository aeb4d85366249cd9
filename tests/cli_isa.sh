#!/bin/sh
# TRAC0R_ISA picks the wide BVH's traversal (docs/cli.md): every value renders, the same
# image bit for bit (every ISA computes what the scalar code computes), the summary names
# the traversal that ran, and a value the CPU or build cannot honour falls back to the
# automatic choice instead of failing.
# Usage: cli_isa.sh TRAC0R_BINARY SCRATCH_DIR
set -u
. "$(dirname "$0")/common.sh"
cli_begin "$1" "$2"
unset TRAC0R_ISA

R="render --scene builtin:cornell-ico-4 --width 24 --height 18 --spp 3 --threads 2"
# The traversal named in the summary line: "bvh (8-wide NAME...".
isa_of() {
    sed -n 's/.*bvh ([0-9]*-wide \([a-z0-9]*\).*/\1/p' "$1"
}

if "$BIN" $R --out auto.pfm 2>auto.txt; then
    auto=$(isa_of auto.txt)
    [ -n "$auto" ] || fail "no ISA in the summary: $(cat auto.txt)"
else
    fail "render without TRAC0R_ISA failed: $(cat auto.txt)"
    auto=none
fi

for isa in scalar sse2 avx2 avx512 nonsense ""; do
    if TRAC0R_ISA=$isa "$BIN" $R --out "isa_$isa.pfm" 2>err.txt; then
        ran=$(isa_of err.txt)
        cmp -s auto.pfm "isa_$isa.pfm" || fail "TRAC0R_ISA=$isa ($ran): image differs"
        case $isa in
        scalar) [ "$ran" = scalar ] || fail "TRAC0R_ISA=scalar ran $ran" ;;
        nonsense | "") [ "$ran" = "$auto" ] || fail "TRAC0R_ISA='$isa' ran $ran, not $auto" ;;
        *) [ "$ran" = "$isa" ] || [ "$ran" = "$auto" ] ||
            fail "TRAC0R_ISA=$isa ran $ran: neither it nor the automatic $auto" ;;
        esac
    else
        fail "TRAC0R_ISA=$isa: render failed: $(cat err.txt)"
    fi
    rm -f "isa_$isa.pfm" err.txt
done
# The automatic choice is the best the CPU has: asking for it changes nothing.
if TRAC0R_ISA=$auto "$BIN" $R --out best.pfm 2>err.txt; then
    [ "$(isa_of err.txt)" = "$auto" ] || fail "TRAC0R_ISA=$auto ran $(isa_of err.txt)"
else
    fail "TRAC0R_ISA=$auto: render failed: $(cat err.txt)"
fi
rm -f auto.pfm auto.txt best.pfm err.txt

cli_end cli_isa
