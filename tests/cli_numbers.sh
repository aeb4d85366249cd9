#!/bin/sh
# Numbers follow one set of rules everywhere (trac0r/parse.h): no wrap-around past the
# type (--sizes 4294967304x8, TRAC0R_OPENCL_WORK_GROUP=4294967304x1), no leading blanks
# (--spp " 1"), limits compared in the value's own type (the documented minimums --budget
# 0.1, --svgf-sigma-l 0.1 and a sun's angle 0.001 are accepted), over-long lists refused
# rather than cut to fit (--methods); a sun without its optional angle is read with the
# default.
# Usage: cli_numbers.sh TRAC0R_BINARY SCRATCH_DIR
set -u
. "$(dirname "$0")/common.sh"
cli_begin "$1" "$2"

expect_usage_error "--spp" render --spp " 1" --width 8 --height 8 --out a.png
expect_usage_error "--width" render --width "8 " --height 8 --out a.png
# Each line ends in a bad option, so that a value taken wrongly does not start the work.
expect_usage_error "--sizes" bench convergence --sizes 4294967304x8 --budget 0
expect_usage_error "--sizes" bench convergence --sizes 8x4294967304 --budget 0
long="pt$(printf ',%.0s' $(seq 300))nosuch"
expect_usage_error "--methods" bench convergence --methods "$long" --budget 0
# A documented minimum is accepted: the error names the option after it.
expect_usage_error "--sizes" bench convergence --budget 0.1 --sizes 0x0
expect_usage_error "--frames" bench realtime --svgf-sigma-l 0.1 --frames 0
expect_usage_error "--builds" bench complexity --builds 0
expect_usage_error "--builds" bench complexity --builds 101
expect_usage_error "--frames" bench complexity --builds 100 --frames 0

if "$BIN" render --device opencl --width 8 --height 8 --spp 1 --out wg.png >/dev/null 2>&1; then
    TRAC0R_OPENCL_WORK_GROUP=4294967304x1 "$BIN" render --device opencl --width 8 --height 8 \
        --spp 1 --out wg2.png >/dev/null 2>err.txt
    rc=$?
    [ $rc -eq 2 ] || fail "TRAC0R_OPENCL_WORK_GROUP=4294967304x1: exit $rc, expected 2: $(cat err.txt)"
    rm -f wg.png wg2.png
fi

# The sun: the angle is optional (default 0.526 degrees); 0.001, its documented least, is
# accepted.
sun_scene() { # ANGLE_KEY
    cat >"$1.json" <<EOT
{"version": 1,
 "camera": {"position": [0, 1, 3], "look_at": [0, 0, 0], "fov": 50},
 "materials": {"white": {"type": "diffuse", "color": [0.8, 0.8, 0.8]}},
 "shapes": [{"type": "quad", "material": "white",
             "vertices": [[-1, 0, -1], [1, 0, -1], [1, 0, 1], [-1, 0, 1]]}],
 "sun": {"direction": [0, 1, 0.2]$2}}
EOT
}
sun_scene none ""
sun_scene least ', "angle": 0.001'
for s in none least; do
    "$BIN" render --scene $s.json --width 8 --height 8 --spp 1 --out $s.png >/dev/null 2>err.txt
    rc=$?
    [ $rc -eq 0 ] || fail "a sun ($s): exit $rc, expected 0: $(cat err.txt)"
done

cli_end cli_numbers
