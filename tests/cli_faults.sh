#!/bin/sh
# Faults around the trac0r command: what an attacker or an unlucky user can do
# to it must end in a clear error and an exit status, never a crash, a hang, code run, a
# lost or partial file. Each check fails without its fix.
# Usage: cli_faults.sh TRAC0R_BINARY SCRATCH_DIR
set -u
. "$(dirname "$0")/common.sh"
SRC=$(cd "$(dirname "$0")/.." && pwd)
MESH=$SRC/tests/data/mesh
cli_begin "$1" "$2"
T="timeout 20"

# no_temps WHAT: no PATH.tmp.XXXXXX file is left in the scratch directory.
no_temps() {
    left=$(find . -name '*.tmp.*' | head -n 3)
    [ -z "$left" ] || fail "$1: temporary files left: $left"
}

# scene_with_mesh PATH: a scene file (s.json) with one emitter plane and the mesh PATH.
scene_with_mesh() {
    printf '{"camera": {"position": [0, 0, -3], "look_at": [0, 0, 0], "fov": 60},
 "materials": {"lamp": {"type": "emitter", "color": [1, 1, 1], "emittance": 1}},
 "shapes": [{"type": "plane", "material": "lamp"}],
 "meshes": [{"path": "%s", "material": "lamp"}]}\n' "$1" >s.json
}

# --- crashes, hangs and injection ---------------------------------------------------
# OpenMP's default team size is clamped like --threads (it overflowed the team's stack).
OMP_NUM_THREADS=100000 $T "$BIN" render --width 8 --height 8 --spp 1 --out omp.pfm \
    >/dev/null 2>err.txt
rc=$?
[ "$rc" -eq 0 ] || fail "OMP_NUM_THREADS=100000 render: exit $rc: $(cat err.txt)"

# An output prefix is never gnuplot code: the plot is still drawn, nothing is run.
prefix="x'; system('touch PWNED'); y='"
$T "$BIN" bench complexity --width 8 --height 8 --max-level 0 --frames 1 --accels bvh \
    --out "$prefix" >out.txt 2>err.txt
rc=$?
[ "$rc" -eq 0 ] || fail "bench complexity with a quote in --out: exit $rc: $(cat err.txt)"
[ ! -e PWNED ] || fail "bench complexity: the --out prefix ran as gnuplot code"
[ -s "$prefix.png" ] || fail "bench complexity: no plot for a prefix with a quote: $(cat out.txt)"
rm -f -- "$prefix.csv" "$prefix.png" PWNED

# FIFOs as a scene file, a mesh, an OBJ's mtllib and a glTF buffer: refused, not waited on.
mkfifo fifo.json fifo.obj
$T "$BIN" info fifo.json >/dev/null 2>err.txt
rc=$?
[ "$rc" -eq 2 ] || fail "info on a FIFO scene: exit $rc (124: hung): $(cat err.txt)"
scene_with_mesh "$PWD/fifo.obj"
$T "$BIN" info s.json >/dev/null 2>err.txt
rc=$?
[ "$rc" -eq 2 ] || fail "a FIFO mesh: exit $rc (124: hung): $(cat err.txt)"
mkdir -p model
mkfifo model/lib.mtl model/buf.bin
printf 'mtllib lib.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n' >model/m.obj
scene_with_mesh "$PWD/model/m.obj"
$T "$BIN" info s.json >/dev/null 2>err.txt
rc=$?
[ "$rc" -eq 2 ] || fail "an mtllib FIFO: exit $rc (124: hung): $(cat err.txt)"
sed 's|"uri": "data:[^"]*"|"uri": "buf.bin"|' "$MESH/tri.gltf" >model/m.gltf
grep -q '"buf.bin"' model/m.gltf || fail "test setup: no buffer uri replaced in tri.gltf"
scene_with_mesh "$PWD/model/m.gltf"
$T "$BIN" info s.json >/dev/null 2>err.txt
rc=$?
[ "$rc" -eq 2 ] || fail "a glTF buffer FIFO: exit $rc (124: hung): $(cat err.txt)"
mkfifo fifo.pfm fifo.ttf
"$BIN" render --width 8 --height 8 --spp 1 --out ok.pfm >/dev/null 2>&1
$T "$BIN" compare fifo.pfm ok.pfm >/dev/null 2>err.txt
rc=$?
[ "$rc" -eq 2 ] || fail "compare with a FIFO image: exit $rc (124: hung): $(cat err.txt)"
if "$BIN" view --help >/dev/null 2>&1; then
    $T "$BIN" view --font fifo.ttf >/dev/null 2>err.txt
    rc=$?
    [ "$rc" -eq 2 ] || fail "view --font FIFO: exit $rc (124: hung): $(cat err.txt)"
