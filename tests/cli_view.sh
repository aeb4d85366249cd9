#!/bin/sh
# Drives `trac0r view` from the outside: bad input and a missing display fail before
# any window; the headless mode equals `trac0r render`; and in a real X server (Xvfb,
# on a display number it picks itself) the window shows the Cornell box, B toggles the
# debug text, W moves the camera and restarts accumulation, right mouse + motion turns
# it, F12 saves the film `trac0r render` computes, and Esc exits 0 within a second.
# The viewer dumps its window's pixels on SIGUSR1 (--dump-window) and its state to a
# file (--state-file); keys and the mouse come from xdotool through the X server.
# Usage: cli_view.sh TRAC0R_BINARY SCRATCH_DIR
set -u
. "$(dirname "$0")/common.sh"
SRC=$(cd "$(dirname "$0")/.." && pwd)
cli_begin "$1" "$2"
XVFB_PID=
VIEW_PID=

cleanup() {
    [ -n "$VIEW_PID" ] && kill "$VIEW_PID" 2>/dev/null
    [ -n "$XVFB_PID" ] && kill "$XVFB_PID" 2>/dev/null
    wait 2>/dev/null
}
trap cleanup EXIT
trap 'exit 1' INT TERM HUP

# --- bad input: exit 2 and one line naming the fault, before any window -----------
expect_usage_error "unknown option '--bogus'" view --bogus
expect_usage_error "missing-scene.json" view missing-scene.json
expect_usage_error "--frames: needs --screenshot" view --frames 3
expect_usage_error "--stride: expected 1, 2 or 4, got '3'" view --stride 3
expect_usage_error "--recon: expected off, accumulate" view --recon blur
# The reconstruction's settings, parsed as bench realtime parses them.
expect_usage_error "--svgf-iterations" view --svgf-iterations 9
expect_usage_error "--max-history" view --max-history 0
expect_usage_error "--max-history-moving" view --max-history-moving 0
expect_usage_error "--taa" view --taa -0.5
expect_usage_error "--target-fps: expected" view --target-fps 0
expect_usage_error "--benchmark: expected an integer in 0..9, got '10'" view --benchmark 10
expect_usage_error "--screenshot: 'x.jpg' has an unknown extension" view --screenshot x.jpg
expect_usage_error "--font: cannot open 'no-such-font.ttf'" view --font no-such-font.ttf
# No display for the interactive mode: the message names DISPLAY.
env -u DISPLAY -u WAYLAND_DISPLAY -u SDL_VIDEODRIVER "$BIN" view >out.txt 2>err.txt
rc=$?
[ "$rc" -eq 2 ] || fail "view without DISPLAY: exit $rc, expected 2"
grep -q "DISPLAY" err.txt || fail "view without DISPLAY: message lacks DISPLAY: $(cat err.txt)"
[ "$(wc -l <err.txt)" -eq 1 ] || fail "view without DISPLAY: not one line: $(cat err.txt)"
"$BIN" view --help >out.txt || fail "view --help failed"
grep -q "F12" out.txt || fail "view --help does not list F12"
grep -q -- "--svgf-iterations" out.txt || fail "view --help does not list --svgf-iterations"

# --- headless: equals trac0r render, without any display ---------------------------
for args in "--width 40 --height 30" "--width 33 --height 21 --seed 5 --max-depth 3"; do
    # shellcheck disable=SC2086
    env -u DISPLAY SDL_VIDEODRIVER=dummy "$BIN" view $args --frames 5 --screenshot v.png \
        2>err.txt || fail "headless view $args: $(cat err.txt)"
    # shellcheck disable=SC2086
    "$BIN" render $args --spp 5 --out r.png 2>err.txt || fail "render $args: $(cat err.txt)"
    cmp -s v.png r.png || fail "headless view $args differs from render --spp 5"
    # shellcheck disable=SC2086
    "$BIN" render $args --spp 4 --out r4.png 2>/dev/null
    cmp -s v.png r4.png && fail "headless view $args equals a 4-spp render too"
    rm -f v.png r.png r4.png
done
env -u DISPLAY "$BIN" view --benchmark 1 --width 32 --height 24 --frames 3 >out.txt 2>err.txt ||
    fail "benchmark: $(cat err.txt)"
