#!/bin/sh
# Drives `trac0r ... --device opencl` on PoCL (registered only in builds with the OpenCL
# backend): device listing, a render that matches the CPU's, and the bad configurations
# (no platform, no such device, a scene too big for the device), each one clear line and
# exit status 2, with the CPU backend still working.
# Usage: cli_opencl.sh TRAC0R_BINARY SCRATCH_DIR
set -u
. "$(dirname "$0")/common.sh"
cli_begin "$1" "$2"

# The device list names device 0 with its compute units and memory.
if "$BIN" info --devices >devices.txt 2>err.txt; then
    grep -q "^  0: " devices.txt || fail "info --devices lists no device 0: $(cat devices.txt)"
    grep -q "compute units: [1-9]" devices.txt || fail "info --devices: no compute units"
    grep -q "memory: [1-9][0-9]* MiB" devices.txt || fail "info --devices: no memory size"
else
    fail "info --devices failed: $(cat err.txt)"
fi
rm -f devices.txt err.txt

# Options.
R="render --width 8 --height 6 --spp 1 --out x.png"
expect_usage_error "--device: unknown device 'gpu'" $R --device gpu
expect_usage_error "--device: expected opencl:N with N in 0..1023, got 'opencl:x'" $R --device opencl:x
expect_usage_error "--device: expected opencl:N" $R --device opencl:-1
expect_usage_error "--device: missing value" $R --device
"$BIN" render --help >help.txt 2>&1 && grep -q -- "--device" help.txt ||
    fail "render --help does not mention --device"
"$BIN" bench frame --help >help.txt 2>&1 && grep -q -- "--device" help.txt ||
    fail "bench frame --help does not mention --device"
"$BIN" bench complexity --help >help.txt 2>&1 && grep -q -- "--device" help.txt ||
    fail "bench complexity --help does not mention --device"
rm -f help.txt

# Bad configurations: exit 2, one line; the CPU backend still works afterwards.
expect_usage_error "--device: OpenCL device 7 does not exist" $R --device opencl:7
mkdir empty-icd
OCL_ICD_VENDORS=$PWD/empty-icd
export OCL_ICD_VENDORS
expect_usage_error "--device: no OpenCL platform found" $R --device opencl
"$BIN" info --devices >out.txt 2>err.txt
[ $? -eq 2 ] || fail "info --devices without a platform: exit status not 2"
grep -q "no OpenCL platform found" err.txt || fail "info --devices without a platform: $(cat err.txt)"
rm -f out.txt err.txt
"$BIN" render --width 8 --height 6 --spp 1 --out keep-cpu.png 2>/dev/null ||
    fail "the CPU backend fails when no OpenCL platform exists"
unset OCL_ICD_VENDORS
# PoCL with 1 GiB of memory allocates at most 256 MiB per buffer; the 5 242 880
# triangles of cornell-ico-9 take 340 MiB (the flat structure needs no BVH build).
POCL_MEMORY_LIMIT=1
export POCL_MEMORY_LIMIT
expect_usage_error "does not fit on OpenCL device 0" render --scene builtin:cornell-ico-9 \
    --accel flat --width 8 --height 6 --spp 1 --device opencl --out x.png
unset POCL_MEMORY_LIMIT
"$BIN" render --width 8 --height 6 --spp 1 --out keep-cpu.png 2>/dev/null ||
    fail "the CPU backend fails after an OpenCL error"

# vcm on the device: the same light subpaths, buckets and merges as on the CPU, so the
# two images agree far below the noise (the device's exp, pow, sin and cos differ from
# glibc's in the last bits: docs/opencl.md). bdpt renders the sun and the sky on the device
# as on the CPU.
"$BIN" render --width 32 --height 24 --spp 4 --device opencl --integrator vcm --out vc-cl.pfm \
    >/dev/null 2>err.txt || fail "vcm on OpenCL: exit status $?: $(cat err.txt)"
"$BIN" render --width 32 --height 24 --spp 4 --integrator vcm --out vc-cpu.pfm >/dev/null 2>&1 ||
    fail "vcm on the CPU failed"
psnr=$("$BIN" compare vc-cl.pfm vc-cpu.pfm | awk '/^psnr/ { print $2 }')
awk -v p="$psnr" 'BEGIN { exit !(p == "inf" || p + 0 >= 80) }' ||
    fail "vcm: OpenCL and CPU images only $psnr dB apart"
# Merging off (radius 0): no light pass, the grid one empty bucket; still the CPU's image.
TRAC0R_VCM_RADIUS=0 "$BIN" render --width 32 --height 24 --spp 2 --device opencl --integrator vcm \
    --out vc0-cl.pfm >/dev/null 2>err.txt || fail "vcm, radius 0, on OpenCL: $(cat err.txt)"
