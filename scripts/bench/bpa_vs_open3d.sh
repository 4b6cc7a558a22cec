#!/bin/sh
# Dev-only, not run by tests or CI: reconbench's `ball-pivoting` against Open3D's
# `create_from_point_cloud_ball_pivoting` on the same PLY file (with normals) and the
# same radii (2, 3, 5 mean spacings), both single-threaded, runs interleaved so that the
# ratio is taken under the same machine load. Prints the minimum of each and two ratios:
# against Open3D's ball pivoting call alone, and against that call plus the mean
# nearest-neighbour spacing Open3D's caller computes for the radii (reconbench's time
# includes its own spacing, input checks and writing the mesh; not the file read).
#
#   PY=/path/to/venv/bin/python scripts/bench/bpa_vs_open3d.sh target/release/reconbench /tmp/torus100k.ply 5
#
# PY must have `open3d` (pip install open3d-cpu; see scripts/peers/bpa_open3d.py).
set -eu
bin=$1
ply=$2
runs=${3:-5}
py=${PY:-python3}
root=$(cd "$(dirname "$0")/../.." && pwd)
ours=""
theirs=""
i=0
while [ "$i" -lt "$runs" ]; do
    t=$(RAYON_NUM_THREADS=1 "$bin" reconstruct --method ball-pivoting "$ply" -o /tmp/bpa_vs_open3d.ply --json |
        "$py" -c "import json,sys; d=json.load(sys.stdin); print(d['seconds'], int(d['summary']['faces']), int(d['diagnostics']['boundary_edges']))")
    ours="$ours
$t"
    o=$(OMP_NUM_THREADS=1 "$py" "$root/scripts/peers/bpa_open3d.py" "$ply" --repeat 1)
    theirs="$theirs
$(echo "$o" | sed -n 's/.*(\([0-9.]*\) s), radii.* \([0-9]*\) triangles, \([0-9.]*\) s .*/\3 \2 \1/p')"
    i=$((i + 1))
done
best_ours=$(echo "$ours" | sort -n | sed -n 2p)
best_theirs=$(echo "$theirs" | sort -n | sed -n 2p)
best_both=$(echo "$theirs" | awk 'NF { print $1 + $3 }' | sort -n | head -n 1)
echo "reconbench (s, triangles, boundary edges): $best_ours"
echo "open3d (s, triangles, s for the spacing): $best_theirs"
echo "$best_ours $best_theirs" | awk '{printf "ratio open3d / reconbench: %.2f\n", $4 / $1}'
echo "$best_ours $best_both" | awk '{printf "ratio open3d with its spacing (%.3f s) / reconbench: %.2f\n", $4, $4 / $1}'
