#!/bin/sh
# Drives the real-time side of trac0r from the outside: the display curve (--tonemap) of
# render and view, render --denoise, and `trac0r bench realtime`.
# Usage: cli_realtime.sh TRAC0R_BINARY SCRATCH_DIR
set -u
. "$(dirname "$0")/common.sh"
SRC=$(cd "$(dirname "$0")/.." && pwd)
cli_begin "$1" "$2"
CLASSIC=$SRC/scenes/cornell-classic.json

expect_usage_error "--tonemap: expected clamp or filmic, got 'aces'" render --tonemap aces
expect_usage_error "--tonemap: expected clamp or filmic, got 'x'" view --tonemap x
expect_usage_error "--recon: expected off, accumulate" view --recon x

# psnr A B: the PSNR trac0r compare prints for A against the reference B.
psnr() {
    "$BIN" compare "$1" "$2" | awk '$1 == "psnr" { print $2 }'
}

# --tonemap: clamp is the default's bytes; filmic changes them; the headless viewer's
# screenshot through filmic equals render's.
"$BIN" render --width 40 --height 30 --spp 3 --out plain.png 2>/dev/null || fail "render failed"
"$BIN" render --width 40 --height 30 --spp 3 --tonemap clamp --out clamp.png 2>/dev/null ||
    fail "render --tonemap clamp failed"
cmp -s plain.png clamp.png || fail "--tonemap clamp changed the PNG"
"$BIN" render --width 40 --height 30 --spp 3 --tonemap filmic --out filmic.png 2>/dev/null ||
    fail "render --tonemap filmic failed"
cmp -s plain.png filmic.png && fail "--tonemap filmic wrote the clamp's bytes"
env -u DISPLAY SDL_VIDEODRIVER=dummy "$BIN" view --width 40 --height 30 --frames 3 \
    --tonemap filmic --screenshot vfilmic.png 2>err.txt || fail "view --tonemap filmic: $(cat err.txt)"
cmp -s vfilmic.png filmic.png || fail "view and render differ through filmic"
# The PFM stays linear radiance whatever the curve.
"$BIN" render --width 40 --height 30 --spp 3 --out plain.pfm 2>/dev/null
"$BIN" render --width 40 --height 30 --spp 3 --tonemap filmic --out filmic.pfm 2>/dev/null
cmp -s plain.pfm filmic.pfm || fail "--tonemap filmic changed the PFM"

# --denoise: the offline denoiser guided by the passes brings a 4-spp render closer to a
# converged one (by more than 3 dB).
"$BIN" render "$CLASSIC" --width 64 --height 64 --spp 256 --seed 99 --out ref.pfm 2>/dev/null ||
    fail "reference render failed"
"$BIN" render "$CLASSIC" --width 64 --height 64 --spp 4 --out noisy.pfm 2>/dev/null
"$BIN" render "$CLASSIC" --width 64 --height 64 --spp 4 --denoise --out den.pfm 2>err.txt ||
    fail "render --denoise: $(cat err.txt)"
p0=$(psnr noisy.pfm ref.pfm)
p1=$(psnr den.pfm ref.pfm)
awk -v a="$p0" -v b="$p1" 'BEGIN { exit !(b > a + 3) }' ||
    fail "--denoise: PSNR $p0 dB -> $p1 dB"
"$BIN" render "$CLASSIC" --width 64 --height 64 --spp 4 --denoise --tonemap filmic \
    --out den.png 2>/dev/null || fail "render --denoise --tonemap filmic to PNG failed"

# bench realtime: a short path through the classic box with a camera cut; the CSV has a
# row per method and frame, accumulation beats the raw frames and SVGF beats them by more
# than 2 dB even at this tiny size (measured 2.7 dB; 6-7 dB at 160x120), and every method
# recovers after the cut within 8 frames.
rm -f err.txt
expect_usage_error "--methods: unknown method 'blur'" bench realtime --methods blur
expect_usage_error "'halton'" bench realtime --sampler halton
expect_usage_error "--cut: expected a frame before --frames (8), got 9" bench realtime --frames 8 --cut 9
"$BIN" bench realtime "$CLASSIC" --width 48 --height 36 --frames 14 --cut 6 --reference-spp 64 \
    --threads 1 --out rt >rt.txt 2>rt.err || fail "bench realtime: $(cat rt.err)"
