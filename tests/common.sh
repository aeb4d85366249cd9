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
