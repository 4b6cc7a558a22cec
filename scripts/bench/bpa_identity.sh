#!/bin/sh
# Dev-only: run `ball-pivoting` (defaults, given normals) on the 100k uniform torus, the
# vendored bunny's own vertices with their mesh normals, an open height-field sheet, a
# noisy box and the fandisk-like part, and print one checksum line per output mesh, so
# that two builds can be compared face for face (diff the two listings).
#
#   scripts/bench/bpa_identity.sh BINARY OUTDIR > listing.txt
set -eu
bin=$1
out=$2
root=$(cd "$(dirname "$0")/../.." && pwd)
mkdir -p "$out"
[ -f "$out/torus100k.ply" ] || "$bin" gen torus --points 100000 -o "$out/torus100k.ply" >/dev/null
[ -f "$out/bunny_v.ply" ] || "$bin" gen --mesh-input "$root/datasets/real/bunny.ply" --sampler vertices -o "$out/bunny_v.ply" >/dev/null
[ -f "$out/sheet.ply" ] || "$bin" gen height-field --points 20000 --seed 1 -o "$out/sheet.ply" >/dev/null
[ -f "$out/box_noisy.ply" ] || "$bin" gen box --points 20000 --noise gaussian:sigma=0.002 --seed 1 -o "$out/box_noisy.ply" >/dev/null
[ -f "$out/fandisk.ply" ] || "$bin" gen fandisk-like --points 20000 --sampler blue-noise --seed 1 -o "$out/fandisk.ply" >/dev/null
for b in torus100k bunny_v sheet box_noisy fandisk; do
    for t in 1 2; do
        RAYON_NUM_THREADS=$t "$bin" reconstruct --method ball-pivoting "$out/$b.ply" -o "$out/$b.bpa$t.ply" >/dev/null
        echo "$b.bpa.threads$t $(md5sum < "$out/$b.bpa$t.ply" | cut -d' ' -f1)"
    done
done