[ "$(wc -l <rt.csv)" -eq $((1 + 5 * 14)) ] || fail "bench realtime: $(wc -l <rt.csv) CSV lines"
head -n1 rt.csv | grep -q "^method,frame,render_ms,temporal_ms,spatial_ms,total_ms,psnr_db,ssim,flicker$" ||
    fail "bench realtime CSV header: $(head -n1 rt.csv)"
grep -q "frame 14/14" rt.err || fail "bench realtime: no progress on stderr"
# The plot: a PNG (its signature and gnuplot's 900x600 in the IHDR chunk), named in the
# last line.
[ "$(od -An -tx1 -N8 rt.png | tr -d ' \n')" = "89504e470d0a1a0a" ] || fail "bench realtime: rt.png is no PNG"
[ "$(od -An -tu1 -j16 -N8 rt.png | tr -s ' ' | sed 's/^ //')" = "0 0 3 132 0 0 2 88" ] ||
    fail "bench realtime: rt.png is not 900x600"
tail -n1 rt.txt | grep -qF "rt.png" || fail "bench realtime: plot not named: $(tail -n1 rt.txt)"
# A scene whose name would end gnuplot's quoted title still plots; a prefix whose PNG
# cannot be written is refused before anything renders.
cp "$CLASSIC" "q'uote.json"
"$BIN" bench realtime "q'uote.json" --width 16 --height 12 --frames 2 --reference-spp 2 \
    --threads 1 --methods off --out rq >rq.txt 2>rq.err || fail "bench realtime, quoted scene: $(cat rq.err)"
[ -s rq.png ] && tail -n1 rq.txt | grep -q "rq.png" || fail "bench realtime: no plot for a quoted scene name"
mkdir -p dirpng.png
"$BIN" bench realtime "$CLASSIC" --width 16 --height 12 --frames 2 --reference-spp 2 \
    --threads 1 --methods off --out dirpng >/dev/null 2>&1
rc=$?
[ "$rc" -eq 2 ] || fail "bench realtime with PREFIX.png a directory: exit $rc"
[ ! -e dirpng.csv ] || fail "bench realtime wrote a CSV although its plot could not be written"
# col METHOD N: column N of METHOD's row in the table.
col() {
    awk -v m="$1" -v n="$2" '$1 == m { print $n }' rt.txt
}
raw=$(col off 7)
svgf=$(col svgf 7)
acc=$(col accumulate 7)
awk -v a="$raw" -v b="$svgf" -v c="$acc" 'BEGIN { exit !(b > a + 2 && c > a) }' ||
    fail "bench realtime: svgf $svgf dB, accumulate $acc dB vs raw $raw dB"
for m in accumulate bilateral atrous svgf; do
    r=$(col $m 11)
    [ "$r" != never ] && [ "$r" -le 8 ] || fail "bench realtime: $m recovers after $r frames"
done

# --max-depth D renders frames and references at depth D; --bias-reference-depth prints
# the PSNR of the depth-D reference against a deeper one: it must rise with D (measured
# at this size: 28.4 dB at depth 2, 34.3 dB at 3, 51 dB for 64 against 64).
expect_usage_error "--bias-reference-depth" bench realtime --bias-reference-depth 0
expect_usage_error "--bias-reference-depth" bench realtime --integrator bdpt --bias-reference-depth 64
# --reference-sampler: the frames keep their sampler, the references take the one named
# (sobol named is the default's run to the digit; random gives other references).
expect_usage_error "'halton'" bench realtime --reference-sampler halton
refs() {
    n=$1
    shift
    "$BIN" bench realtime "$CLASSIC" --width 48 --height 36 --frames 2 --reference-spp 16 \
        --threads 1 --methods off --out "rs$n" "$@" >/dev/null 2>&1 || fail "--reference-sampler $*"
    cut -d, -f7 "rs$n.csv" | tr '\n' ' '
}
rs_default=$(refs 0)
rs_sobol=$(refs 1 --reference-sampler sobol)
rs_random=$(refs 2 --reference-sampler random)
[ "$rs_default" = "$rs_sobol" ] || fail "--reference-sampler sobol: '$rs_sobol' vs '$rs_default'"
[ "$rs_default" != "$rs_random" ] || fail "--reference-sampler random changed nothing: '$rs_random'"
# The frames' sampler: random unless --sampler names one, and the references stay sobol
# whatever the frames' (so --sampler random is the default's run to the digit, and
# --sampler sobol changes the frames, not the references).
fs_random=$(refs 3 --sampler random)
fs_sobol=$(refs 4 --sampler sobol)
[ "$rs_default" = "$fs_random" ] || fail "--sampler random: '$fs_random' vs '$rs_default'"
[ "$rs_default" != "$fs_sobol" ] || fail "--sampler sobol changed nothing: '$fs_sobol'"
"$BIN" bench realtime "$CLASSIC" --width 48 --height 36 --frames 2 --reference-spp 16 \
    --threads 1 --methods off --out rs5 --sampler zsobol --reference-sampler random >rs5.txt \
    2>/dev/null || fail "bench realtime --sampler zsobol --reference-sampler random"
