#!/bin/sh
# Checks cmake/EmbedKernel.cmake on a made-up kernel: quoted includes are inlined, each
# file once, in order; #line directives keep __LINE__ and file names right; quotes,
# backslashes, tabs and line continuations survive the trip through the C string; a
# missing header fails the build step with a message naming it.
# Usage: embed_kernel.sh CMAKE EMBED_SCRIPT C_COMPILER SCRATCH_DIR
set -u
CMAKE=$1
SCRIPT=$2
CC=$3
DIR=$4
rm -rf "$DIR"
mkdir -p "$DIR/k" "$DIR/inc/pub"
cd "$DIR" || exit 1
failures=0
fail() {
    echo "FAIL: $*" >&2
    failures=$((failures + 1))
}

printf '#ifndef B_H\n#define B_H\nconst char *b_text = "q\\"uote\\\\ \ttab";\nint line_b = __LINE__;\n#define TWO_LINES(x) \\\n    ((x) + 1)\n#endif\n' >k/b.h
printf '#include "b.h"\n#include <math.h>\n#include "pub/c.h"\nint line_a = __LINE__;\n' >k/a.h
# A header outside the kernel's directory, found through TR_KERNEL_INCLUDE_DIRS (as the
# public include/trac0r/types.h is), although the kernel has a file of the same name.
printf 'int c_public = 1;\n' >inc/pub/c.h
printf 'int c_kernel = 1;\n' >k/c.h
printf '/* entry */\n#include "a.h"\n#include "b.h"\nint line_entry = __LINE__;\n' >k/entry.cl

"$CMAKE" -DTR_KERNEL_ENTRY="$DIR/k/entry.cl" -DTR_KERNEL_OUT="$DIR/gen.c" \
    -DTR_KERNEL_INCLUDE_DIRS="$DIR/inc" -P "$SCRIPT" || fail "the script failed"
cat >main.c <<'EOC'
#include <stdio.h>
#include <string.h>
extern const char tr_cl_kernel_source[];
extern const size_t tr_cl_kernel_source_length;
int main(void) {
    fputs(tr_cl_kernel_source, stdout);
    return strlen(tr_cl_kernel_source) == tr_cl_kernel_source_length ? 0 : 1;
}
EOC
"$CC" -Wall -Wextra -Werror -o dump main.c gen.c || fail "the generated C does not compile"
./dump >out.cl || fail "the embedded length is wrong"

# The text: b.h once (guarded anyway), before a.h's own line, <math.h> left alone.
[ "$(grep -c 'const char \*b_text' out.cl)" -eq 1 ] || fail "b.h inlined $(grep -c b_text out.cl) times"
grep -q '^#include <math.h>$' out.cl || fail "the system include was touched"
if grep -q '#include "' out.cl; then fail "a quoted #include is left"; fi
grep -qF 'const char *b_text = "q\"uote\\ 	tab";' out.cl || fail "escapes did not survive: $(grep b_text out.cl)"
grep -q '^#define TWO_LINES(x) \\$' out.cl || fail "the line continuation was lost"
grep -q '^int c_public = 1;$' out.cl || fail "the header under the include directory is missing"
if grep -q c_kernel out.cl; then fail "k/c.h was taken for pub/c.h"; fi
# The preprocessor sees the original line numbers and file names.
"$CC" -E -x c out.cl >pp.txt 2>&1 || fail "the embedded text does not preprocess: $(cat pp.txt)"
grep -q 'int line_b = 4;' pp.txt || fail "__LINE__ in b.h: $(grep line_b pp.txt)"
grep -q 'int line_a = 4;' pp.txt || fail "__LINE__ in a.h: $(grep line_a pp.txt)"
grep -q 'int line_entry = 4;' pp.txt || fail "__LINE__ in entry.cl: $(grep line_entry pp.txt)"
grep -q '"b.h"' pp.txt || fail "no line marker names b.h"
grep -q '"pub/c.h"' pp.txt || fail "no line marker names pub/c.h as it was included"

# Unchanged input: the output file is not rewritten (no needless rebuilds).
touch -d '2000-01-01' gen.c
"$CMAKE" -DTR_KERNEL_ENTRY="$DIR/k/entry.cl" -DTR_KERNEL_OUT="$DIR/gen.c" \
    -DTR_KERNEL_INCLUDE_DIRS="$DIR/inc" -P "$SCRIPT"
[ -z "$(find gen.c -newermt '2001-01-01')" ] || fail "gen.c rewritten although nothing changed"

# A missing header fails with its name.
printf '#include "missing.h"\n' >k/bad.cl
if "$CMAKE" -DTR_KERNEL_ENTRY="$DIR/k/bad.cl" -DTR_KERNEL_OUT="$DIR/bad.c" -P "$SCRIPT" \
    >bad.txt 2>&1; then
    fail "a missing header was not reported"
fi
grep -q 'missing.h' bad.txt || fail "the error does not name missing.h: $(cat bad.txt)"

if [ "$failures" -ne 0 ]; then
    echo "embed_kernel: $failures failures" >&2
    exit 1
fi
echo "embed_kernel: all checks passed"