fi
rm -rf model fifo.json fifo.obj fifo.pfm fifo.ttf ok.pfm s.json

# No display reachable: SDL's offscreen fallback is refused instead of spinning for ever.
if "$BIN" view --help >/dev/null 2>&1; then
    env -u DISPLAY -u SDL_VIDEODRIVER WAYLAND_DISPLAY=nowhere XDG_RUNTIME_DIR=/nonexistent \
        $T "$BIN" view --width 32 --height 24 >/dev/null 2>err.txt
    rc=$?
    [ "$rc" -eq 2 ] || fail "view with an unreachable display: exit $rc (124: hung): $(cat err.txt)"
fi

# --- data written wrongly, or not at all --------------------------------------------
# Modes: 0666 less the umask for a new file; a replaced file keeps its mode.
(umask 002 && "$BIN" render --width 8 --height 8 --spp 1 --out m.png >/dev/null 2>&1)
[ "$(stat -c %a m.png)" = 664 ] || fail "new image under umask 002: mode $(stat -c %a m.png)"
chmod 0640 m.png
(umask 077 && "$BIN" render --width 8 --height 8 --spp 1 --out m.png >/dev/null 2>&1)
[ "$(stat -c %a m.png)" = 640 ] || fail "replaced image: mode $(stat -c %a m.png), expected 640"
rm -f m.png

# A file-size limit (a full disk): exit 1, the reason said, nothing partial, no temporary.
(ulimit -f 8 && exec "$BIN" render --width 256 --height 256 --spp 1 --out big.pfm) \
    >/dev/null 2>err.txt
rc=$?
[ "$rc" -eq 1 ] || fail "render past ulimit -f: exit $rc, expected 1: $(cat err.txt)"
[ ! -e big.pfm ] || fail "render past ulimit -f: wrote a partial big.pfm"
(ulimit -f 8 && exec "$BIN" bench complexity --width 8 --height 8 --max-level 0 --frames 1 \
    --accels bvh --out cx) >out.txt 2>err.txt
rc=$?
[ "$rc" -eq 1 ] || fail "bench complexity past ulimit -f: exit $rc, expected 1: $(cat out.txt err.txt)"
grep -q "^wrote" out.txt && fail "bench complexity past ulimit -f: claims it wrote: $(cat out.txt)"
[ ! -e cx.png ] || fail "bench complexity past ulimit -f: a partial cx.png"
(ulimit -f 1 && exec "$BIN" bench convergence --sizes 16x12 --budget 0.2 --reference-spp 4 \
    --out conv) >out.txt 2>err.txt
rc=$?
[ "$rc" -eq 1 ] || fail "bench convergence past ulimit -f: exit $rc, expected 1: $(cat err.txt)"
[ ! -e conv.csv ] || fail "bench convergence past ulimit -f: a partial conv.csv"
no_temps "past ulimit -f"
rm -f cx.csv cx.png conv.csv conv.png

