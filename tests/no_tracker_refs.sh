#!/bin/sh
# Fails when a file of the source tree cites a development step or a tracker entry by
# number: "stop" or "issue(s)" followed by a number, or a bare "#" and a number after a
# space or an opening parenthesis. Nothing in the repository resolves such numbers (there
# is no public tracker), so a comment, test or page must say the reason or the feature
# instead. Measurement records in docs/log/ name their date and commit.
# Usage: no_tracker_refs.sh SOURCE_DIR
# The files are those git tracks when SOURCE_DIR is a git checkout, else every file under
# it outside .git and build*/ directories; binary files are skipped (grep -I).
set -u
SRC=$1
cd "$SRC" || exit 1

# Files exempt from the check: none. (A file being rewritten on a branch may be listed here
# while it is, never on main.)
pending_files=""

PATTERN='\b[Ss]tops? [0-9]+|\b[Ii]ssues? [0-9]+|(^|[[:space:](])#[0-9]+([^-[:alnum:]]|$)'

list_files() {
    if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
        git ls-files --cached --others --exclude-standard
    else
        find . \( -name .git -o -path './build*' \) -prune -o -type f -print | sed 's|^\./||'
    fi
}

# The pattern must catch each form (a grep without \b would pass everything), and must not
# catch a number that only follows a word ending in those letters, nor a dated anchor.
n=12
for sample in "see stop $n" "Stop $n's binary" "issue $n" "Issues $n and 13" "fixed (#$n)"; do
    printf '%s\n' "$sample" | grep -qE "$PATTERN" || {
        echo "no_tracker_refs: the pattern misses '$sample'" >&2
        exit 1
    }
done
for sample in "backstop $n" "tissue $n" "nonstop $n" "x#$n" "(#2026-11-23--an-anchor)"; do
    if printf '%s\n' "$sample" | grep -qE "$PATTERN"; then
        echo "no_tracker_refs: the pattern catches '$sample'" >&2
        exit 1
    fi
done

TMP=${TMPDIR:-/tmp}/no_tracker_refs.$$
trap 'rm -f "$TMP"' EXIT
: >"$TMP"
list_files | while IFS= read -r f; do
    [ -f "$f" ] || continue
    skip=0
    for p in $pending_files; do
        [ "$f" = "$p" ] && skip=1
    done
    [ $skip -eq 1 ] && continue
    grep -nIE "$PATTERN" "$f" /dev/null >>"$TMP"
done

# The check must see something: a tree with no files listed is an error, not a pass.
if [ "$(list_files | wc -l)" -eq 0 ]; then
    echo "no_tracker_refs: no files found under $SRC" >&2
    exit 1
fi
if [ -s "$TMP" ]; then
    echo "no_tracker_refs: references to numbered steps or tracker entries (say the reason instead):" >&2
    cat "$TMP" >&2
    exit 1
fi
echo "no_tracker_refs: $(list_files | wc -l) files, none cites a step or tracker number"
exit 0
