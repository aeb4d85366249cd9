#!/bin/sh
# web_check.sh - the web build (docs/web.md) tested in a real browser.
#
#   web_check.sh build SRC WEBDIR
#       configures and builds the web preset's targets into WEBDIR (Emscripten);
#   web_check.sh page SRC TRAC0R WEBDIR SCRATCH isolated|fallback
#       serves WEBDIR with scripts/serve-web (with the cross-origin isolation headers, or
#       without them for the fallback), opens test.html in headless Chromium
#       (scripts/web-browser) and checks what the page reports: the module that fits
#       (threads and SIMD, or the single-threaded one with the fallback said), and its
#       still of the classic box at a fixed seed against the native `trac0r render` of
#       the same settings: bit for bit, or within 45 dB PSNR (Emscripten's libm rounds
#       some float functions otherwise than glibc; docs/web.md); then three real-time
#       frames with SVGF; and every shipped scene file loads and renders (without its
#       meshes: the web build has no Assimp).
#
# Exits 77 (CTest: skipped) where emcc or chromium is absent; scripts/install-deps
# installs both.
set -u
mode=$1
src=$2

need() {
    if ! command -v "$1" >/dev/null 2>&1; then
        echo "SKIP: $1 not found (scripts/install-deps installs emscripten and chromium)"
        exit 77
    fi
}
need emcc
need chromium

if [ "$mode" = build ]; then
    web=$3
    cmake -S "$src" -B "$web" -G Ninja -DCMAKE_BUILD_TYPE=Release \
        -DCMAKE_TOOLCHAIN_FILE="$src/cmake/web-toolchain.cmake" >"$web.configure.log" 2>&1 ||
        { cat "$web.configure.log"; exit 1; }
    cmake --build "$web" -j 2 || exit 1
    for f in index.html app.js common.js test.html test.js trac0r.js trac0r.wasm \
        trac0r.worker.js trac0r-st.js trac0r-st.wasm scenes/index.json \
        scenes/cornell-classic.json; do
        [ -f "$web/$f" ] || { echo "FAIL: the web build has no $f"; exit 1; }
    done
    echo "web build complete: $web"
    exit 0
fi

bin=$3
web=$(cd "$4" && pwd) || exit 1
dir=$5
kind=$6
w=160 h=120 spp=8 seed=7
rm -rf "$dir"
mkdir -p "$dir/site"
failures=0
fail() {
    echo "FAIL: $*" >&2
    failures=$((failures + 1))
}

# The site: the web build's files, and the native render beside them.
for f in "$web"/*.html "$web"/*.js "$web"/*.wasm "$web"/scenes; do
    ln -s "$f" "$dir/site/"
done
"$bin" render "$src/scenes/cornell-classic.json" --width $w --height $h --spp $spp --seed $seed \
    --threads 2 --out "$dir/site/native.pfm" 2>"$dir/native.err" ||
    { cat "$dir/native.err"; echo "FAIL: native render"; exit 1; }

flag=""
[ "$kind" = fallback ] && flag=--no-isolation
python3=/usr/bin/python3
[ -x "$python3" ] || python3=python3
"$python3" "$src/scripts/serve-web" --dir "$dir/site" --port 0 --port-file "$dir/port" --quiet \
    $flag 2>"$dir/serve.err" &
server=$!
trap 'kill $server 2>/dev/null' EXIT
i=0
while [ ! -s "$dir/port" ] && [ $i -lt 100 ]; do
    sleep 0.1
    i=$((i + 1))
done
[ -s "$dir/port" ] || { cat "$dir/serve.err"; echo "FAIL: serve-web did not start"; exit 1; }
port=$(cat "$dir/port")

url="http://127.0.0.1:$port/test.html?w=$w&h=$h&spp=$spp&seed=$seed&threads=2&ref=native.pfm&frames=3&fw=64&fh=48&allscenes=1"
"$python3" "$src/scripts/web-browser" "$url" --wait "window.testDone === true" --timeout 300 \
    --print "document.getElementById('result').textContent" >"$dir/result.txt" 2>"$dir/browser.err"
rc=$?
cat "$dir/result.txt"
[ $rc -eq 0 ] || { cat "$dir/browser.err"; fail "headless Chromium: exit $rc"; }

value() {
    sed -n "s/^$1=//p" "$dir/result.txt" | head -n 1
}
expect() {
    got=$(value "$1")
    [ "$got" = "$2" ] || fail "$kind: $1 is '$got', expected '$2' ($(value error))"
}

expect ok 1
nscenes=$(ls "$src"/scenes/*.json | wc -l)
expect scenes "$nscenes"
expect scenes_rendered "$nscenes"
expect json_text_same 1
expect frames 3
expect frame_method svgf
if [ "$kind" = isolated ]; then
    expect isolated 1
    expect fallback 0
    expect module trac0r
    expect threads 2
    value info | grep -q "traversal sse2" || fail "isolated: the wide BVH does not take its SSE path: $(value info)"
else
    expect isolated 0
    expect fallback 1
    expect module trac0r-st
    expect threads 1
    [ -n "$(value fallback_reason)" ] || fail "fallback: no reason given"
fi
expect compare_values $((w * h * 3))
if [ "$(value identical)" != 1 ]; then
    psnr=$(value psnr)
    awk -v p="$psnr" 'BEGIN { exit !(p == "inf" || p + 0 >= 45) }' ||
        fail "$kind: the still differs from the native render: PSNR '$psnr' dB < 45"
fi

if [ $failures -ne 0 ]; then
    echo "web_check $kind: $failures check(s) failed"
    exit 1
fi
echo "web_check $kind: all checks passed ($(value compare_equal) of $(value compare_values) values equal, PSNR $(value psnr) dB)"
