#!/bin/sh
# Two trac0r binaries measured alternately on the same benchmarks, so that a change can be
# shown to keep the speed: `bench frame` (the thesis's frame, median frame time) and
# `bench rays` (Mrays/s of the wide BVH on primary, diffuse and shadow rays), ROUNDS times
# each, old then new; prints every figure and the median of each with the ratio new/old.
# Usage: tools/bench-ab.sh OLD_BINARY NEW_BINARY [ROUNDS (default 5)]
# Run it on a quiet machine: nothing else building or testing; it prints the load average.
set -eu
old=$1
new=$2
rounds=${3:-5}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

median() { sort -g | awk '{v[NR]=$1} END {print (NR%2) ? v[(NR+1)/2] : (v[NR/2]+v[NR/2+1])/2}'; }

echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
i=1
while [ "$i" -le "$rounds" ]; do
    for which in old new; do
        bin=$old
        [ "$which" = new ] && bin=$new
        # bench frame: "median X ms" -> X
        "$bin" bench frame --frames 20 >"$tmp/frame.txt" 2>&1
        grep -o 'median [0-9.]* ms' "$tmp/frame.txt" | awk '{print $2}' >>"$tmp/frame.$which"
        # bench rays on the small box: bvh's primary, diffuse and shadow Mrays/s
        "$bin" bench rays --scene builtin:cornell --accels bvh --runs 3 >"$tmp/rays.txt" 2>&1
        awk '$3 == "bvh" {print $(NF - 2), $(NF - 1), $NF; exit}' "$tmp/rays.txt" >>"$tmp/rays.$which"
    done
    i=$((i + 1))
done
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
for which in old new; do
    echo "$which frame ms: $(tr '\n' ' ' <"$tmp/frame.$which")"
    echo "$which rays Mrays/s (primary diffuse shadow): $(tr '\n' '|' <"$tmp/rays.$which")"
done
fo=$(median <"$tmp/frame.old")
fn=$(median <"$tmp/frame.new")
echo "bench frame median: old $fo ms, new $fn ms, new/old $(echo "$fn $fo" | awk '{printf "%.3f", $1 / $2}')"
col=1
while [ "$col" -le 3 ]; do
    ro=$(awk -v c="$col" '{print $c}' "$tmp/rays.old" | median)
    rn=$(awk -v c="$col" '{print $c}' "$tmp/rays.new" | median)
    name=$(echo "primary diffuse shadow" | cut -d' ' -f"$col")
    echo "bench rays bvh $name median: old $ro, new $rn, new/old $(echo "$rn $ro" | awk '{printf "%.3f", $1 / $2}')"
    col=$((col + 1))
done
