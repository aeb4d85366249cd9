# md2man.awk - turns one of docs/*.md into a manual page (roff, man macros), so that the
# man pages say what the docs say and never drift from them.
#
#   awk -v name=trac0r -v section=1 -v version=0.1.0 -v title="..." -f md2man.awk docs/cli.md
#
# It knows the Markdown the docs use: headings (# is the page's own title, ## a section,
# ### a subsection), paragraphs, "* " lists with indented continuation lines, code blocks
# indented by four spaces, pipe tables (a row becomes a tagged paragraph: the first cell
# is the tag, the others follow under their column's heading) and, inline, `code`,
# **bold**, *emphasis* and [links](target) (the link text is kept).
# POSIX awk only (Debian's default awk is mawk).

BEGIN {
    mode = ""          # "", "para", "list", "code", "table"
    ncols = 0
    printf "'\\\" -*- coding: UTF-8 -*-\n"
    printf ".\\\" Generated from docs/ by cmake/md2man.awk; edit the Markdown, not this.\n"
    printf ".TH \"%s\" \"%s\" \"\" \"trac0r %s\" \"trac0r manual\"\n", toupper(name), section, version
    printf ".SH NAME\n%s \\- %s\n", name, esc(title)
    if (section == "1") {
        printf ".SH SYNOPSIS\n.B %s\n\\fICOMMAND\\fR [\\fIoptions\\fR]\n", name
    }
    printf ".SH DESCRIPTION\n"
}

# Roff escapes for plain text: backslashes, and hyphens as \- (options stay copyable).
function esc(s) {
    gsub(/\\/, "\\e", s)
    gsub(/-/, "\\-", s)
    return s
}

# Emphasis and links in text outside code spans.
function prose(s,    out, pre, m) {
    s = esc(s)
    # [text](target) keeps the text.
    while (match(s, /\[[^]]*\]\([^)]*\)/)) {
        m = substr(s, RSTART, RLENGTH)
        sub(/\]\(.*$/, "", m)
        s = substr(s, 1, RSTART - 1) substr(m, 2) substr(s, RSTART + RLENGTH)
    }
    out = ""
    while (match(s, /\*\*[^*]+\*\*/)) {
        out = out substr(s, 1, RSTART - 1) "\\fB" substr(s, RSTART + 2, RLENGTH - 4) "\\fR"
        s = substr(s, RSTART + RLENGTH)
    }
    s = out s
    out = ""
    # *emphasis*: a star that opens a word and one that closes it (not 2*3 or *.png).
    while (match(s, /(^|[ (])\*[^* ][^*]*\*/)) {
        pre = substr(s, RSTART, 1)
        if (pre == "*") {
            pre = ""
            out = out substr(s, 1, RSTART - 1) "\\fI" substr(s, RSTART + 1, RLENGTH - 2) "\\fR"
        } else {
            out = out substr(s, 1, RSTART) "\\fI" substr(s, RSTART + 2, RLENGTH - 3) "\\fR"
        }
        s = substr(s, RSTART + RLENGTH)
    }
    return out s
}

# Inline formatting: `code` in bold, the rest through prose().
function inline(s,    out, i, j) {
    out = ""
    while ((i = index(s, "`")) > 0) {
        j = index(substr(s, i + 1), "`")
        if (j == 0) {
            break
        }
        out = out prose(substr(s, 1, i - 1)) "\\fB" esc(substr(s, i + 1, j - 1)) "\\fR"
        s = substr(s, i + j + 1)
    }
    return out prose(s)
}

# A line of running text must not start with a control character.
function textline(s) {
    if (s ~ /^[.']/) {
        s = "\\&" s
    }
    print s
}

function end_block() {
    if (mode == "code") {
        print ".fi"
        print ".RE"
    }
    mode = ""
}

function trim(s) {
    sub(/^[ \t]+/, "", s)
    sub(/[ \t]+$/, "", s)
    return s
}

# Splits a table row into cells[1..n]; returns n. An escaped pipe (\|) is a character of
# its cell, not a separator.
function cells_of(line, cells,    n, k, parts) {
    line = trim(line)
    gsub(/\\\|/, "\001", line)
    sub(/^\|/, "", line)
    sub(/\|$/, "", line)
    n = split(line, parts, "|")
    for (k = 1; k <= n; k++) {
        gsub(/\001/, "|", parts[k])
        cells[k] = trim(parts[k])
    }
    return n
}

# Headings.
/^# / {
    end_block()
    next
}
/^## / {
    end_block()
    print ".SH \"" inline(toupper(substr($0, 4))) "\""
    next
}
/^###+ / {
    end_block()
    sub(/^###+ /, "")
    print ".SS \"" inline($0) "\""
    next
}

# Blank lines end paragraphs and lists; inside a code block they are kept.
/^[ \t]*$/ {
    if (mode == "code") {
        blank_in_code++
        next
    }
    end_block()
    next
}

# Code blocks: four spaces of indent after a blank line (not a list's continuation).
/^    / && (mode == "" || mode == "code") {
    if (mode != "code") {
        print ".PP"
        print ".RS 4"
        print ".nf"
        mode = "code"
        blank_in_code = 0
    }
    for (; blank_in_code > 0; blank_in_code--) {
        print ""
    }
    line = substr($0, 5)
    gsub(/\\/, "\\e", line)
    textline(line)
    next
}

# Tables.
/^\|/ {
    if (mode != "table") {
        end_block()
        mode = "table"
        ncols = cells_of($0, head)
        next
    }
    if ($0 ~ /^\|[ \t:|-]+$/) {
        next
    }
    n = cells_of($0, cell)
    print ".TP"
    textline(inline(cell[1]))
    first = 1
    for (k = 2; k <= n; k++) {
        if (cell[k] == "") {
            continue
        }
        if (!first) {
            print ".br"
        }
        # The last column (the meaning) needs no label; the ones before it do.
        if (ncols > 2 && k < n) {
            textline("\\fI" esc(head[k]) ":\\fR " inline(cell[k]))
        } else {
            textline(inline(cell[k]))
        }
        first = 0
    }
    next
}

# List items, and their continuation lines (indented).
/^[*-] / {
    if (mode == "code") {
        end_block()
    }
    mode = "list"
    print ".IP \\(bu 2"
    textline(inline(substr($0, 3)))
    next
}

{
    if (mode == "code" || mode == "table") {
        end_block()
    }
    if (mode == "") {
        print ".PP"
        mode = "para"
    }
    textline(inline(trim($0)))
}

END {
    end_block()
    if (name == "trac0r") {
        print ".SH \"SEE ALSO\""
        print "\\fBtrac0r\\-scene\\fR(5); docs/viewer.md, docs/integrators.md and docs/opencl.md in the sources"
    } else {
        print ".SH \"SEE ALSO\""
        print "\\fBtrac0r\\fR(1)"
    }
}
