#!/bin/sh
# Checks that libtrac0r.so exports exactly the public API: every function the public
# headers declare (not the static inline ones), and nothing else, so the library's
# internals (src/) stay private and a public function cannot be left unexported. The
# declared functions are taken from clang's AST dump of the public headers (as in
# public_names.sh), the exported ones from the library's dynamic symbol table.
# Usage: shared_exports.sh CLANG INCLUDE_DIR LIBTRAC0R_SO STATIC_LIB SCRATCH_DIR HEADER...
set -u
CLANG=$1
INC=$2
SO=$3
STATIC=$4
DIR=$5
shift 5
rm -rf "$DIR"
mkdir -p "$DIR"
cd "$DIR" || exit 1
failures=0

for h in "$@"; do
    printf '#include "trac0r/%s"\n' "$h"
done >pub.c
"$CLANG" -x c -std=c11 -fsyntax-only -fno-color-diagnostics -I"$INC" -Xclang -ast-dump pub.c \
    >pub.ast || exit 1
# Top-level function declarations from our headers that are neither static nor inline.
grep -E '^[|`]-FunctionDecl ' pub.ast | grep -v -E ' (static|inline)( |$)' |
    sed -E "s/ '.*//" | awk '{ print $NF }' | grep -E '^tr_' | sort -u >declared.txt
nm -D --defined-only "$SO" | awk '{ print $NF }' | sort -u >exported.txt
# Global functions in the archive: the library's internals are among them.
nm "$STATIC" | awk '$2 == "T" { print $3 }' | sort -u >archive.txt

declared=$(wc -l <declared.txt)
internal=$(comm -23 archive.txt declared.txt | wc -l)
if [ "$declared" -lt 10 ] || [ "$internal" -lt 1 ]; then
    echo "FAIL: $declared declared functions, $internal internal ones: the extraction is broken" >&2
    failures=$((failures + 1))
fi
missing=$(comm -23 declared.txt exported.txt)
if [ -n "$missing" ]; then
    echo "FAIL: declared in include/trac0r/ but not exported by libtrac0r.so:" >&2
    echo "$missing" | sed 's/^/  /' >&2
    failures=$((failures + 1))
fi
extra=$(comm -13 declared.txt exported.txt)
if [ -n "$extra" ]; then
    echo "FAIL: exported by libtrac0r.so but declared in no public header:" >&2
    echo "$extra" | sed 's/^/  /' >&2
    failures=$((failures + 1))
fi
if [ "$failures" -ne 0 ]; then
    exit 1
fi
echo "shared_exports: $declared public functions exported, $internal internal ones hidden"
