#!/bin/sh
# scripts/gpu-measure in its --quick mode on PoCL: every part runs end to end and writes its
# row of the one table (the figures themselves are not checked: tiny sizes on a CPU
# device); a failing command gives a failed row and exit status 1, a bad option status 2.
# Usage: cli_opencl_measure.sh TRAC0R_BINARY SCRATCH_DIR
set -u
. "$(dirname "$0")/common.sh"
SRC=$(cd "$(dirname "$0")/.." && pwd)
cli_begin "$1" "$2"
script=$SRC/scripts/gpu-measure

# textured-demo.json names Assimp's test models relative to itself: a copy of the scenes
# with the installed models linked beside it (a clean checkout has no link).
cp -R "$SRC/scenes" scenes
rm -rf scenes/assimp-models
ln -s /usr/share/assimp/models scenes/assimp-models
sh "$script" --quick --bin "$BIN" --scenes "$PWD/scenes" --out table.md 2>err.txt ||
    fail "gpu-measure --quick: exit status $?: $(cat err.txt)"
[ -s table.md.log ] || fail "gpu-measure wrote no log"
grep -q "^| figure | command | result |" table.md || fail "no table header: $(cat table.md)"
rows() { grep -c "^| $1" table.md; }
[ "$(grep -c '^| program build, .* | [0-9.]* s (the whole command) |$' table.md)" -eq 3 ] ||
    fail "not 3 program build rows with times: $(cat table.md)"
[ "$(rows 'rays, builtin:')" -eq 2 ] || fail "not 2 rays rows: $(cat table.md)"
[ "$(grep -c '^| rays.*bvh, .*cwbvh, .*primary [0-9.]*, diffuse [0-9.]*, shadow [0-9.]* Mrays/s |$' table.md)" -eq 2 ] ||
    fail "rays rows without the bvh and cwbvh rates (or with a note): $(cat table.md)"
[ "$(grep -c '^| thesis settings, .*[0-9] FPS (' table.md)" -eq 3 ] ||
    fail "not 3 thesis rows with FPS: $(cat table.md)"
for bvh in bvh2 cwbvh; do
    grep -q "^| thesis settings, bvh, $bvh | .*--device-bvh $bvh\` | .*[0-9] FPS (" table.md ||
        fail "no thesis row for $bvh: $(cat table.md)"
    grep -q "^| pt samples/s, 32x24, $bvh | .*--device-bvh $bvh\` | .* Msamples/s" table.md ||
        fail "no pt samples/s row for $bvh: $(cat table.md)"
done
grep -q '^| figure 3.5 .*FPS at 56 triangles' table.md || fail "no figure 3.5 row: $(cat table.md)"
for int in pt "pt wavefront" bdpt vcm; do
    grep -q "^| $int samples/s, 32x24[ ,].* Msamples/s" table.md ||
        fail "no $int samples/s row: $(cat table.md)"
done
# Six scenes at two sizes, the classic box at the second size from a quarter of the pixels,
# and ReSTIR DI on the device (every pixel, a quarter of them) at the first size.
[ "$(grep -c '^| real time, .* FPS, [0-9.]* dB mean' table.md)" -eq 25 ] ||
    fail "not 25 real-time rows with FPS and dB: $(cat table.md)"
grep -q '^| real time, cornell-classic, 48x32, 1/4 of the pixels | .*--fraction 1/4.* FPS' table.md ||
    fail "no quarter-of-the-pixels row at the second size: $(cat table.md)"
[ "$(grep -c '^| real time, .*, 32x24, --restir di .* FPS, [0-9.]* dB mean' table.md)" -eq 12 ] ||
    fail "not 12 ReSTIR DI rows with FPS and dB: $(cat table.md)"
if grep -q 'failed' table.md; then fail "a failed row: $(cat table.md)"; fi
rm -f table.md table.md.log err.txt

# --no-variants: the real-time part's six scenes at one size, without the ReSTIR rows.
sh "$script" --quick --bin "$BIN" --scenes "$PWD/scenes" --only realtime --sizes 16x12 \
    --no-variants --out nv.md 2>err.txt || fail "gpu-measure --no-variants: exit status $?"
[ "$(grep -c '^| real time, .*, 16x12 | .* FPS, [0-9.]* dB mean' nv.md)" -eq 6 ] ||
    fail "--no-variants: not 6 real-time rows: $(cat nv.md)"
if grep -q 'restir' nv.md; then fail "--no-variants: a ReSTIR row: $(cat nv.md)"; fi
rm -f nv.md nv.md.log err.txt

# A device that does not exist: every row of the part says failed, exit status 1.
sh "$script" --quick --bin "$BIN" --only frame --device opencl:7 --out bad.md 2>/dev/null
[ $? -eq 1 ] || fail "gpu-measure on a missing device: exit status not 1"
[ "$(grep -c '^| thesis settings.*\*\*failed\*\*: .*does not exist' bad.md)" -eq 3 ] ||
    fail "no failed rows for a missing device: $(cat bad.md)"
rm -f bad.md bad.md.log
# Usage errors: status 2, nothing written.
sh "$script" --only bogus --bin "$BIN" --out u.md 2>/dev/null
[ $? -eq 2 ] || fail "gpu-measure --only bogus: exit status not 2"
[ ! -e u.md ] || fail "gpu-measure --only bogus wrote a table"
sh "$script" --frobnicate 2>/dev/null
[ $? -eq 2 ] || fail "gpu-measure --frobnicate: exit status not 2"

cli_end cli_opencl_measure
