#!/bin/sh
# The scene files shipped in scenes/ and the table of them in docs/scene-format.md agree:
# every scenes/*.json has its row, and every row names a file that exists.
# Usage: scene_list.sh SOURCE_DIR
set -u
SRC=$1
DOC=$SRC/docs/scene-format.md
status=0
for f in "$SRC"/scenes/*.json; do
    name=$(basename "$f")
    grep -q -F "| \`$name\` |" "$DOC" || {
        echo "scenes/$name has no row in docs/scene-format.md"
        status=1
    }
done
rows=$(sed -n 's/^| `\([A-Za-z0-9_.-]*\.json\)` |.*/\1/p' "$DOC")
[ -n "$rows" ] || { echo "no scene rows found in docs/scene-format.md"; exit 1; }
for name in $rows; do
    [ -f "$SRC/scenes/$name" ] || {
        echo "docs/scene-format.md lists $name, which scenes/ does not hold"
        status=1
    }
done
[ $status -eq 0 ] && echo "scene_list: $(echo "$rows" | wc -l) scenes listed and shipped"
exit $status