grep -q "frames zsobol, references random" rs5.txt || fail "bench realtime: samplers not named"

# The reconstruction's settings: out-of-range values are refused; --max-history 1 leaves
# no history, so accumulate is the raw frame to the digit when the emission is filtered
# with the rest (--resolve-emission 0), and above it on average when the lamp's edge is
# resolved (the default, 4 x 4 rays per edge pixel); SVGF's settings change SVGF and
# not the bilateral filter; a new frame's weight of 0.5 instead of 1/3 and 1/4 changes
# frames 2 and 3 of accumulate; the header names the settings.
expect_usage_error "--svgf-iterations" bench realtime --svgf-iterations 0
expect_usage_error "--svgf-iterations" bench realtime --svgf-iterations 9
expect_usage_error "--alpha-min" bench realtime --alpha-min 0
expect_usage_error "--max-history" bench realtime --max-history 0.5
expect_usage_error "--svgf-sigma-l" bench realtime --svgf-sigma-l x
expect_usage_error "--taa" bench realtime --taa 1.5
expect_usage_error "--resolve-emission" bench realtime --resolve-emission 17
expect_usage_error "--resolve-emission" bench realtime --resolve-emission -1
rp() {
    n=$1
    shift
    "$BIN" bench realtime "$CLASSIC" --width 48 --height 36 --frames 4 --reference-spp 8 \
        --threads 1 --methods off,accumulate,bilateral,svgf --out "rp$n" "$@" >"rp$n.txt" \
        2>/dev/null || fail "bench realtime $*"
}
col() { awk -F, -v m="$2" '$1 == m { printf "%s ", $7 }' "rp$1.csv"; }
rp 0
rp 1 --max-history 1 --resolve-emission 0
rp 4 --max-history 1
rp 2 --svgf-iterations 1 --svgf-sigma-l 8 --taa 0.5
rp 3 --alpha-min 0.5
[ "$(col 1 off)" = "$(col 1 accumulate)" ] ||
    fail "--max-history 1: accumulate '$(col 1 accumulate)' is not the raw '$(col 1 off)'"
[ "$(col 0 off)" != "$(col 0 accumulate)" ] || fail "accumulate is the raw frame by default"
[ "$(col 0 bilateral)" = "$(col 2 bilateral)" ] || fail "SVGF's settings changed bilateral"
[ "$(col 0 svgf)" != "$(col 2 svgf)" ] || fail "SVGF's settings changed nothing"
[ "$(col 0 accumulate)" != "$(col 3 accumulate)" ] || fail "--alpha-min 0.5 changed nothing"
grep -q "svgf-iterations 3, svgf-sigma-l 4, taa 0," rp0.txt || fail "defaults not named"
[ "$(col 4 off)" = "$(col 1 off)" ] || fail "--resolve-emission changed the raw frame"
mean() { awk -F, -v m="$2" '$1 == m { s += $7; n++ } END { printf "%.4f", s / n }' "rp$1.csv"; }
awk -v a="$(mean 4 accumulate)" -v r="$(mean 4 off)" 'BEGIN { exit !(a > r + 0.1) }' ||
    fail "resolved emission: accumulate $(mean 4 accumulate) dB not above raw $(mean 4 off) dB"
grep -q "4 x 4" rp0.txt || fail "the emission's resolution not named"
grep -q "4 x 4" rp1.txt && fail "--resolve-emission 0 still names a resolution"
grep -q "svgf-iterations 1, svgf-sigma-l 8, taa 0.5," rp2.txt || fail "settings not named"

