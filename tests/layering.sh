#!/bin/sh
# layering.sh SRC DOC - the library's modules (the directories under SRC) include only
# modules at their own layer or below, and no two modules include each other, directly or
# through others.
#
# The order comes from DOC's one line that starts with "layers: " (docs/architecture.md,
# section "Layers"), lowest first: "layers: util < kernel < accel, film < scene". Modules
# separated by "," share a layer: they may include each other, but not in a cycle.
#
# Every #include "..." of every .c, .h and .cl file under SRC is resolved as the compiler
# resolves it: next to the including file first, then under SRC (the library's -Isrc).
# Public headers (trac0r/..., include/) belong to no module and may be included anywhere.
# An include that resolves to neither fails the test, so that a new kind of include is
# looked at rather than passed over.
#
# Exit status: 0 when the layering holds, 1 when it does not (every violation is listed),
# 2 when the arguments or the order line are unusable.
set -eu

if [ $# -ne 2 ] || [ ! -d "$1" ] || [ ! -f "$2" ]; then
    echo "usage: layering.sh SRC_DIR DOC" >&2
    exit 2
fi
src=$(cd "$1" && pwd -P)
doc=$2

order=$(sed -n 's/^layers: //p' "$doc")
if [ -z "$order" ] || [ "$(printf '%s\n' "$order" | wc -l)" -ne 1 ]; then
    echo "$doc: expected exactly one line starting with 'layers: '" >&2
    exit 2
fi

# One line per include between files of SRC: "FROM_MODULE TO_MODULE FILE INCLUDE";
# TO_MODULE is "-" for a public header and "?" for one that does not resolve.
edges=$(
    find "$src" -type f \( -name '*.c' -o -name '*.h' -o -name '*.cl' \) | LC_ALL=C sort |
        while IFS= read -r f; do
            rel=${f#"$src"/}
            case $rel in
            */*) from=${rel%%/*} ;;
            *) from="?" ;;
            esac
            dir=$(dirname "$f")
            sed -n 's/^[[:space:]]*#[[:space:]]*include[[:space:]]*"\([^"]*\)".*/\1/p' "$f" |
                while IFS= read -r inc; do
                    to="?"
                    case $inc in
                    trac0r/*) to="-" ;;
                    *)
                        if [ -f "$dir/$inc" ]; then
                            target=$(realpath "$dir/$inc")
                        elif [ -f "$src/$inc" ]; then
                            target=$(realpath "$src/$inc")
                        else
                            target=""
                        fi
                        case $target in
                        "$src"/*/*)
                            t=${target#"$src"/}
                            to=${t%%/*}
                            ;;
                        */include/trac0r/*) to="-" ;;
                        esac
                        ;;
                    esac
                    printf '%s %s %s %s\n' "$from" "$to" "src/$rel" "$inc"
                done
        done
)

printf '%s\n' "$edges" | awk -v order="$order" '
function unusable(msg) {
    print msg > "/dev/stderr"
    bad = 2
    exit 2
}
BEGIN {
    nl = split(order, layers, "<")
    if (nl < 2) unusable("the layers line names fewer than two layers")
    for (i = 1; i <= nl; ++i) {
        nm = split(layers[i], mods, ",")
        for (j = 1; j <= nm; ++j) {
            m = mods[j]; gsub(/[[:space:]`]/, "", m)
            if (m == "") unusable("an empty name in the layers line")
            if (m in rank) unusable("module " m " named twice in the layers line")
            rank[m] = i; nmod++; name[nmod] = m
        }
    }
    bad = 0
}
NF >= 4 {
    from = $1; to = $2; file = $3; inc = $4
    if (from == "?") { print file ": not inside a module directory"; bad = 1; next }
    if (!(from in rank)) {
        if (!(from in unknown)) print "src/" from "/: a module the layers line does not name"
        unknown[from] = 1; bad = 1; next
    }
    if (to == "-") next
    if (to == "?") { print file ": #include \"" inc "\" resolves to no file of src/ or include/"; bad = 1; next }
    if (!(to in rank)) next  # reported above when its own files are read
    if (rank[to] > rank[from]) {
        print file ": #include \"" inc "\": " from " may not include " to " (a higher layer)"
        bad = 1
    }
    if (to != from) reach[from, to] = 1
}
END {
    if (bad == 2) exit 2
    # Transitive closure over the modules (a dozen at most): a module that reaches itself
    # through another is in a cycle.
    for (k = 1; k <= nmod; ++k)
        for (i = 1; i <= nmod; ++i)
            if ((name[i], name[k]) in reach)
                for (j = 1; j <= nmod; ++j)
                    if ((name[k], name[j]) in reach) reach[name[i], name[j]] = 1
    for (i = 1; i <= nmod; ++i)
        for (j = i + 1; j <= nmod; ++j)
            if ((name[i], name[j]) in reach && (name[j], name[i]) in reach) {
                print "include cycle between modules " name[i] " and " name[j]
                bad = 1
            }
    exit bad
}'