TRAC0R_VCM_RADIUS=0 "$BIN" render --width 32 --height 24 --spp 2 --integrator vcm \
    --out vc0-cpu.pfm >/dev/null 2>&1 || fail "vcm, radius 0, on the CPU failed"
psnr=$("$BIN" compare vc0-cl.pfm vc0-cpu.pfm | awk '/^psnr/ { print $2 }')
awk -v p="$psnr" 'BEGIN { exit !(p == "inf" || p + 0 >= 80) }' ||
    fail "vcm, radius 0: OpenCL and CPU images only $psnr dB apart"
# The same with the kernel built as for a device without 64-bit atomics and doubles: the
# splats as 32-bit pairs, folded on the host; the same image bits as with them.
TRAC0R_OPENCL_DISABLE_EXT=cl_khr_int64_base_atomics,cl_khr_fp64 "$BIN" render --width 32 \
    --height 24 --spp 4 --device opencl --integrator vcm --out vc-fb.pfm >/dev/null 2>err.txt ||
    fail "vcm without the extensions: $(cat err.txt)"
cmp -s vc-fb.pfm vc-cl.pfm || fail "vcm without the extensions: another image"
rm -f err.txt
TRAC0R_OPENCL_DISABLE_EXT=cl_khr_fp16 expect_usage_error "TRAC0R_OPENCL_DISABLE_EXT" render \
    --device opencl --integrator bdpt --out x.png
# bdpt's work groups: left to the driver, PoCL's overflowed its stack at 64x48 (a crash).
"$BIN" render --width 64 --height 48 --spp 2 --device opencl --integrator bdpt --out bd64.pfm \
    >/dev/null 2>err.txt
[ $? -eq 0 ] || fail "bdpt at 64x48 on OpenCL: exit status not 0: $(cat err.txt)"
[ -s bd64.pfm ] || fail "bdpt at 64x48 on OpenCL wrote no image"
for dev in cpu opencl; do
    "$BIN" render "$(dirname "$0")/../scenes/window-room.json" --width 8 --height 6 --spp 1 \
        --device $dev --integrator bdpt --out bd-$dev.pfm >/dev/null 2>err.txt
    [ $? -eq 0 ] || fail "bdpt with the sun on $dev: exit status not 0: $(cat err.txt)"
    [ -s bd-$dev.pfm ] || fail "bdpt with the sun on $dev wrote no image"
done
rm -f err.txt

# A device render and a CPU render of the same scene, seed and spp: PFM floats compared
# value by value. Identical is what PoCL gives for this scene (docs/opencl.md); allow at
# most 1 % of the values to differ by more than 1e-4 (relative) and the mean to move by 1 %.
# bdpt too: its light tracing's splats are 64-bit fixed-point sums on both sides (atomic
# adds on the device), folded into the film in double precision after each frame.
for accel in flat bvh embree bdpt-flat bdpt-bvh; do
    int=pt
    case $accel in bdpt-*) int=bdpt accel=${accel#bdpt-} ;; esac
    "$BIN" render --width 24 --height 18 --spp 4 --seed 7 --accel $accel --device opencl \
        --integrator $int --out dev.pfm 2>err.txt ||
        fail "--device opencl --accel $accel --integrator $int failed: $(cat err.txt)"
    grep -q "opencl:0" err.txt || fail "the summary line does not name the device: $(cat err.txt)"
    if [ $accel = embree ]; then
        grep -q "device traces a bvh" err.txt || fail "embree on the device: $(cat err.txt)"
    fi
    "$BIN" render --width 24 --height 18 --spp 4 --seed 7 --accel $accel --integrator $int \
        --out cpu.pfm 2>/dev/null || fail "CPU render failed"
    od -An -v -tf4 -w4 -j 14 dev.pfm >dev.txt
    od -An -v -tf4 -w4 -j 14 cpu.pfm >cpu.txt
    verdict=$(paste dev.txt cpu.txt | awk '
        function abs(v) { return v < 0 ? -v : v }
        { n++; sa += $1; sb += $2
          m = abs($1) > abs($2) ? abs($1) : abs($2)
          if ($1 != $2 && abs($1 - $2) > 1e-4 * m) d++ }
        END { if (n != 24 * 18 * 3) print "count " n;
              else if (d * 100 > n) print "differ " d;
              else if (sa - sb > 0.01 * sb || sb - sa > 0.01 * sb) print "mean " sa " " sb;
              else print "ok " d }')
    case $verdict in
    ok*) ;;
    *) fail "--accel $accel --integrator $int: OpenCL and CPU images disagree: $verdict" ;;
    esac
    rm -f dev.pfm cpu.pfm dev.txt cpu.txt err.txt
done

# Benchmarks accept the device.
"$BIN" bench frame --width 16 --height 12 --frames 2 --device opencl >bench.txt 2>&1 ||
    fail "bench frame --device opencl failed: $(cat bench.txt)"
