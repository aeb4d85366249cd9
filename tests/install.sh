#!/bin/sh
# Installs trac0r into a temporary prefix, as a user without root would, and checks what
# `cmake --install` put there:
#   - the installed `trac0r` runs and renders; no RPATH/RUNPATH of an installed file
#     points into the build tree;
#   - a program (tests/install/client.c) builds against the installed library through
#     `pkg-config --cflags --libs trac0r` alone, and again through find_package(trac0r)
#     and trac0r::trac0r alone, and each build renders what the installed command renders,
#     bit for bit;
#   - trac0r.pc's Libs.private names every library libtrac0r.so needs;
#   - the man pages and the bash completion are where man and bash-completion look.
# Usage: install.sh CMAKE BUILD_DIR SOURCE_DIR SCRATCH_DIR C_COMPILER GENERATOR [EXTRA_FLAGS]
set -u
CMAKE=$1
BUILD=$2
SRC=$3
DIR=$4
CC=$5
GENERATOR=$6
FLAGS=${7:-}
rm -rf "$DIR"
mkdir -p "$DIR"
cd "$DIR" || exit 1
PREFIX=$DIR/prefix
failures=0
fail() {
    echo "FAIL: $*" >&2
    failures=$((failures + 1))
}

"$CMAKE" --install "$BUILD" --prefix "$PREFIX" >install.log 2>&1 || {
    cat install.log >&2
    echo "FAIL: cmake --install" >&2
    exit 1
}
# Debian's GNUInstallDirs may pick lib/<multiarch> for some prefixes; find it.
PC=$(find "$PREFIX" -name trac0r.pc)
[ -n "$PC" ] || { echo "FAIL: no trac0r.pc installed" >&2; exit 1; }
LIBDIR=$(dirname "$(dirname "$PC")")
for f in bin/trac0r include/trac0r/trac0r.h share/man/man1/trac0r.1 share/man/man5/trac0r-scene.5 \
    share/bash-completion/completions/trac0r; do
    [ -f "$PREFIX/$f" ] || fail "$f is not installed"
done
[ -f "$LIBDIR/cmake/trac0r/trac0rConfig.cmake" ] || fail "trac0rConfig.cmake is not installed"
[ -f "$LIBDIR/cmake/trac0r/trac0rConfigVersion.cmake" ] || fail "trac0rConfigVersion.cmake is not installed"

# The shared library: a soname with the version, the link name a symlink to it.
SO=$LIBDIR/libtrac0r.so
[ -L "$SO" ] || fail "libtrac0r.so is not a symlink"
SONAME=$(objdump -p "$SO" | awk '$1 == "SONAME" { print $2 }')
case $SONAME in
    libtrac0r.so.[0-9]*) [ -e "$LIBDIR/$SONAME" ] || fail "soname $SONAME is not installed" ;;
    *) fail "libtrac0r.so has soname '$SONAME'" ;;
esac
# Only a static libtrac0r would make pkg-config --static meaningful for trac0r itself;
# none is installed (tests link the build tree's archive).
[ ! -e "$LIBDIR/libtrac0r.a" ] || fail "libtrac0r.a is installed"

# Nothing installed may look for libraries in the build tree.
for f in "$PREFIX/bin/trac0r" "$LIBDIR/$SONAME"; do
    if objdump -p "$f" | grep -E '(RPATH|RUNPATH)' | grep -q -F "$BUILD"; then
        fail "$f has a RUNPATH into the build tree"
    fi
done

# The installed command renders the reference the clients must match.
"$PREFIX/bin/trac0r" render --width 16 --height 12 --spp 2 --out ref.pfm >render.log 2>&1 ||
    fail "installed trac0r render: exit $?"
[ -s ref.pfm ] || fail "installed trac0r render wrote no ref.pfm"

# 1. pkg-config only.
export PKG_CONFIG_PATH="$LIBDIR/pkgconfig"
PCFLAGS=$(pkg-config --cflags --libs trac0r) || fail "pkg-config --cflags --libs trac0r"
# shellcheck disable=SC2086 # the flags are words
if "$CC" -std=c11 -Wall -Wextra -Werror $FLAGS -o client-pc "$SRC/tests/install/client.c" $PCFLAGS \
    >pc-build.log 2>&1; then
    LD_LIBRARY_PATH="$LIBDIR" ./client-pc ref.pfm || fail "client built with pkg-config: exit $?"
    # It is the installed library that the program loads.
    LD_LIBRARY_PATH="$LIBDIR" ldd ./client-pc | grep -q -F "$LIBDIR/$SONAME" ||
        fail "client-pc does not load $LIBDIR/$SONAME"
else
    cat pc-build.log >&2
    fail "building the client with '$PCFLAGS'"
fi
# pkg-config --static: every library libtrac0r.so was linked against is named.
STATIC=$(pkg-config --static --libs trac0r)
for lib in $(objdump -p "$SO" | awk '$1 == "NEEDED" { print $2 }'); do
    name=${lib#lib}
    name=${name%%.so*}
    case $name in c | ld-linux* | gcc_s) continue ;; esac # come with every link
    case " $STATIC " in
        *" -l$name "*) ;;
        *) fail "pkg-config --static --libs trac0r lacks -l$name ($lib): $STATIC" ;;
    esac
done

# 2. find_package(trac0r) only.
if "$CMAKE" -S "$SRC/tests/install" -B client-cmake -G "$GENERATOR" -DCMAKE_C_COMPILER="$CC" \
    -DCMAKE_PREFIX_PATH="$PREFIX" -DCMAKE_C_FLAGS="$FLAGS" -DCMAKE_BUILD_TYPE=Release \
    >cmake-build.log 2>&1 && "$CMAKE" --build client-cmake >>cmake-build.log 2>&1; then
    # CMake gives the client a RUNPATH to the installed library: no LD_LIBRARY_PATH.
    ./client-cmake/client ref.pfm || fail "client built with find_package: exit $?"
else
    cat cmake-build.log >&2
    fail "building the client with find_package(trac0r)"
fi
# find_package honours the version: 99 is not this library.
if "$CMAKE" -S "$SRC/tests/install" -B client-v99 -G "$GENERATOR" -DCMAKE_C_COMPILER="$CC" \
    -DCMAKE_PREFIX_PATH="$PREFIX" -DTRAC0R_WANT=99 >v99.log 2>&1; then
    fail "find_package(trac0r 99) succeeded"
fi

# The man pages render without warnings; the completion loads and completes.
for page in "$PREFIX/share/man/man1/trac0r.1" "$PREFIX/share/man/man5/trac0r-scene.5"; do
    if ! groff -man -Tutf8 -k -ww -z "$page" >groff.log 2>&1 || [ -s groff.log ]; then
        cat groff.log >&2
        fail "$page: groff warnings"
    fi
done
REPLY=$(PATH="$PREFIX/bin:$PATH" bash -c '
    . "$1/share/bash-completion/completions/trac0r" || exit 1
    COMP_LINE="trac0r ren"
    COMP_POINT=${#COMP_LINE}
    _trac0r
    echo "${COMPREPLY[*]}"' sh "$PREFIX")
[ "$REPLY" = render ] || fail "installed completion of 'trac0r ren' gave '$REPLY'"

if [ "$failures" -ne 0 ]; then
    exit 1
fi
echo "install: installed into $PREFIX; pkg-config and find_package clients agree with trac0r"