grep -q "benchmark cornell-ico-1 (.* triangles) 32x24, 3 frames.* average FPS" out.txt ||
    fail "benchmark output: $(cat out.txt)"

# --- a real window under Xvfb --------------------------------------------------------
xvfb_start || exit 1
# A display that cannot be opened (screen 7 of a one-screen server): exit 2, naming it.
DISPLAY=$DISPLAY.7 timeout 30 "$BIN" view >out.txt 2>err.txt
rc=$?
[ "$rc" -eq 2 ] || fail "view on $DISPLAY.7: exit $rc, expected 2"
grep -qF "DISPLAY='$DISPLAY.7'" err.txt || fail "view on $DISPLAY.7: message: $(cat err.txt)"
# A state file that cannot be written (a directory) is refused before the window opens.
mkdir -p state.dir
timeout 30 "$BIN" view --state-file state.dir >out.txt 2>err.txt
rc=$?
[ "$rc" -eq 2 ] || fail "view --state-file DIRECTORY: exit $rc, expected 2: $(cat err.txt)"
rmdir state.dir
# SDL's software renderer, and no OpenGL behind the window surface: Mesa is loaded
# with dlopen and unloaded at SDL_Quit, so LeakSanitizer (sanitizer build) could not
# name it in a suppression. The leak check itself covers every interactive run below:
# a leak exits nonzero, and quit_viewer wants status 0.
export SDL_RENDER_DRIVER=software
export SDL_FRAMEBUFFER_ACCELERATION=0

# state KEY: a value from the viewer's state file.
state() {
    awk -v k="$1" '$1 == k { $1 = ""; sub(/^ /, ""); print; exit }' state.txt 2>/dev/null
}
# settled_at STRIDE SPP: the frame on screen belongs to the current view at rest (not a
# moving view's film, whose samples are numbered by frame), at this stride and sample
# count. One read of the file for all of them: spp is not monotonic (it
# restarts with a new view), so values read from two successive versions of the file
# could pass together when neither version does.
settled_at() {
    awk -v stride="$1" -v spp="$2" '$1 == "stride" { s = $2 } $1 == "spp" { p = $2 }
        $1 == "generation" { g = $2 } $1 == "view_generation" { v = $2 } $1 == "moving" { m = $2 }
        END { exit !(s == stride && p == spp && g == v && m == 0) }' state.txt 2>/dev/null
}
# wait_for SECONDS 'shell condition': polls every 50 ms.
wait_for() {
    n=$(($1 * 20))
    while [ "$n" -gt 0 ]; do
        eval "$2" && return 0
        sleep 0.05
        n=$((n - 1))
    done
    return 1
}
# dump FILE: asks the viewer for its window's pixels.
dump() {
    before=$(state dumps)
    kill -USR1 "$VIEW_PID"
    wait_for 20 '[ "$(state dumps)" -gt "$before" ]' || fail "no window dump after SIGUSR1"
    cp window.ppm "$1"
}
# region PPM X0 Y0 X1 Y1: "mean_r mean_g mean_b bright_count" over [X0,X1) x [Y0,Y1),
# bright meaning all channels above 200.
region() {
    # The header is three text lines: P6, "W H", 255.
    w=$(sed -n 2p "$1" | cut -d' ' -f1)
    hdr=$(head -n 3 "$1" | wc -c)
    tail -c +$((hdr + 1)) "$1" | od -An -v -tu1 -w3 |
        awk -v w="$w" -v x0="$2" -v y0="$3" -v x1="$4" -v y1="$5" '
        { x = (NR - 1) % w; y = int((NR - 1) / w)
          if (x >= x0 && x < x1 && y >= y0 && y < y1) {
              r += $1; g += $2; b += $3; n++
              if ($1 > 200 && $2 > 200 && $3 > 200) bright++ } }
        END { printf "%.1f %.1f %.1f %d\n", r / n, g / n, b / n, bright }'
}
# flat PPM: the percentage of pixels, of those neither black nor white, that equal all eight
# of their neighbours: the inside of blocks of 3x3 pixels or more, which a frame shown at a
# third of the window's resolution or less is made of, and a path-traced frame is not.
flat() {
    w=$(sed -n 2p "$1" | cut -d' ' -f1)
    hdr=$(head -n 3 "$1" | wc -c)
    tail -c +$((hdr + 1)) "$1" | od -An -v -tu1 -w3 |
        awk -v w="$w" '{ p[NR - 1] = $1 " " $2 " " $3 }
        END { h = NR / w
              for (y = 1; y < h - 1; y++) for (x = 1; x < w - 1; x++) {
                  c = p[y * w + x]
                  if (c == "0 0 0" || c == "255 255 255") continue
                  n++; same = 1
                  for (dy = -1; dy <= 1; dy++) for (dx = -1; dx <= 1; dx++)
                      if (p[(y + dy) * w + x + dx] != c) same = 0
                  f += same }
              printf "%d\n", n ? 100 * f / n : 0 }'
}
start_viewer() {
    rm -f state.txt window.ppm
    "$BIN" view --width 160 --height 120 --threads 1 --state-file state.txt \
        --dump-window window.ppm --shot-dir shots "$@" >view.out 2>view.err &
    VIEW_PID=$!
    wait_for 30 '[ -s state.txt ]' || fail "viewer wrote no state: $(cat view.err)"
    WID=$(xdotool search --sync --onlyvisible --name '^trac0r view' 2>/dev/null | head -n1)
    [ -n "$WID" ] || fail "no window titled 'trac0r view' appeared"
    xdotool windowfocus "$WID" 2>/dev/null
    sleep 0.2
}
# quit_viewer: Esc must end the process with status 0 within a second. Under the sanitizers
# (the sanitize preset sets ASAN_OPTIONS) the exit itself is slower: LeakSanitizer's scan of
# the heap after main returns took 0.1-0.2 s on a quiet 2-core machine and 0.9-1.0 s with
# three busy processes beside it (the suite runs two tests at once, some with several
# processes), and the frame in flight stops only at its next tile or filter iteration,
# each several times slower instrumented. So there the limit is 5 s; a viewer that ignores
# Esc still fails.
QUIT_LIMIT=1
[ -n "${ASAN_OPTIONS:-}" ] && QUIT_LIMIT=5
quit_viewer() {
    xdotool key Escape
    wait_for "$QUIT_LIMIT" '! kill -0 "$VIEW_PID" 2>/dev/null' ||
        fail "viewer still running $QUIT_LIMIT s after Esc"
    wait "$VIEW_PID"
    rc=$?
    [ "$rc" -eq 0 ] || fail "viewer exit status $rc after Esc: $(cat view.err)"
    VIEW_PID=
}

