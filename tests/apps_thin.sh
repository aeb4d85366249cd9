#!/bin/sh
# The command's code parses, prints and draws; the render loops are the library's. Two
# rules that keep it so, checked over apps/: no function longer than MAX lines (from the
# line that opens its body at column 0 to the brace that closes it), and no branch on which
# kind of device renders (the library answers what a program needs to know: capabilities,
# the structures a device walks, a one-line description).
# A third keeps the command small as a whole: apps/trac0r's C files under LINES lines in
# all, so that what a program needs beyond parsing, printing and drawing goes to the
# library, where the Python module and the web page reach it too.
# Usage: apps_thin.sh SOURCE_DIR [MAX (default 150)] [LINES (default 6500)]
set -u
SRC=$1
MAX=${2:-150}
LINES=${3:-6500}
status=0
total=$(cat "$SRC"/apps/trac0r/*.c "$SRC"/apps/trac0r/*.h 2>/dev/null | wc -l)
if [ "$total" -ge "$LINES" ]; then
    echo "apps/trac0r: $total lines of C (under $LINES wanted)"
    status=1
fi
for f in "$SRC"/apps/*/*.c; do
    # A function body starts with a line ending in '{' at column 0 that is not a type or
    # data definition, and ends with the '}' at column 0 that follows it.
    out=$(awk -v max="$MAX" -v file="$f" '
        /^[A-Za-z].*\)[^;]*\{$/ && !/^(typedef|struct|enum|union|static const|const)/ {
            start = NR; name = $0; next
        }
        /^\}/ && start {
            n = NR - start + 1
            if (n > max) printf "%s:%d: %d lines (at most %d): %s\n", file, start, n, max, name
            start = 0
        }' "$f")
    if [ -n "$out" ]; then
        echo "$out"
        status=1
    fi
done
# Asking the device for its kind to choose what to do.
hits=$(grep -nE 'tr_device_get_kind[[:space:]]*\(|strn?cmp[[:space:]]*\([[:space:]]*tr_device_kind|TR_DEVICE_(CPU|OPENCL)\b' \
    "$SRC"/apps/*/*.[ch] 2>/dev/null)
if [ -n "$hits" ]; then
    echo "a branch on the device kind in apps/:"
    echo "$hits"
    status=1
fi
[ $status -eq 0 ] && echo "apps_thin: every function at most $MAX lines, no branch on the device kind, $total lines in apps/trac0r"
exit $status
