#!/bin/sh
# measure.sh - pt against Cycles (docs/cycles.md): for trac0r `pt` and for Blender's Cycles, a
# ladder of sample counts on one scene, the time of each render and its relative MSE against a
# converged reference (`trac0r compare`), then the time each renderer needs to reach a target
# relative MSE (log-log interpolation between the rungs) and their ratio. See docs/cycles.md.
#
#     tools/cycles/measure.sh --reference REF.exr|REF.pfm [--scene scenes/cornell-classic.json]
#         [--size 256x256] [--ladder "16 32 64 128 256 512 1024"] [--target 4.7e-4]
#         [--seed 1] [--threads 0] [--trac0r build/release/trac0r] [--blender blender]
#         [--reference-error 0] [--out cycles-measure]
#
# --reference-error E: the reference's own relative MSE (from two independent halves:
# tools/cycles/pfmtool.py halves), taken off every measured figure before the fit, since
# measured = true + reference's for independent noise. The CSV keeps the measured figures.
#
# Run it on a quiet machine: the renders take turns rung by rung (trac0r, then Cycles, at
# each sample count), so slow drifts of the load hit both. Times:
#   seconds       trac0r: the render time of its summary line (sampling; the scene load and
#                 BVH build excluded); Cycles: its own render_time from the EXR header
#                 (sampling; Blender's start-up, the scene building and Cycles' sync/BVH
#                 build excluded)
#   wall_seconds  the whole process, start-up included, for both
# Output: OUT/measure.csv (renderer,spp,seed,seconds,wall_seconds,relmse), OUT/summary.txt,
# and the images OUT/{trac0r,cycles}-SPP.pfm. Blender is a measuring instrument only: it is
# no dependency of trac0r.
set -eu

here=$(cd "$(dirname "$0")" && pwd)
scene=scenes/cornell-classic.json
size=256x256
ladder="16 32 64 128 256 512 1024"
target=4.7e-4
seed=1
threads=0
trac0r=build/release/trac0r
blender=blender
out=cycles-measure
reference=
referr=0

die() {
    echo "measure.sh: $*" >&2
    exit 2
}

while [ $# -gt 0 ]; do
    [ $# -ge 2 ] || die "$1 needs a value"
    case $1 in
    --scene) scene=$2 ;;
    --size) size=$2 ;;
    --ladder) ladder=$2 ;;
    --target) target=$2 ;;
    --seed) seed=$2 ;;
    --threads) threads=$2 ;;
    --trac0r) trac0r=$2 ;;
    --blender) blender=$2 ;;
    --out) out=$2 ;;
    --reference) reference=$2 ;;
    --reference-error) referr=$2 ;;
    *) die "unknown option '$1'" ;;
    esac
    shift 2
done

[ -n "$reference" ] || die "--reference REF.exr|REF.pfm is required (a converged image of the scene at --size)"
[ -f "$reference" ] || die "--reference: no file '$reference'"
[ -f "$scene" ] || die "--scene: no file '$scene'"
[ -x "$trac0r" ] || die "--trac0r: '$trac0r' is not an executable (build trac0r first)"
command -v "$blender" >/dev/null 2>&1 || die "--blender: '$blender' not found (Debian: apt-get install blender; it is only a measuring instrument)"
case $size in
*x*) width=${size%x*} height=${size#*x} ;;
*) die "--size: expected WxH, got '$size'" ;;
esac
for v in $width $height $seed $threads $ladder; do
    case $v in
    '' | *[!0-9]*) die "expected a non-negative integer, got '$v' (in --size, --seed, --threads or --ladder)" ;;
    esac
done
python3 -c "import sys; t = float(sys.argv[1]); sys.exit(0 if t > 0 else 1)" "$target" 2>/dev/null ||
    die "--target: expected a positive number, got '$target'"
python3 -c "import sys; e = float(sys.argv[1]); sys.exit(0 if e >= 0 else 1)" "$referr" 2>/dev/null ||
    die "--reference-error: expected a number >= 0, got '$referr'"

mkdir -p "$out"
csv=$out/measure.csv
echo "renderer,spp,seed,seconds,wall_seconds,relmse" >"$csv"

now() { date +%s.%N; }
elapsed() { python3 -c "import sys; print('%.3f' % (float(sys.argv[2]) - float(sys.argv[1])))" "$1" "$2"; }

# relmse of IMAGE against the reference, from trac0r compare's output.
relmse_of() {
    "$trac0r" compare "$1" "$reference" | awk '$1 == "relmse" { print $2 }'
}

for spp in $ladder; do
    img=$out/trac0r-$spp.pfm
    t0=$(now)
    "$trac0r" render "$scene" --width "$width" --height "$height" --spp "$spp" --seed "$seed" \
        --threads "$threads" --out "$img" 2>"$out/trac0r-$spp.log" ||
        die "trac0r render failed at $spp spp (see $out/trac0r-$spp.log)"
    t1=$(now)
    # The summary line: "...: 20.76 s, 1.32 Mrays/s -> FILE".
    secs=$(tail -n 1 "$out/trac0r-$spp.log" | sed -n 's/.*: \([0-9.]*\) s, [0-9.]* Mrays\/s -> .*/\1/p')
    [ -n "$secs" ] || die "no render time in trac0r's summary line ($out/trac0r-$spp.log)"
    err=$(relmse_of "$img")
    echo "trac0r,$spp,$seed,$secs,$(elapsed "$t0" "$t1"),$err" >>"$csv"
    echo "trac0r $spp spp: $secs s, relmse $err" >&2

    img=$out/cycles-$spp.pfm
    t0=$(now)
    "$blender" -b --factory-startup -P "$here/render_scene.py" -- "$scene" --width "$width" \
        --height "$height" --spp "$spp" --seed "$seed" --threads "$threads" --out "$img" \
        >"$out/cycles-$spp.log" 2>&1 || die "Cycles render failed at $spp spp (see $out/cycles-$spp.log)"
    t1=$(now)
    secs=$(sed -n 's/^cycles_render_seconds=\([0-9.]*\) .*/\1/p' "$out/cycles-$spp.log")
    [ -n "$secs" ] || die "no cycles_render_seconds line in $out/cycles-$spp.log"
    err=$(relmse_of "$img")
    echo "cycles,$spp,$seed,$secs,$(elapsed "$t0" "$t1"),$err" >>"$csv"
    echo "cycles $spp spp: $secs s, relmse $err" >&2
done

{
    echo "scene $scene, ${width}x${height}, seed $seed, threads $threads (0: all), reference $reference"
    echo "relative MSE (mean of (a - r)^2 / (r^2 + 0.01), trac0r compare) at equal spp:"
    awk -F, 'NR > 1 { e[$1 "," $2] = $6; s[$2] = 1 }
        END { for (n in s) printf "  %6d spp: trac0r %s, cycles %s\n", n, e["trac0r," n], e["cycles," n] }' \
        "$csv" | sort -n -k1
    echo "time to relative MSE $target (render seconds; log-log interpolation; reference's own error $referr taken off):"
    python3 "$here/pfmtool.py" fit "$csv" "$target" "$referr" | sed 's/^/  /'
    echo "the same on the wall time of the whole process (start-up included):"
    awk -F, 'BEGIN { OFS = "," } NR > 1 { t = $4; $4 = $5; $5 = t } { print }' "$csv" >"$out/wall.csv"
    python3 "$here/pfmtool.py" fit "$out/wall.csv" "$target" "$referr" | sed 's/^/  /'
} >"$out/summary.txt"
cat "$out/summary.txt"
