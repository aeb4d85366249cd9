#!/bin/sh
# features.sh - trac0r `pt` against Cycles on the one-feature scenes of tools/cycles/test/
# (docs/cycles.md, "Lights, cameras and the environment"): each scene rendered by both in two
# independent halves (two seeds), then tools/cycles/pfmtool.py compare: the relative MSE of
# trac0r's mean against Cycles' with both renderers' own noise taken out, and 8 x 8 block
# means in units of their noise.
#
#     tools/cycles/features.sh [--size 128x96] [--spp 512] [--threads 1]
#         [--trac0r build/release/trac0r] [--blender blender] [--out cycles-features]
#         [--set lights|principled]
#         [SCENE.json...]     (default: --set lights, the eight scenes of lights, cameras
#                             and the environment in tools/cycles/test/ but
#                             shapes-left.json; --set principled: the five principled
#                             spheres, principled-*.json)
#
# Output: OUT/NAME-{trac0r,cycles}-{1,2}.pfm and their means OUT/NAME-{trac0r,cycles}.pfm,
# OUT/NAME.png (the means side by side and their difference), OUT/summary.txt (one block per
# scene, with the render times). Blender is a measuring instrument only: it is no dependency of trac0r.
set -eu

here=$(cd "$(dirname "$0")" && pwd)
size=128x96
spp=512
threads=1
trac0r=build/release/trac0r
blender=blender
out=cycles-features
set=lights

die() {
    echo "features.sh: $*" >&2
    exit 2
}

while [ $# -gt 0 ]; do
    case $1 in
    --size | --spp | --threads | --trac0r | --blender | --out | --set)
        [ $# -ge 2 ] || die "$1 needs a value"
        case $1 in
        --size) size=$2 ;;
        --spp) spp=$2 ;;
        --threads) threads=$2 ;;
        --trac0r) trac0r=$2 ;;
        --blender) blender=$2 ;;
        --out) out=$2 ;;
        --set) set=$2 ;;
        esac
        shift 2
        ;;
    --*) die "unknown option '$1'" ;;
    *) break ;;
    esac
done
if [ $# -eq 0 ] && [ "$set" = principled ]; then
    set -- "$here/test/principled-metal-rough.json" "$here/test/principled-metal-smooth.json" \
        "$here/test/principled-plastic.json" "$here/test/principled-clearcoat.json" \
        "$here/test/principled-sheen.json"
elif [ $# -eq 0 ]; then
    [ "$set" = lights ] || die "--set: expected lights or principled, got '$set'"
    set -- "$here/test/sky.json" "$here/test/sun.json" "$here/test/point.json" \
        "$here/test/directional.json" "$here/test/spot.json" "$here/test/lens.json" \
        "$here/test/lens-pinhole.json" "$here/test/lens-sun.json"
fi
w=${size%x*}
h=${size#*x}
[ -x "$trac0r" ] || die "$trac0r: not an executable (build trac0r or pass --trac0r)"
mkdir -p "$out"
summary=$out/summary.txt
for scene in "$@"; do
    [ -f "$scene" ] || die "$scene: no such file"
    name=$(basename "$scene" .json)
    {
        echo "== $name: $scene, ${w}x$h, two halves of $spp spp each, $(date -u +%FT%TZ)," \
            "load $(cut -d' ' -f1-3 /proc/loadavg)"
    } >>"$summary"
    for half in 1 2; do
        # Seeds: trac0r 11, 12; Cycles 21, 22 (independent of each other).
        "$trac0r" render "$scene" --width "$w" --height "$h" --spp "$spp" \
            --seed $((10 + half)) --threads "$threads" \
            --out "$out/$name-trac0r-$half.pfm" 2>&1 | tail -n 1 >>"$summary"
        "$blender" -b --factory-startup -P "$here/render_scene.py" -- "$scene" \
            --width "$w" --height "$h" --spp "$spp" --seed $((20 + half)) \
            --threads "$threads" --out "$out/$name-cycles-$half.pfm" 2>&1 |
            grep '^cycles_render_seconds' >>"$summary" ||
            die "$name: Cycles did not render (run render_scene.py by hand to see why)"
    done
    /usr/bin/python3 "$here/pfmtool.py" compare "$out/$name-trac0r-1.pfm" \
        "$out/$name-trac0r-2.pfm" "$out/$name-cycles-1.pfm" "$out/$name-cycles-2.pfm" \
        >>"$summary"
    # Side by side: trac0r's mean, Cycles' mean, their difference x 4 (docs/img/cycles-*.png).
    for r in trac0r cycles; do
        /usr/bin/python3 "$here/pfmtool.py" mean "$out/$name-$r.pfm" "$out/$name-$r-1.pfm" \
            "$out/$name-$r-2.pfm" >/dev/null
    done
    /usr/bin/python3 "$here/pfmtool.py" side "$out/$name.png" "$out/$name-trac0r.pfm" \
        "$out/$name-cycles.pfm" >/dev/null
done
cat "$summary"
