#!/bin/sh
# Checks that every name the public headers declare or define starts with tr_ / TR_
# (TRAC0R_ for include guards and the version): functions, variables, typedefs, struct,
# union and enum tags, enum constants and macros. The names are not parsed from the
# headers' text but taken from the compiler: clang's AST dump (top-level declarations and
# enum constants) and its macro list (-dM), of one file including the public headers,
# minus the same of a file including only the system headers they include. So macro
# expansions (X-macro lists) are seen as compiled, and system headers' names drop out.
# Usage: public_names.sh CLANG INCLUDE_DIR SCRATCH_DIR HEADER...
set -u
CLANG=$1
INC=$2
DIR=$3
shift 3
rm -rf "$DIR"
mkdir -p "$DIR"
cd "$DIR" || exit 1

# The system headers the public headers include, in one file; then ours after them.
for h in "$@"; do
    grep -h '^[[:space:]]*#[[:space:]]*include[[:space:]]*<' "$INC/trac0r/$h"
done | sort -u >sys.c
cp sys.c pub.c
for h in "$@"; do
    printf '#include "trac0r/%s"\n' "$h" >>pub.c
done

# Top-level declarations (|-Decl / `-Decl) and enum constants, one name per line.
names() {
    "$CLANG" -x c -std=c11 -fsyntax-only -fno-color-diagnostics -I"$INC" \
        -Xclang -ast-dump "$1" >"$1.ast" || exit 1
    sed -n -E \
        -e '/^[|`]-(TypedefDecl|RecordDecl|EnumDecl|FunctionDecl|VarDecl) /p' \
        -e '/^[| ] [|`]-EnumConstantDecl /p' "$1.ast" |
        sed -E -e "s/'.*//" -e 's/ definition$//' -e 's/[[:space:]]+$//' |
        awk '{ n = $NF; if (n != "struct" && n != "union" && n != "enum" && n ~ /^[A-Za-z_][A-Za-z0-9_]*$/) print n }' |
        sort -u
}
macros() {
    "$CLANG" -x c -std=c11 -E -dM -I"$INC" "$1" | awk '{ sub(/\(.*/, "", $2); print $2 }' | sort -u
}

failures=0
names sys.c >sys.names
names pub.c >pub.names
macros sys.c >sys.macros
macros pub.c >pub.macros
comm -13 sys.names pub.names >ours.names
comm -13 sys.macros pub.macros >ours.macros
count=$(cat ours.names ours.macros | wc -l)
# The check must have seen the API at all (a broken dump would pass vacuously).
for expect in tr_scene_create tr_scene TR_OK; do
    if ! grep -qx "$expect" ours.names ours.macros; then
        echo "FAIL: '$expect' is not among the names found: the extraction is broken" >&2
        failures=$((failures + 1))
    fi
done
bad=$(cat ours.names ours.macros | grep -v -E '^(tr_|TR_|TRAC0R_)')
if [ -n "$bad" ]; then
    echo "FAIL: public names without the tr_/TR_ prefix:" >&2
    echo "$bad" | sed 's/^/  /' >&2
    failures=$((failures + 1))
fi
if [ "$failures" -ne 0 ]; then
    exit 1
fi
echo "public_names: $count names, all prefixed"