mkdir -p shots
start_viewer
wait_for 30 '[ "$(state spp)" -ge 32 ]' || fail "fewer than 32 spp after 30 s"
dump plain.ppm
# The Cornell box: not black, the red wall on the left, the green one on the right
# (converged, the walls' regions are (152, 48, 47) and (102, 149, 67)).
set -- $(region plain.ppm 0 0 160 120)
awk -v r="$1" -v g="$2" -v b="$3" 'BEGIN { exit !(r + g + b > 30) }' ||
    fail "window is black: mean $*"
set -- $(region plain.ppm 40 50 52 70)
awk -v r="$1" -v g="$2" 'BEGIN { exit !(r > 1.5 * g && r > 40) }' || fail "left wall not red: $*"
set -- $(region plain.ppm 108 50 120 70)
awk -v r="$1" -v g="$2" 'BEGIN { exit !(g > 1.15 * r && g > 40) }' || fail "right wall not green: $*"
# B: debug text appears in the top-left corner (black outside the room), and goes.
set -- $(region plain.ppm 0 0 60 14)
bright_off=$4
xdotool key b
wait_for 10 '[ "$(state overlay)" = 1 ]' || fail "B did not turn the debug view on"
dump overlay.ppm
set -- $(region overlay.ppm 0 0 60 14)
[ "$4" -gt $((bright_off + 15)) ] || fail "no debug text in the top left: $4 bright vs $bright_off"
xdotool key b
wait_for 10 '[ "$(state overlay)" = 0 ]' || fail "B did not turn the debug view off"
dump off.ppm
set -- $(region off.ppm 0 0 60 14)
[ "$4" -le $((bright_off + 2)) ] || fail "debug text still there: $4 bright vs $bright_off"
# Holding W moves the camera forward (+z here) and starts the accumulation over.
wait_for 30 '[ "$(state spp)" -ge 40 ]' || fail "fewer than 40 spp"
z0=$(state pos | cut -d' ' -f3)
gen0=$(state generation)
xdotool keydown w
sleep 0.4
xdotool keyup w
spp1=$(state spp)
wait_for 10 '[ "$(state generation)" -gt "$gen0" ]' || fail "W did not start a new view"
z1=$(state pos | cut -d' ' -f3)
awk -v a="$z0" -v b="$z1" 'BEGIN { exit !(b > a + 0.05) }' || fail "W: z went $z0 -> $z1"
spp_now=$(state spp)
[ "$spp_now" -lt 40 ] || [ "$spp1" -lt 40 ] || fail "W: spp did not restart ($spp1, $spp_now)"
# Right click, then move the mouse: the view direction turns.
dir0=$(state dir)
xdotool mousemove --window "$WID" 80 60
sleep 0.1
xdotool click 3
wait_for 10 '[ "$(state mouselook)" = 1 ]' || fail "right click did not start mouse-look"
for step in 1 2 3 4 5; do
    xdotool mousemove_relative -- 8 3
    sleep 0.05