grep -q "opencl:0" bench.txt || fail "bench frame does not name the device: $(cat bench.txt)"
grep -q "^fps " bench.txt || fail "bench frame printed no fps: $(cat bench.txt)"
grep -q "device/cpu [0-9]" bench.txt || fail "bench frame printed no CPU reference: $(cat bench.txt)"
"$BIN" bench complexity --width 16 --height 12 --frames 1 --max-level 1 --device opencl \
    --out cx >bench.txt 2>&1 || fail "bench complexity --device opencl failed: $(cat bench.txt)"
grep -q "^1,[0-9]*,bvh," cx.csv || fail "complexity CSV lacks the bvh row of level 1: $(cat cx.csv)"
grep -q "^0,.*,flat," cx.csv || fail "complexity CSV lacks the flat row of level 0: $(cat cx.csv)"
if grep -q embree cx.csv; then fail "embree measured on the device: $(cat cx.csv)"; fi
rm -f bench.txt cx.csv cx.png
# bench realtime on the device reconstructs there (recon_device.h): the device's SVGF
# lifts the raw frames' PSNR as the host's does (tests/test_opencl_recon.c checks the
# two agree).
"$BIN" bench realtime "$(dirname "$0")/../scenes/cornell-classic.json" --width 32 --height 24 \
    --frames 4 --reference-spp 16 --methods off,svgf --device opencl --out rt >rt.txt 2>rt.err ||
    fail "bench realtime --device opencl: $(cat rt.err)"
raw=$(awk '$1 == "off" { print $7 }' rt.txt)
svgf=$(awk '$1 == "svgf" { print $7 }' rt.txt)
awk -v a="$raw" -v b="$svgf" 'BEGIN { exit !(b > a + 1) }' ||
    fail "bench realtime --device opencl: svgf $svgf dB vs raw $raw dB"
rm -f rt.txt rt.err rt.csv rt.png
# bench rays on the device: both structures it walks, and the compressed wide BVH converted
# from the binary one, trace the same rays with the same hits (a difference prints a
# note), at a positive rate; Embree is refused there.
"$BIN" bench rays --device opencl --scene builtin:cornell --width 16 --height 12 --runs 1 \
    --accels flat,bvh >rays.txt 2>rays.err || fail "bench rays --device opencl: $(cat rays.err)"
grep -q "on opencl:0" rays.txt || fail "bench rays does not name the device: $(cat rays.txt)"
for accel in flat bvh cwbvh; do
    awk -v a=$accel '$3 == a && $5 > 0 && $6 > 0 && $7 > 0 { ok = 1 } END { exit !ok }' rays.txt ||
        fail "bench rays --device opencl: no $accel row with three rates: $(cat rays.txt)"
done
if grep -q "note:" rays.txt; then fail "bench rays: flat and bvh hit differently: $(cat rays.txt)"; fi
rm -f rays.txt rays.err
expect_usage_error "--accels: embree runs on the CPU only" bench rays --device opencl \
    --accels bvh,embree
expect_usage_error "--accels:" bench complexity --device opencl \
    --accels bvh,embree

# pt as a wavefront (--cl-kernel, TRAC0R_OPENCL_KERNEL): the megakernel's image byte for byte;
# an unknown kernel is the command line's error, in the option or the variable.
W="render --width 21 --height 13 --spp 3 --seed 9 --device opencl"
"$BIN" $W --cl-kernel mega --out mega.pfm 2>err.txt || fail "--cl-kernel mega: $(cat err.txt)"
"$BIN" $W --cl-kernel wavefront --out wave.pfm 2>err.txt || fail "--cl-kernel wavefront: $(cat err.txt)"
TRAC0R_OPENCL_KERNEL=wavefront "$BIN" $W --out env.pfm 2>err.txt ||
    fail "TRAC0R_OPENCL_KERNEL=wavefront: $(cat err.txt)"
cmp -s mega.pfm wave.pfm || fail "--cl-kernel wavefront: not the megakernel's image"
cmp -s mega.pfm env.pfm || fail "TRAC0R_OPENCL_KERNEL=wavefront: not the megakernel's image"
rm -f mega.pfm wave.pfm env.pfm err.txt
"$BIN" bench frame --width 16 --height 12 --frames 2 --device opencl --integrator pt \
    --cl-kernel wavefront >bench.txt 2>&1 || fail "bench frame --cl-kernel wavefront: $(cat bench.txt)"
rm -f bench.txt
expect_usage_error "--cl-kernel:" $R --cl-kernel fast
TRAC0R_OPENCL_KERNEL=fast "$BIN" $W --out x.pfm 2>err.txt
[ $? -eq 2 ] || fail "TRAC0R_OPENCL_KERNEL=fast: not exit status 2: $(cat err.txt)"
rm -f x.pfm err.txt

cli_end cli_opencl
