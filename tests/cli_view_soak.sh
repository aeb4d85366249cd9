#!/bin/sh
# The viewer stays flat over a long run: under Xvfb, `trac0r view --animate` (the scene's
# last shape moving every frame) with W held (the camera moving), its resident memory
# sampled twice a second from /proc. After a warm-up of a fifth of the run the rest is cut
# into three windows: a leak raises the peak in each window over the one before, so the
# run fails when both the second and the third window's peak exceed the window's before by
# more than 0.5 %. A single step does not fail it: while moving, the viewer picks its traced
# size by the measured frame time, and a load spike that makes it pick another reallocates
# its reconstruction's buffers once (steps of 100-800 KiB, at any time of the run, seen with
# binaries that leak nothing; comparing the two halves' peaks failed on them about one run
# in five). The process holds as many file descriptors at the end as after the warm-up.
# Usage: cli_view_soak.sh TRAC0R_BINARY SCRATCH_DIR [SECONDS (default 20)]
set -u
. "$(dirname "$0")/common.sh"
cli_begin "$1" "$2"
SECONDS_RUN=${3:-20}
XVFB_PID=
VIEW_PID=
cleanup() {
    [ -n "$VIEW_PID" ] && kill "$VIEW_PID" 2>/dev/null
    [ -n "$XVFB_PID" ] && kill "$XVFB_PID" 2>/dev/null
    wait 2>/dev/null
}
trap cleanup EXIT
trap 'exit 1' INT TERM HUP
xvfb_start || exit 1
export SDL_RENDER_DRIVER=software SDL_FRAMEBUFFER_ACCELERATION=0
"$BIN" view --animate --width 160 --height 120 --state-file state.txt >view.out 2>view.err &
VIEW_PID=$!
n=0
while ! grep -q "^frames [1-9]" state.txt 2>/dev/null && [ $n -lt 300 ]; do
    sleep 0.1
    n=$((n + 1))
done
grep -q "^frames [1-9]" state.txt 2>/dev/null || {
    fail "the viewer showed no frame: $(cat view.err)"
    exit 1
}
xdotool search --sync --pid "$VIEW_PID" windowactivate --sync >/dev/null 2>&1
xdotool keydown w
# The soak is measured from the first frame the viewer renders as moving (W held): under a
# loaded machine the key can take seconds to arrive, and the frames at rest before it
# need less memory than moving ones (the reconstruction's buffers), which read as growth.
n=0
while ! grep -q "^moving 1" state.txt 2>/dev/null && [ $n -lt 100 ]; do
    sleep 0.1
    n=$((n + 1))
done
grep -q "^moving 1" state.txt 2>/dev/null || fail "the viewer never moved with W held"
rss() { awk '$1 == "VmRSS:" { print $2 }' "/proc/$VIEW_PID/status"; }
fds() { ls "/proc/$VIEW_PID/fd" | wc -l; }
samples=$((SECONDS_RUN * 2))
warm=$((samples / 5))
third=$(((samples - warm) / 3))
b2=$((warm + third))
b3=$((warm + 2 * third))
peak1=0
peak2=0
peak3=0
k=0
while [ $k -lt $samples ]; do
    sleep 0.5
    kill -0 "$VIEW_PID" 2>/dev/null || break
    r=$(rss)
    [ $k -eq $warm ] && fds_warm=$(fds)
    if [ $k -ge $warm ] && [ $k -lt $b2 ] && [ "$r" -gt $peak1 ]; then peak1=$r; fi
    if [ $k -ge $b2 ] && [ $k -lt $b3 ] && [ "$r" -gt $peak2 ]; then peak2=$r; fi
    if [ $k -ge $b3 ] && [ "$r" -gt $peak3 ]; then peak3=$r; fi
    k=$((k + 1))
done
xdotool keyup w
fds_end=$(fds)
frames=$(awk '$1 == "frames" { print $2 }' state.txt)
echo "cli_view_soak: $frames frames in ${SECONDS_RUN} s, resident peaks $peak1, $peak2 and $peak3 KiB, $fds_warm and $fds_end file descriptors"
[ $k -eq $samples ] || fail "the viewer ended during the soak: $(cat view.err)"
# Whether window b's peak exceeds window a's by more than 0.5 % and SOAK_SLACK_KB (the
# sanitizer build's allocator wanders by that much: tests/CMakeLists.txt).
grew() { [ $(($2 * 1000)) -gt $(($1 * 1005 + ${SOAK_SLACK_KB:-0} * 1000)) ]; }
[ "$peak1" -gt 0 ] || fail "no resident memory measured"
if grew "$peak1" "$peak2" && grew "$peak2" "$peak3"; then
    fail "resident memory grew in every window: $peak1, $peak2 and $peak3 KiB"
fi
[ "$fds_warm" -eq "$fds_end" ] || fail "file descriptors: $fds_warm after the warm-up, $fds_end at the end"
grep -q "^moving 1" state.txt || fail "the camera was not moving at the end"
cli_end cli_view_soak
