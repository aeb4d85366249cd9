#!/bin/sh
# scripts/gpu-bundle with the built binary (--bin: no second build): the folder runs with
# its own libraries and an empty environment, leaves the C library and the compiler's
# runtime to the target, bundles the ICD loader, and the wrapper leaves an ICD setting
# given by the user alone.
# Usage: cli_opencl_bundle.sh TRAC0R_BINARY SCRATCH_DIR
set -u
. "$(dirname "$0")/common.sh"
cli_begin "$1" "$2"
script=$(dirname "$0")/../scripts/gpu-bundle

sh "$script" --bin "$BIN" --out b 2>err.txt || fail "gpu-bundle: exit status $?: $(cat err.txt)"
for f in b/trac0r b/bin/trac0r b/scripts/gpu-measure b/scenes/cornell-classic.json \
    b/lib/libOpenCL.so.1 b.tar.gz; do
    [ -e "$f" ] || fail "gpu-bundle made no $f"
done
for f in b/lib/libc.so.6 b/lib/libm.so.6 b/lib/libstdc++.so.6 b/lib/libgcc_s.so.1; do
    [ ! -e "$f" ] || fail "gpu-bundle copied $f, which the target provides"
done
# Every library the binary needs, other than the C library's and the compiler's, comes
# from lib/ when the wrapper's LD_LIBRARY_PATH is in force.
LD_LIBRARY_PATH=$PWD/b/lib ldd b/bin/trac0r | awk -v lib="$PWD/b/lib/" '
    $2 == "=>" && $1 !~ /^(libc|libm|libpthread|libdl|librt|libresolv|libstdc\+\+|libgcc_s)\.so/ &&
    index($3, lib) != 1 { print; bad = 1 } END { exit bad }' >stray.txt ||
    fail "libraries from outside the bundle: $(cat stray.txt)"
env -i PATH=/usr/bin:/bin b/trac0r --version >v.txt 2>&1 || fail "the bundle does not run: $(cat v.txt)"
grep -q "^trac0r " v.txt || fail "the bundle's --version: $(cat v.txt)"
env -i PATH=/usr/bin:/bin b/trac0r info --devices >d.txt 2>&1 || fail "info --devices: $(cat d.txt)"
grep -q "^  0: " d.txt || fail "the bundle lists no OpenCL device 0: $(cat d.txt)"
mkdir empty-icd
env -i PATH=/usr/bin:/bin OCL_ICD_VENDORS=$PWD/empty-icd b/trac0r info --devices >d.txt 2>&1
[ $? -eq 2 ] || fail "the wrapper overrode OCL_ICD_VENDORS: $(cat d.txt)"
rm -rf b b.tar.gz err.txt stray.txt v.txt d.txt empty-icd
# Usage errors: status 2.
sh "$script" --bin /nonexistent/trac0r --out c 2>/dev/null
[ $? -eq 2 ] || fail "gpu-bundle --bin /nonexistent: exit status not 2"
[ ! -e c ] || fail "gpu-bundle made a folder after a usage error"
sh "$script" --frobnicate 2>/dev/null
[ $? -eq 2 ] || fail "gpu-bundle --frobnicate: exit status not 2"

cli_end cli_opencl_bundle