done
wait_for 10 '[ "$(state dir)" != "$dir0" ]' || fail "mouse-look: direction stayed $dir0"
xdotool click 3
wait_for 10 '[ "$(state mouselook)" = 0 ]' || fail "second right click did not end mouse-look"
# The other keys, through the state file: 2 (stride 2, a new view), +/- (exposure,
# same view), wheel (speed), H (help), V and ] (BVH boxes, one level deeper), N
# (per-stage timings on stdout).
gen0=$(state generation)
xdotool key 2
wait_for 10 '[ "$(state stride)" = 2 ] && [ "$(state generation)" -gt "$gen0" ]' ||
    fail "2 did not switch to stride 2: stride $(state stride)"
xdotool key 3
wait_for 10 '[ "$(state stride)" = 4 ]' || fail "3 did not switch to stride 4"
xdotool key 1
wait_for 10 '[ "$(state stride)" = 1 ]' || fail "1 did not switch back to stride 1"
# view_generation counts view changes asked for (the end of a move is one: the view restarts
# at full resolution, moving 0), generation is the one on screen.
wait_for 10 '[ "$(state moving)" = 0 ] && [ "$(state generation)" = "$(state view_generation)" ]' || fail "view did not settle"
gen0=$(state view_generation)
xdotool key plus plus minus
wait_for 10 '[ "$(state exposure)" = 0.50 ]' || fail "+ + -: exposure $(state exposure)"
[ "$(state view_generation)" = "$gen0" ] || fail "exposure restarted the accumulation"
speed0=$(state speed)
xdotool click 4
wait_for 10 '[ "$(state speed)" != "$speed0" ]' || fail "wheel did not change the speed"
xdotool key h v bracketright
wait_for 10 '[ "$(state help)" = 1 ] && [ "$(state bvh)" = 1 ] && [ "$(state bvh_depth)" = 4 ]' ||
    fail "H/V/]: help $(state help), bvh $(state bvh), depth $(state bvh_depth)"
dump bvh.ppm
cmp -s bvh.ppm off.ppm && fail "BVH boxes and help changed nothing in the window"
xdotool key n
wait_for 20 'grep -q "^frame [0-9]*: input .* ms, scene rebuild .* ms, render .* ms, film->texture .* ms" view.out' ||
    fail "N printed no per-stage timings: $(head -c 300 view.out)"
# Resizing the window resizes the film: the next frames are 600x450.
xdotool windowsize "$WID" 600 450
wait_for 30 '[ "$(state size)" = "600 450" ] && [ "$(state moving)" = 0 ] && [ "$(state generation)" = "$(state view_generation)" ]' ||
    fail "resize: size $(state size), generation $(state generation)/$(state view_generation)"
