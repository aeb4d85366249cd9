#!/bin/sh
# --device-bvh and TRAC0R_OPENCL_BVH on PoCL: the compressed wide BVH renders the binary
# BVH's image bit for bit (naive and pt, an icosphere box), the summary line and bench
# frame's header name the BVH walked, and bad values are refused with exit status 2.
# Usage: cli_opencl_cwbvh.sh TRAC0R_BINARY SCRATCH_DIR
set -u
. "$(dirname "$0")/common.sh"
cli_begin "$1" "$2"

# Bad values: refused while parsing (render, view, bench frame, bench complexity).
expect_usage_error "--device-bvh" render --device opencl --device-bvh wide --out x.png
expect_usage_error "--device-bvh" render --device-bvh "" --out x.png
expect_usage_error "--device-bvh" view --device opencl --device-bvh BVH2
expect_usage_error "--device-bvh" bench frame --device opencl --device-bvh cw
expect_usage_error "--device-bvh" bench complexity --device opencl --device-bvh 2
# A bad TRAC0R_OPENCL_BVH: the device does not open.
TRAC0R_OPENCL_BVH=wide expect_usage_error "TRAC0R_OPENCL_BVH" render --device opencl --out x.png

args="--scene builtin:cornell-ico-2 --width 32 --height 24 --spp 4 --seed 3 --device opencl"
for int in naive pt; do
    for bvh in bvh2 cwbvh; do
        # shellcheck disable=SC2086
        "$BIN" render $args --integrator $int --device-bvh $bvh --out $bvh.pfm 2>err.txt ||
            fail "render --integrator $int --device-bvh $bvh: $(cat err.txt)"
        grep -q "device bvh $bvh" err.txt || fail "the summary line lacks $bvh: $(cat err.txt)"
    done
    cmp -s bvh2.pfm cwbvh.pfm || fail "$int: the cwbvh image differs from the bvh2 one"
    # shellcheck disable=SC2086
    TRAC0R_OPENCL_BVH=cwbvh "$BIN" render $args --integrator $int --out env.pfm 2>err.txt ||
        fail "TRAC0R_OPENCL_BVH=cwbvh: $(cat err.txt)"
    grep -q "device bvh cwbvh" err.txt || fail "auto does not take the variable: $(cat err.txt)"
    cmp -s bvh2.pfm env.pfm || fail "$int: TRAC0R_OPENCL_BVH=cwbvh's image differs"
    rm -f bvh2.pfm cwbvh.pfm env.pfm err.txt
done

# bench frame's header names the BVH; the CPU takes the option and ignores it.
"$BIN" bench frame --width 16 --height 12 --frames 1 --device opencl --device-bvh cwbvh \
    >bench.txt 2>&1 || fail "bench frame --device-bvh cwbvh: $(cat bench.txt)"
grep "^bench frame:" bench.txt | grep -q "cwbvh" || fail "bench frame's header lacks cwbvh: $(cat bench.txt)"
"$BIN" render --width 16 --height 12 --spp 1 --device-bvh cwbvh --out cpu.png 2>err.txt ||
    fail "--device cpu --device-bvh cwbvh: $(cat err.txt)"
rm -f bench.txt cpu.png err.txt

cli_end cli_opencl_cwbvh