# --animate: the thesis box's last shape (a sphere) moves before every frame but the
# first, so frame 0 is the static run's to the digit and later frames differ; the moving
# shape's pixels get their own PSNR per method, and SVGF's is above the raw frame's. Without
# the extra samples for pixels without history (--fresh-spp 0): they go to the frame every
# method gets, raw included, so on the shape's few pixels without history they would
# compare the raw frame's extra samples with SVGF's, not SVGF with the raw frame.
THESIS=$SRC/scenes/cornell-thesis.json
an() {
    n=$1
    shift
    "$BIN" bench realtime "$THESIS" --width 64 --height 48 --frames 6 --reference-spp 8 \
        --threads 1 --methods off,accumulate,svgf --fresh-spp 0 --out "an$n" "$@" >"an$n.txt" \
        2>/dev/null ||
        fail "bench realtime $*"
}
an 0
an 1 --animate
f0() { awk -F, -v f="$2" '$1 == "svgf" && $2 == f { print $7 }' "an$1.csv"; }
[ "$(f0 0 0)" = "$(f0 1 0)" ] || fail "--animate changed frame 0: $(f0 1 0) vs $(f0 0 0)"
[ "$(f0 0 5)" != "$(f0 1 5)" ] || fail "--animate changed nothing by frame 5"
mv_off=$(awk '/^moving shape/ { for (i = 1; i < NF; ++i) if ($i == "off") print $(i + 1) }' an1.txt)
mv_svgf=$(awk '/^moving shape/ { for (i = 1; i < NF; ++i) if ($i == "svgf") print $(i + 1) }' an1.txt)
awk -v a="$mv_off" -v b="$mv_svgf" 'BEGIN { exit !(a + 0 > 0 && b > a) }' ||
    fail "--animate: moving shape PSNR raw '$mv_off', svgf '$mv_svgf'"
grep -q "^moving shape" an0.txt && fail "a static run printed a moving shape's PSNR"
head -n1 an1.csv | grep -q ",flicker,shape_psnr_db$" || fail "--animate: no shape_psnr_db column"
head -n1 an0.csv | grep -q "shape_psnr_db" && fail "a static run wrote shape_psnr_db"

# --max-history-moving: a moving surface keeps at most that many frames (default 4), so
# frames 0-3 equal a run with a cap of 64 to the digit and frame 5 does not (the classic
# box's moving wall: at this size most of the thesis box's sphere is its rim, whose
# history restarts anyway).
expect_usage_error "--max-history-moving" bench realtime --max-history-moving 0
for cap in 4 64; do
    "$BIN" bench realtime "$CLASSIC" --width 64 --height 48 --frames 6 --reference-spp 8 \
        --threads 1 --methods accumulate --out "mh$cap" --animate --max-history-moving "$cap" \
        >"mh$cap.txt" 2>/dev/null || fail "bench realtime --max-history-moving $cap"
done
f1() { awk -F, -v f="$2" '$1 == "accumulate" && $2 == f { print $7 }' "mh$1.csv"; }
for f in 0 1 2 3; do
    [ "$(f1 4 $f)" = "$(f1 64 $f)" ] || fail "--max-history-moving 64 changed frame $f"
done
[ "$(f1 4 5)" != "$(f1 64 5)" ] || fail "--max-history-moving 64 changed nothing by frame 5"
grep -q "max-history-moving 64," mh64.txt || fail "--max-history-moving not named"

# --animate-frames A:B: the shape rests before frame A (frames 0-2 are the static run's
# to the digit, frame 3 is not) and after B; with A >= 2 and B < N every method gets
# the frames it needs after the stop to return to the shape's PSNR before it moved.
expect_usage_error "--animate-frames" bench realtime --animate-frames 0:3
expect_usage_error "--animate-frames" bench realtime --animate-frames 3:3
expect_usage_error "--animate-frames" bench realtime --animate-frames 3:x
expect_usage_error "--animate-frames" bench realtime --animate-frames -1:3
expect_usage_error "--animate-frames" bench realtime --frames 8 --animate-frames 2:9
an 4 --animate-frames 3:5
for f in 0 1 2; do
    [ "$(f0 0 $f)" = "$(f0 4 $f)" ] || fail "--animate-frames 3:5 changed frame $f"