# A signal while a file is being written: the temporary file goes, the signal ends the
# program. A slow gnuplot holds bench's plot open until the signal (it writes a byte a
# tenth of a second, and ends when trac0r has gone: SIGPIPE). A background job starts
# with SIGINT ignored, which trac0r respects; env gives it the default back.
mkdir -p slow
printf '#!/bin/sh\nwhile printf x; do sleep 0.1; done\n' >slow/gnuplot
chmod +x slow/gnuplot
for sig in TERM INT HUP; do
    PATH=$PWD/slow:$PATH env --default-signal=INT "$BIN" bench complexity --width 8 --height 8 --max-level 0 --frames 1 \
        --accels bvh --out sig >/dev/null 2>&1 &
    pid=$!
    n=0
    # The file being written: sig.png.tmp.XXXXXX, or where the file system has O_TMPFILE
    # an open descriptor of an unnamed file in this directory.
    while [ -z "$(find . -maxdepth 1 -name 'sig.png.tmp.*')" ] &&
        ! ls -l /proc/$pid/fd 2>/dev/null | grep -qF "$PWD/#" && [ "$n" -lt 200 ]; do
        sleep 0.05
        n=$((n + 1))
    done
    [ "$n" -lt 200 ] || fail "SIG$sig: the plot's temporary file never appeared"
    kill -"$sig" "$pid"
    wait "$pid"
    rc=$?
    [ "$rc" -gt 128 ] || fail "SIG$sig while writing: exit $rc, expected death by the signal"
    no_temps "SIG$sig while writing"
    rm -f sig.csv
done
rm -rf slow

# An output that names a directory is refused before the work (a long render here).
mkdir d.png d.pfm
$T "$BIN" render --width 64 --height 64 --spp 1000000 --out d.png >/dev/null 2>err.txt
rc=$?
[ "$rc" -eq 2 ] || fail "render --out DIRECTORY: exit $rc, expected 2 at once: $(cat err.txt)"
"$BIN" render --width 8 --height 8 --spp 1 --out a.pfm >/dev/null 2>&1
$T "$BIN" compare a.pfm a.pfm --error-image d.pfm >/dev/null 2>err.txt
rc=$?
[ "$rc" -eq 2 ] || fail "compare --error-image DIRECTORY: exit $rc, expected 2: $(cat err.txt)"
if "$BIN" view --help >/dev/null 2>&1; then
    $T "$BIN" view --width 16 --height 16 --frames 100000 --screenshot d.png >/dev/null 2>err.txt
    rc=$?
    [ "$rc" -eq 2 ] || fail "view --screenshot DIRECTORY: exit $rc, expected 2: $(cat err.txt)"
fi
rmdir d.png d.pfm

# Standard output that cannot be written is a failure.
"$BIN" compare a.pfm a.pfm >/dev/full 2>/dev/null
rc=$?
[ "$rc" -eq 1 ] || fail "compare > /dev/full: exit $rc, expected 1"
"$BIN" info builtin:cornell >/dev/full 2>/dev/null
rc=$?
[ "$rc" -eq 1 ] || fail "info > /dev/full: exit $rc, expected 1"
"$BIN" --help >/dev/full 2>/dev/null
rc=$?
[ "$rc" -eq 1 ] || fail "--help > /dev/full: exit $rc, expected 1"
"$BIN" render --help >/dev/full 2>/dev/null
rc=$?
[ "$rc" -eq 1 ] || fail "render --help > /dev/full: exit $rc, expected 1"
rm -f a.pfm omp.pfm

# --- messages -----------------------------------------------------------------------
# A film that does not fit in memory is a failure while working (1), not a usage error.
# The sanitizers reserve more address space than any ulimit -v leaves; there the
# allocator is told to fail large allocations instead.
if [ -n "${ASAN_OPTIONS:-}" ]; then
    ASAN_OPTIONS="$ASAN_OPTIONS:allocator_may_return_null=1:max_allocation_size_mb=256" \
        "$BIN" render --width 16384 --height 4096 --spp 1 --threads 1 --out oom.pfm \
        >/dev/null 2>err.txt
    rc=$?
