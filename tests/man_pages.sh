#!/bin/sh
# Checks that a manual page generated from docs/ (cmake/md2man.awk) lost nothing of its
# Markdown: every `code` span of the Markdown file (options, keys, values, file names)
# appears in the page's text, every heading is a section of the page, and groff reads the
# page without a warning.
# Usage: man_pages.sh MARKDOWN MAN_PAGE SCRATCH_DIR
set -u
MD=$1
MAN=$2
DIR=$3
. "$(dirname "$0")/common.sh"
cli_begin "$MD" "$DIR" # the scratch directory, entered; fail() counts

# The page as text: roff's \- as -, \e as a backslash, font changes and \& dropped,
# words broken over lines joined by one blank.
sed -e 's/\\-/-/g' -e 's/\\e/\\/g' -e 's/\\f[BIRP]//g' -e 's/\\&//g' "$MAN" | tr '\n' ' ' >page.txt

# Code spans, one per line (a span does not cross lines in the docs).
# shellcheck disable=SC2016 # backquotes, not an expansion
# (An escaped pipe in a table cell, \|, is a plain | on the page.)
grep -o '`[^`]*`' "$MD" | sed -e 's/^`//' -e 's/`$//' -e 's/\\|/|/g' | sort -u >spans.txt
spans=$(wc -l <spans.txt)
[ "$spans" -ge 20 ] || fail "only $spans code spans in $MD: the extraction is broken"
while IFS= read -r span; do
    # Case aside: section headings are upper case, as man pages have them.
    grep -q -i -F -- "$span" page.txt || fail "$MAN lacks '$span' of $MD"
done <spans.txt

# Headings: ## as .SH (upper case), ### as .SS.
sed -n 's/^##* //p' "$MD" | sed 1d >headings.txt
while IFS= read -r h; do
    plain=$(printf '%s\n' "$h" | tr -d '`*')
    upper=$(printf '%s\n' "$plain" | tr '[:lower:]' '[:upper:]')
    grep -q -F -- "\"$plain\"" page.txt || grep -q -F -- "\"$upper\"" page.txt ||
        fail "$MAN lacks the heading '$h'"
done <headings.txt

if ! groff -man -Tutf8 -k -ww -z "$MAN" >groff.log 2>&1 || [ -s groff.log ]; then
    cat groff.log >&2
    fail "groff warns about $MAN"
fi
if [ "$failures" -ne 0 ]; then
    exit 1
fi
echo "man_pages: $MAN has all $spans code spans and $(wc -l <headings.txt) headings of $MD"