done
[ "$(f0 0 3)" != "$(f0 4 3)" ] || fail "--animate-frames 3:5: frame 3 did not change"
grep -q "moves before frames 3 to 4" an4.txt || fail "--animate-frames: window not named"
awk '/^moving shape stopped at frame 5/ { for (m = 0; m < 3; ++m) {
        name = m == 0 ? "off" : m == 1 ? "accumulate" : "svgf"; found = 0
        for (i = 1; i < NF; ++i) if ($i == name && ($(i + 1) ~ /^[0-9]+$/ || $(i + 1) == "never")) found = 1
        if (!found) exit 1 } ok = 1 } END { exit !ok }' an4.txt ||
    fail "--animate-frames: no recovery per method: $(grep '^moving shape stopped' an4.txt)"

# bias D: the bias PSNR printed for --max-depth D against depth 64.
bias() {
    "$BIN" bench realtime "$CLASSIC" --width 48 --height 36 --frames 2 --reference-spp 64 \
        --threads 1 --methods off --max-depth "$1" --bias-reference-depth 64 --out "b$1" \
        >"b$1.txt" 2>"b$1.err" || fail "bench realtime --max-depth $1: $(cat "b$1.err")"
    grep -q "max depth $1," "b$1.txt" || fail "bench realtime --max-depth $1: header"
    # "PSNR X dB", or "PSNR above X dB" where the references do not resolve the bias.
    awk '$1 == "bias" { for (i = 1; i < NF; ++i) if ($i == "PSNR") {
        print ($(i + 1) == "above" ? $(i + 2) : $(i + 1)); exit } }' "b$1.txt"
}
b2=$(bias 2)
b3=$(bias 3)
b64=$(bias 64)
awk -v a="$b2" -v b="$b3" -v c="$b64" 'BEGIN { exit !(a + 2 < b && b + 5 < c && c > 40) }' ||
    fail "bench realtime: depth bias $b2 / $b3 / $b64 dB at depths 2 / 3 / 64"

# ReSTIR DI and the firefly control: the frames change (the options reach the library),
# the references do not, and unknown values are usage errors (status 2).
rt_psnr() { # CSV: the raw frames' mean PSNR
    awk -F, '$1 == "off" { s += $7; n += 1 } END { printf "%.4f", s / n }' "$1"
}
"$BIN" bench realtime "$CLASSIC" --width 32 --height 24 --frames 3 --reference-spp 8 --threads 1 \
    --methods off,accumulate --out plainff >/dev/null 2>&1 || fail "bench realtime (plain) failed"
"$BIN" bench realtime "$CLASSIC" --width 32 --height 24 --frames 3 --reference-spp 8 --threads 1 \
    --methods off,accumulate --restir di --out restir >/dev/null 2>restir.err ||
    fail "bench realtime --restir di: $(cat restir.err)"
[ "$(wc -l <restir.csv)" -eq $((1 + 2 * 3)) ] || fail "--restir di: $(wc -l <restir.csv) CSV lines"
[ "$(rt_psnr plainff.csv)" != "$(rt_psnr restir.csv)" ] || fail "--restir di changed no frame"
"$BIN" bench realtime "$CLASSIC" --width 32 --height 24 --frames 2 --reference-spp 8 --threads 1 \
    --methods off --restir di --restir-unbiased --clamp-indirect 0 --regularize off --out unb \
    >/dev/null 2>unb.err || fail "bench realtime --restir-unbiased: $(cat unb.err)"
"$BIN" bench realtime "$CLASSIC" --width 32 --height 24 --frames 3 --reference-spp 8 --threads 1 \
    --methods off,accumulate --restir di+gi --out restirgi >/dev/null 2>restirgi.err ||
    fail "bench realtime --restir di+gi: $(cat restirgi.err)"
[ "$(rt_psnr restir.csv)" != "$(rt_psnr restirgi.csv)" ] || fail "--restir di+gi changed no frame"
for bad in "--restir gi" "--regularize maybe" "--clamp-indirect -1"; do
    # shellcheck disable=SC2086
    "$BIN" bench realtime "$CLASSIC" --frames 2 $bad >/dev/null 2>&1
    [ $? -eq 2 ] || fail "bench realtime $bad: not a usage error"
done

cli_end cli_realtime