dump resized.ppm
[ "$(sed -n 2p resized.ppm)" = "600 450" ] || fail "resized window dump is $(sed -n 2p resized.ppm)"
# A window wider than a film may be (16384) renders scaled down instead of ending the
# viewer; back to 600x450 for what follows.
xdotool windowsize "$WID" 17000 100
wait_for 30 'w17=$(state size | cut -d" " -f1); [ "${w17:-0}" -gt 600 ] && [ "$w17" -le 16384 ]' ||
    fail "window 17000 wide: render size $(state size): $(cat view.err)"
kill -0 "$VIEW_PID" 2>/dev/null || fail "viewer ended on a window wider than a film: $(cat view.err)"
xdotool windowsize "$WID" 600 450
wait_for 30 '[ "$(state size)" = "600 450" ] && [ "$(state generation)" = "$(state view_generation)" ]' ||
    fail "back to 600x450: size $(state size)"
# View changes 30 ms apart, each shorter than a 600x450 frame on one thread: the
# frames in flight are cancelled, and the last change still shows up.
cancelled0=$(state cancelled)
xdotool key --delay 30 2 1 2 1 2 1 2
wait_for 30 '[ "$(state stride)" = 2 ] && [ "$(state moving)" = 0 ] && [ "$(state generation)" = "$(state view_generation)" ]' ||
    fail "after quick stride changes: stride $(state stride)"
[ "$(state cancelled)" -gt "$cancelled0" ] || fail "no frame in flight was cancelled"
quit_viewer

# A right-handed scene (the classic box: red wall on the left) stays the same way round
# after a move, and holding a key keeps the picture live: frames keep being finished and
# shown (the counter rises, the window changes) while the camera changes every 10 ms,
# here with SVGF reconstructing every frame; M cycles the reconstruction.
# sides PPM: exits 0 when the left strip is red and the right one green.
sides() {
    set -- $(region "$1" 4 40 30 80) $(region "$1" 130 40 156 80)
    awk -v lr="$1" -v lg="$2" -v rr="$5" -v rg="$6" \
        'BEGIN { exit !(lr > 1.3 * lg && rg > 1.1 * rr) }'
}
start_viewer --scene "$SRC/scenes/cornell-classic.json" --target-fps 30 --recon svgf
wait_for 30 '[ "$(state spp)" -ge 16 ]' || fail "classic: fewer than 16 spp after 30 s"
[ "$(state mirrored)" = 1 ] || fail "classic: the viewer's camera is not mirrored"
dump classic0.ppm
sides classic0.ppm || fail "classic before a move: red wall not left: $(region classic0.ppm 4 40 30 80)"
xdotool keydown w
sleep 0.5
frames0=$(state frames)
dump hold1.ppm
sleep 1
frames1=$(state frames)
dump hold2.ppm
moving=$(state moving)
scale=$(state scale)
xdotool keyup w
[ "$moving" = 1 ] || fail "holding W: the viewer does not say it is moving"
# Moving frames keep the window's resolution (temporal upscaling of the traced fraction),
# not blocks of a reduced one.
awk -v s="$scale" 'BEGIN { exit !(s == 1) }' || fail "holding W: a frame at 1/$scale resolution"
[ "$(flat hold2.ppm)" -lt 5 ] || fail "holding W: $(flat hold2.ppm) % of the window in blocks"
[ "$frames1" -ge $((frames0 + 3)) ] || fail "holding W: frames went $frames0 -> $frames1 in 1 s"
cmp -s hold1.ppm hold2.ppm && fail "holding W: the window did not change in 1 s"
wait_for 10 '[ "$(state moving)" = 0 ] && [ "$(state generation)" = "$(state view_generation)" ]' ||
    fail "classic: view did not settle after W"
