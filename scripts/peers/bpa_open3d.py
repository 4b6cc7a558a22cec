#!/usr/bin/env python3
"""Dev-only peer timing: Open3D's ball pivoting on a PLY cloud with normals.

Runs `create_from_point_cloud_ball_pivoting` on the same file and the same radii as
reconbench's `ball-pivoting` (multiples of the mean nearest-neighbour spacing, default
2, 3, 5), single-threaded as Open3D's BPA is, and prints the wall time of the
reconstruction alone (reading the file and the spacing are timed apart), with the
triangle count. Not used by tests or CI.

    pip install open3d-cpu        # needs Debian's libusb-1.0-0, libgl1, libgomp1
    target/release/reconbench gen torus --points 100000 -o /tmp/torus100k.ply
    python3 scripts/peers/bpa_open3d.py /tmp/torus100k.ply --repeat 3
"""

import argparse
import sys
import time


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("ply", help="point cloud with nx, ny, nz (oriented normals)")
    ap.add_argument(
        "--radii-spacing",
        type=float,
        nargs="+",
        default=[2.0, 3.0, 5.0],
        help="radii as multiples of the mean nearest-neighbour spacing",
    )
    ap.add_argument("--repeat", type=int, default=1, help="runs; the minimum is reported")
    ap.add_argument("--out", help="write the mesh of the last run here (PLY)")
    args = ap.parse_args()

    import open3d as o3d

    pcd = o3d.io.read_point_cloud(args.ply)
    if not pcd.has_normals():
        print(f"{args.ply}: no normals (nx, ny, nz) in the file", file=sys.stderr)
        return 2
    t0 = time.perf_counter()
    spacing = float(sum(pcd.compute_nearest_neighbor_distance()) / len(pcd.points))
    t_spacing = time.perf_counter() - t0
    radii = o3d.utility.DoubleVector([k * spacing for k in args.radii_spacing])
    best = None
    mesh = None
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        mesh = o3d.geometry.TriangleMesh.create_from_point_cloud_ball_pivoting(pcd, radii)
        dt = time.perf_counter() - t0
        best = dt if best is None else min(best, dt)
    print(
        f"open3d {o3d.__version__} ball pivoting: {len(pcd.points)} points, "
        f"spacing {spacing:.6g} ({t_spacing:.3f} s), radii {list(radii)}, "
        f"{len(mesh.triangles)} triangles, {best:.3f} s (min of {args.repeat})"
    )
    if args.out:
        o3d.io.write_triangle_mesh(args.out, mesh)
    return 0


if __name__ == "__main__":
    sys.exit(main())
