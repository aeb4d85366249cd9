#!/bin/sh
# Checks the manual page trac0r(1) (generated from docs/cli.md) and the bash completion
# against the program's own --help texts: every command, benchmark and option that
# `trac0r --help`, `trac0r COMMAND --help` and `trac0r bench BENCHMARK --help` list must
# appear in the manual page and be offered by the completion.
# Usage: help_coverage.sh TRAC0R MAN_PAGE COMPLETION SCRATCH_DIR
set -u
TRAC0R=$1
MAN=$2
COMPLETION=$3
DIR=$4
. "$(dirname "$0")/common.sh"
cli_begin "$TRAC0R" "$DIR" # the scratch directory, entered; fail() counts

# The page's text: roff's \- as -, font changes and other escapes dropped.
sed -e 's/\\-/-/g' -e 's/\\f[BIRP]//g' -e 's/\\&//g' "$MAN" >man.txt

# Words of a help section: first word of each two-space-indented line after "$2".
section() {
    awk -v head="$2" '$0 == head { on = 1; next } on && /^[ \t]*$/ { exit } on && /^  [a-z]/ { print $1 }' "$1"
}
# Every --option named in the option column of a help text.
options() {
    awk '/^ ? ? ? ?-/ { line = $0; sub(/^ +/, "", line); n = index(line, "   ");
        if (n > 0) line = substr(line, 1, n - 1); print line }' "$1" |
        tr ',' ' ' | tr ' ' '\n' | grep -E '^--?[a-z]' | sort -u
}
# What the completion offers for the line "$1" ("trac0r ..." with the binary's path).
complete_line() {
    bash -c '. "$1" || exit 1; COMP_LINE=$2; COMP_POINT=${#COMP_LINE}; _trac0r; printf "%s\n" "${COMPREPLY[@]}"' \
        sh "$COMPLETION" "$TRAC0R${1#trac0r}"
}
in_man() {
    grep -q -E -- "(^|[^A-Za-z0-9-])$1([^A-Za-z0-9-]|\$)" man.txt
}
check_options() { # HELP_FILE "LINE PREFIX"
    complete_line "$2 -" >offered.txt
    for opt in $(options "$1"); do
        in_man "$opt" || fail "'$2': $opt is not in $MAN"
        case $opt in --*) grep -q -x -F -- "$opt" offered.txt || fail "'$2 -': $opt is not offered" ;; esac
        checked=$((checked + 1))
    done
}

checked=0
"$TRAC0R" --help >top.txt || fail "trac0r --help: exit $?"
commands=$(section top.txt "Commands:")
[ -n "$commands" ] || fail "no commands found in trac0r --help"
complete_line "trac0r " >offered-commands.txt
check_options top.txt "trac0r"
for cmd in $commands; do
    in_man "$cmd" || fail "command $cmd is not in $MAN"
    grep -q -x -F "$cmd" offered-commands.txt || fail "command $cmd is not offered"
    "$TRAC0R" "$cmd" --help >"$cmd.txt" || fail "trac0r $cmd --help: exit $?"
    if [ "$cmd" = bench ]; then
        benchmarks=$(section bench.txt "Benchmarks:")
        [ -n "$benchmarks" ] || fail "no benchmarks found in trac0r bench --help"
        complete_line "trac0r bench " >offered-benchmarks.txt
        for b in $benchmarks; do
            grep -q -F "bench $b" man.txt || fail "'bench $b' is not in $MAN"
            grep -q -x -F "$b" offered-benchmarks.txt || fail "benchmark $b is not offered"
            grep -q -E "bench .*[ '|]$b[|']" top.txt || fail "trac0r --help does not name benchmark $b"
            "$TRAC0R" bench "$b" --help >"bench-$b.txt" || fail "trac0r bench $b --help: exit $?"
            check_options "bench-$b.txt" "trac0r bench $b"
        done
    else
        check_options "$cmd.txt" "trac0r $cmd"
    fi
done
# The check must have seen the options at all.
[ "$checked" -ge 40 ] || fail "only $checked options checked: the extraction is broken"
if [ "$failures" -ne 0 ]; then
    exit 1
fi
echo "help_coverage: $checked options of $(echo "$commands" | wc -w) commands in the man page and the completion"