wait_for 30 '[ "$(state spp)" -ge 8 ]' || fail "classic after W: fewer than 8 spp"
dump classic1.ppm
sides classic1.ppm || fail "classic after W: mirrored: $(region classic1.ppm 4 40 30 80)"
xdotool key m
wait_for 10 '[ "$(state recon)" = off ]' || fail "M after svgf: recon $(state recon)"
xdotool key m
wait_for 10 '[ "$(state recon)" = accumulate ]' || fail "M after off: recon $(state recon)"
# R resets the camera; C writes it as scene-file JSON that loads back.
pos1=$(state pos)
xdotool key r
wait_for 10 '[ "$(state pos)" != "$pos1" ]' || fail "R did not reset the camera"
xdotool key c
wait_for 10 '[ "$(state cameras)" = 1 ]' || fail "C wrote no camera: $(cat view.err)"
grep -q '"handedness": "right"' shots/trac0r-camera-000.json || fail "C: $(cat shots/trac0r-camera-000.json)"
quit_viewer
# The reset camera, written by C into the scene file in place of its own camera, renders
# the same image: the JSON is the scene's camera, handedness included.
awk -v f=shots/trac0r-camera-000.json '
    /^  "camera": \{/ { skip = 1; while ((getline l < f) > 0) { buf = buf sep "  " l; sep = "\n" }
                       sub(/\n?  $/, "", buf); print buf ","; next }
    skip && /^  \},?$/ { skip = 0; next }
    !skip { print }' "$SRC/scenes/cornell-classic.json" >cam.json
"$BIN" render "$SRC/scenes/cornell-classic.json" --width 40 --height 30 --spp 2 --out c0.png ||
    fail "render cornell-classic failed"
"$BIN" render cam.json --width 40 --height 30 --spp 2 --out c1.png 2>err.txt ||
    fail "the camera C wrote does not load: $(cat err.txt)"
cmp -s c0.png c1.png || fail "the camera C wrote renders another image"

# F12 saves the converged float film: with --max-spp 4 it equals trac0r render --spp 4.
rm -rf shots
mkdir -p shots
start_viewer --max-spp 4
wait_for 30 '[ "$(state spp)" -eq 4 ]' || fail "viewer did not reach 4 spp"
xdotool key F12
wait_for 20 '[ "$(state shots)" -ge 1 ]' || fail "F12 saved nothing: $(cat view.err)"
"$BIN" render --width 160 --height 120 --spp 4 --out r4.png 2>/dev/null
cmp -s shots/trac0r-view-000.png r4.png || fail "F12 screenshot differs from render --spp 4"
grep -q "saved shots/trac0r-view-000.png (4 spp)" view.out || fail "F12 message: $(cat view.out)"
quit_viewer

# --animate: the last shape moves before every frame, so every frame is a new image (1 spp)
# and the scene update is timed; the window shows the box in new places.
start_viewer --animate
wait_for 30 '[ "$(state updates)" -ge 3 ]' || fail "--animate: no scene updates: $(cat view.err)"
dump anim1.ppm
u1=$(state updates)
wait_for 30 '[ "$(state updates)" -ge $((u1 + 15)) ]' || fail "--animate: updates stopped at $u1"
dump anim2.ppm
[ "$(state spp)" -eq 1 ] || fail "--animate: $(state spp) spp accumulated over a moving scene"
awk -v t="$(state rebuild_ms)" 'BEGIN { exit !(t > 0) }' || fail "--animate: rebuild_ms $(state rebuild_ms)"
cmp -s anim1.ppm anim2.ppm && fail "--animate: the window did not change"
quit_viewer

# A 640x360 window: the help (H) lies wholly inside it, and the debug view (B) covers at
# most a third of it without overlapping the help.
start_viewer --width 640 --height 360 --max-spp 4
xdotool key h key b
wait_for 10 '[ "$(state help)" = 1 ] && [ "$(state overlay)" = 1 ] &&
    [ "$(state help_rect | cut -d" " -f3)" -gt 0 ] &&
    [ "$(state overlay_rect | cut -d" " -f3)" -gt 0 ]' || fail "H and B: no panels drawn"
awk -v h="$(state help_rect)" -v o="$(state overlay_rect)" 'BEGIN {
    split(h, a, " "); split(o, b, " ")
    inside = a[1] >= 0 && a[2] >= 0 && a[1] + a[3] <= 640 && a[2] + a[4] <= 360
    third = b[3] * b[4] <= 640 * 360 / 3
    apart = b[1] + b[3] <= a[1] || b[2] + b[4] <= a[2]
    exit !(inside && third && apart) }' ||
    fail "640x360: help at $(state help_rect), debug view at $(state overlay_rect)"
