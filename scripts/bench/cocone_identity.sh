#!/bin/sh
# Dev-only: run cocone / tight-cocone (defaults and literal) on the 100k blue-noise torus,
# the vendored real sets and two CAD analogues, and print one checksum line per output
# mesh, so that two builds can be compared face for face (diff the two listings).
#
#   scripts/bench/cocone_identity.sh BINARY OUTDIR > listing.txt
set -eu
bin=$1
out=$2
root=$(cd "$(dirname "$0")/../.." && pwd)
mkdir -p "$out"
[ -f "$out/torus_bn100k.ply" ] || "$bin" gen torus --points 100000 --sampler blue-noise --seed 1 -o "$out/torus_bn100k.ply" >/dev/null
for s in cube-with-hole fandisk-like; do
    [ -f "$out/$s.ply" ] || "$bin" gen "$s" --points 8000 --sampler blue-noise --seed 1 -o "$out/$s.ply" >/dev/null
done
inputs="$out/torus_bn100k.ply $out/cube-with-hole.ply $out/fandisk-like.ply"
for r in bunny rocker-arm 3holes mechpart golf-club fandisk; do
    inputs="$inputs $root/datasets/real/$r.ply"
done
for f in $inputs; do
    b=$(basename "$f" .ply)
    "$bin" reconstruct --method cocone "$f" -o "$out/$b.cocone.ply" >/dev/null
    "$bin" reconstruct --method tight-cocone "$f" -o "$out/$b.tc.ply" >/dev/null
    "$bin" reconstruct --method tight-cocone --set repair_rounds=0 --set pocket_share=0 "$f" -o "$out/$b.tcl.ply" >/dev/null
    for m in cocone tc tcl; do
        echo "$b.$m $(md5sum < "$out/$b.$m.ply" | cut -d' ' -f1)"
    done
done
