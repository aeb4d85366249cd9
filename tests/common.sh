# common.sh - sourced by the tests/cli_*.sh scripts: their scratch directory, failure
# counting, the usage-error check and the summary line.
#
#     set -u
#     . "$(dirname "$0")/common.sh"
#     cli_begin "$1" "$2"    # BIN=$1; DIR=$2 made fresh and entered; failures=0
#     ...
#     cli_end cli_name       # exits 1 after any fail, else prints "all checks passed"

cli_begin() {
    BIN=$1
    DIR=$2
    rm -rf "$DIR"
    mkdir -p "$DIR"
    cd "$DIR" || exit 1
    failures=0
}

fail() {
    echo "FAIL: $*" >&2
    failures=$((failures + 1))
}

# expect_usage_error WHAT_STDERR_MUST_CONTAIN ARGS...: `trac0r ARGS` exits 2 with one
# stderr line containing the text, and leaves the scratch directory as it found it
# (nothing written, nothing removed).
expect_usage_error() {
    needle=$1
    shift
    before=$(ls -A | sort | tr '\n' ' ')
    "$BIN" "$@" >out.txt 2>err.txt
    rc=$?
    [ "$rc" -eq 2 ] || fail "trac0r $*: exit $rc, expected 2: $(cat err.txt)"
    lines=$(wc -l <err.txt)
    [ "$lines" -eq 1 ] || fail "trac0r $*: $lines stderr lines, expected 1: $(cat err.txt)"
    grep -qF -- "$needle" err.txt || fail "trac0r $*: stderr lacks '$needle': $(cat err.txt)"
    rm -f out.txt err.txt
    after=$(ls -A | sort | tr '\n' ' ')
    [ "$before" = "$after" ] || fail "trac0r $*: files changed: '$before' -> '$after'"
}

cli_end() {
    if [ "$failures" -ne 0 ]; then
        echo "$1: $failures failures" >&2
        exit 1
    fi
    echo "$1: all checks passed"
}

# xvfb_start: Xvfb on a display number it picks itself (-displayfd writes it to fd 9),
# with xdotool at hand; sets XVFB_PID and exports DISPLAY. Returns 1 (after fail) when
# either tool is missing or the server does not start.
xvfb_start() {
    for tool in Xvfb xdotool; do
        command -v $tool >/dev/null || {
            fail "$tool is not installed (scripts/install-deps installs it)"
            return 1
        }
    done
    Xvfb -displayfd 9 -nolisten tcp -screen 0 640x480x24 9>displayfd 2>xvfb.log &
    XVFB_PID=$!
    i=0
    while [ ! -s displayfd ] && [ $i -lt 100 ]; do
        sleep 0.1
        i=$((i + 1))
    done
    [ -s displayfd ] || {
        fail "Xvfb did not start: $(cat xvfb.log)"
        return 1
    }
    DISPLAY=:$(head -n1 displayfd)
    export DISPLAY
    unset WAYLAND_DISPLAY SDL_VIDEODRIVER
}