else
    (ulimit -v 600000 && exec "$BIN" render --width 16384 --height 4096 --spp 1 --threads 1 \
        --out oom.pfm) >/dev/null 2>err.txt
    rc=$?
fi
[ "$rc" -eq 1 ] || fail "film out of memory: exit $rc, expected 1: $(cat err.txt)"
grep -q -- "--width" err.txt && fail "film out of memory blames --width/--height: $(cat err.txt)"

# The subdivisions message gives the range that holds (0..9), whatever the wrong value.
printf '{"camera": {"position": [0, 0, -3], "look_at": [0, 0, 0], "fov": 60},
 "materials": {"l": {"type": "emitter", "color": [1, 1, 1], "emittance": 1}},
 "shapes": [{"type": "icosphere", "subdivisions": 2.5, "material": "l"}]}\n' >sub.json
"$BIN" info sub.json >/dev/null 2>err.txt
rc=$?
[ "$rc" -eq 2 ] || fail "subdivisions 2.5: exit $rc"
grep -q "0\.\.9" err.txt || fail "subdivisions 2.5: the range is not 0..9: $(cat err.txt)"
rm -f sub.json

# A second SCENE is an unexpected argument, not an unknown option.
"$BIN" render a.json b.json >/dev/null 2>err.txt
rc=$?
[ "$rc" -eq 2 ] || fail "two scenes: exit $rc"
grep -q "unknown option" err.txt && fail "two scenes: called an unknown option: $(cat err.txt)"
grep -q "b.json" err.txt || fail "two scenes: the extra argument is not named: $(cat err.txt)"

# A PNG that cannot be written: one line, with the reason (besides the progress lines).
(ulimit -f 4 && exec "$BIN" render --width 256 --height 256 --spp 1 --out w.png) \
    >/dev/null 2>err.txt
rc=$?
[ "$rc" -eq 1 ] || fail "PNG past ulimit -f: exit $rc, expected 1: $(cat err.txt)"
[ "$(grep -vc "elapsed" err.txt)" -eq 1 ] || fail "PNG past ulimit -f: not one line: $(cat err.txt)"
grep -q "File too large" err.txt || fail "PNG past ulimit -f: no reason: $(cat err.txt)"
no_temps "PNG past ulimit -f"

# A long path does not crowd the reason out.
long=$(printf 'd%.0s' $(seq 1 240))
"$BIN" render --width 8 --height 8 --spp 1 --out "$long/$long/$long/x.png" >/dev/null 2>err.txt
rc=$?
[ "$rc" -eq 2 ] || fail "long --out path: exit $rc"
grep -q "No such file or directory" err.txt || fail "long --out path: no reason: $(cut -c 1-80 err.txt)..."

# Five structures for --accels: "more than four", not "unknown".
"$BIN" bench complexity --accels bvh,bvh,bvh,bvh,bvh >/dev/null 2>err.txt
rc=$?
[ "$rc" -eq 2 ] || fail "--accels with five: exit $rc"
grep -q "unknown" err.txt && fail "--accels with five: called unknown: $(cat err.txt)"

# Installed OpenCL drivers that cannot load for want of memory: status 1, not "no OpenCL
# platform" (2). Needs OpenCL in the build and a working driver; not under the sanitizers,
# whose shadow memory no ulimit -v leaves room for.
if [ -z "${ASAN_OPTIONS:-}" ] && "$BIN" info --devices >/dev/null 2>&1; then
    (ulimit -v 200000 && exec "$BIN" info --devices) >/dev/null 2>err.txt
    rc=$?
    [ "$rc" -eq 1 ] || fail "info --devices with 200 MB: exit $rc, expected 1: $(cat err.txt)"
fi
rm -f err.txt out.txt

cli_end cli_faults