echo "640x360: help at $(state help_rect), debug view at $(state overlay_rect)"
[ -n "${TRAC0R_KEEP_DUMP:-}" ] && dump "$TRAC0R_KEEP_DUMP"
quit_viewer

# F: a thin lens focuses on the surface under the mouse. A wall 5 units down the view, a
# lens focused at 1: after F over the wall the camera's focus distance is the wall's.
cat >lens.json <<'JSON'
{"camera": {"position": [0, 0, 0], "direction": [0, 0, -1], "fov": 40,
            "aperture_radius": 0.05, "focus_distance": 1},
 "materials": {"wall": {"type": "diffuse", "color": [0.7, 0.7, 0.7]},
               "lamp": {"type": "emitter", "color": [1, 1, 1], "emittance": 4}},
 "shapes": [{"type": "quad", "vertices": [[-9, -9, -5], [9, -9, -5], [9, 9, -5], [-9, 9, -5]],
             "material": "wall"},
            {"type": "quad", "vertices": [[-1, 3, -1], [1, 3, -1], [1, 3, -3], [-1, 3, -3]],
             "material": "lamp"}]}
JSON
start_viewer --scene lens.json --max-spp 2
awk -v f="$(state focus)" 'BEGIN { exit !(f > 0.999 && f < 1.001) }' || fail "lens: focus $(state focus), not 1"
gen0=$(state view_generation)
xdotool mousemove --window "$WID" 80 60 key f
wait_for 10 '[ "$(state view_generation)" -gt "$gen0" ]' || fail "F did not change the view"
awk -v f="$(state focus)" 'BEGIN { exit !(f > 4.99 && f < 5.01) }' || fail "F: focus $(state focus), not 5"
quit_viewer

# --device opencl (builds and machines with an OpenCL device; tests/cli_opencl.sh checks
# that PoCL is there): the window renders on the device, a stride change clears the
# device's film, and F12 then saves what `trac0r render --device opencl --spp 4` computes.
if "$BIN" info --devices >/dev/null 2>&1; then
    rm -rf shots
    mkdir -p shots
    start_viewer --max-spp 4 --device opencl
    grep -q "rendering on opencl:0" view.err || fail "--device opencl: $(cat view.err)"
    wait_for 60 '[ "$(state spp)" -ge 2 ]' || fail "device viewer did not reach 2 spp"
    gen0=$(state view_generation)
    xdotool key 2
    wait_for 30 '[ "$(state stride)" = 2 ] && [ "$(state generation)" -gt "$gen0" ]' ||
        fail "device viewer: 2 did not switch to stride 2"
    xdotool key 1
    wait_for 60 'settled_at 1 4' ||
        fail "device viewer did not settle at stride 1, 4 spp: spp $(state spp)"
    xdotool key F12
    wait_for 20 '[ "$(state shots)" -ge 1 ]' || fail "device F12 saved nothing: $(cat view.err)"
    "$BIN" render --width 160 --height 120 --spp 4 --device opencl --out d4.png 2>/dev/null
    cmp -s shots/trac0r-view-000.png d4.png ||
        fail "device F12 screenshot differs from render --device opencl --spp 4"
    quit_viewer
    # Reconstructed on the device, the frames leave the film there; F12 reads it then.
    rm -rf shots
    mkdir -p shots
    start_viewer --max-spp 4 --device opencl --recon svgf
    wait_for 60 'settled_at 1 4' || fail "device viewer with svgf did not settle: spp $(state spp)"
    xdotool key F12
    wait_for 20 '[ "$(state shots)" -ge 1 ]' || fail "device F12 with svgf saved nothing: $(cat view.err)"
    cmp -s shots/trac0r-view-000.png d4.png ||
        fail "device F12 with svgf differs from render --device opencl --spp 4"
    quit_viewer
    # Headless too: view --frames equals render on the same device.
    "$BIN" view --device opencl --width 40 --height 30 --frames 3 --screenshot dv.pfm \
        2>/dev/null || fail "headless view --device opencl failed"
    "$BIN" render --device opencl --width 40 --height 30 --spp 3 --out dr.pfm 2>/dev/null
    cmp -s dv.pfm dr.pfm || fail "headless view --device opencl differs from render"
fi

cli_end cli_view
