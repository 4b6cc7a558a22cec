#!/usr/bin/env python3
"""Peer adapters behind reconbench's external-method interface (CGAL, Open3D, PyMeshLab).

    scripts/peers/run <peer> <method> INPUT OUTPUT [options]
    scripts/peers/run check

INPUT is the cloud reconbench writes (PLY, binary or ascii, extra properties ignored);
OUTPUT is the mesh (PLY) or, for normal estimators, the cloud with normals (PLY) that
reconbench reads back. Methods:

    open3d bpa       --radii-spacing 1.25 2.5 5   ball pivoting (needs oriented normals)
    open3d poisson   --depth 8 [--trim Q]         screened Poisson (needs oriented normals)
    open3d normals   --k 30                       PCA normals, oriented by a tangent-plane MST
    pymeshlab poisson --depth 8                   screened Poisson (needs oriented normals)
    pymeshlab bpa                                 ball pivoting, MeshLab's automatic radius
    cgal afront                                   advancing front (Cohen-Steiner & Da)
    cgal jet-normals --k 18                       jet normals + MST orientation
    cgal pca-normals --k 18                       PCA normals + MST orientation

Every adapter prints one line on stderr naming what is missing when its package is absent
(exit 3), so a cell fails with that line.
"""

import argparse
import os
import sys
import tempfile

import numpy as np

PLY_TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1",
    "short": "i2", "int16": "i2", "ushort": "u2", "uint16": "u2",
    "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
}


def read_ply(path):
    """Vertex properties of a PLY file (binary or ascii) as a dict of arrays."""
    with open(path, "rb") as f:
        if f.readline().strip() != b"ply":
            raise SystemExit(f"{path}: not a PLY file")
        fmt, props, count, in_vertex = None, [], 0, False
        while True:
            line = f.readline()
            if not line:
                raise SystemExit(f"{path}: truncated PLY header")
            w = line.split()
            if not w:
                continue
            if w[0] == b"format":
                fmt = w[1].decode()
            elif w[0] == b"element":
                in_vertex = w[1] == b"vertex"
                if in_vertex:
                    count = int(w[2])
            elif w[0] == b"property" and in_vertex:
                if w[1] == b"list":
                    raise SystemExit(f"{path}: list property in the vertex element")
                props.append((w[2].decode(), PLY_TYPES[w[1].decode()]))
            elif w[0] == b"end_header":
                break
        if fmt == "ascii":
            data = np.loadtxt(f, max_rows=count, ndmin=2)
            return {name: data[:, i] for i, (name, _) in enumerate(props)}
        order = "<" if fmt == "binary_little_endian" else ">"
        dt = np.dtype([(n, order + t) for n, t in props])
        arr = np.frombuffer(f.read(dt.itemsize * count), dtype=dt, count=count)
        return {n: arr[n].astype(np.float64) for n, _ in props}


def points_normals(path, need_normals):
    v = read_ply(path)
    p = np.stack([v["x"], v["y"], v["z"]], axis=1)
    n = None
    if all(k in v for k in ("nx", "ny", "nz")):
        n = np.stack([v["nx"], v["ny"], v["nz"]], axis=1)
    if need_normals and n is None:
        raise SystemExit(f"{path}: this peer needs normals (put a normal step before it)")
    return p, n


def write_mesh(path, verts, faces):
    verts = np.asarray(verts, dtype="<f8")
    faces = np.asarray(faces, dtype="<i4")
    with open(path, "wb") as f:
        f.write(
            (
                "ply\nformat binary_little_endian 1.0\n"
                f"element vertex {len(verts)}\nproperty double x\nproperty double y\n"
                f"property double z\nelement face {len(faces)}\n"
                "property list uchar int vertex_indices\nend_header\n"
            ).encode()
        )
        f.write(verts.tobytes())
        rec = np.zeros(len(faces), dtype=[("n", "u1"), ("i", "<i4", (3,))])
        rec["n"] = 3
        rec["i"] = faces
        f.write(rec.tobytes())


def write_cloud(path, pts, normals):
    arr = np.concatenate([pts, normals], axis=1).astype("<f8")
    with open(path, "wb") as f:
        f.write(
            (
                "ply\nformat binary_little_endian 1.0\n"
                f"element vertex {len(arr)}\n"
                + "".join(f"property double {k}\n" for k in ("x", "y", "z", "nx", "ny", "nz"))
                + "end_header\n"
            ).encode()
        )
        f.write(arr.tobytes())


def need(module):
    try:
        return __import__(module)
    except ImportError as e:
        print(f"peer package '{module}' is not installed ({e}); run scripts/peers/setup.sh", file=sys.stderr)
        raise SystemExit(3)


def mean_spacing(o3d, pcd):
    return float(np.mean(np.asarray(pcd.compute_nearest_neighbor_distance())))


def open3d_cloud(o3d, p, n):
    pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(p))
    if n is not None:
        pcd.normals = o3d.utility.Vector3dVector(n)
    return pcd


def o3d_bpa(a):
    o3d = need("open3d")
    p, n = points_normals(a.input, True)
    pcd = open3d_cloud(o3d, p, n)
    s = mean_spacing(o3d, pcd)
    radii = o3d.utility.DoubleVector([r * s for r in a.radii_spacing])
    m = o3d.geometry.TriangleMesh.create_from_point_cloud_ball_pivoting(pcd, radii)
    write_mesh(a.output, np.asarray(m.vertices), np.asarray(m.triangles))


def o3d_poisson(a):
    o3d = need("open3d")
    p, n = points_normals(a.input, True)
    pcd = open3d_cloud(o3d, p, n)
    m, dens = o3d.geometry.TriangleMesh.create_from_point_cloud_poisson(pcd, depth=a.depth)
    if a.trim > 0:
        dens = np.asarray(dens)
        m.remove_vertices_by_mask(dens < np.quantile(dens, a.trim))
    write_mesh(a.output, np.asarray(m.vertices), np.asarray(m.triangles))


def o3d_normals(a):
    o3d = need("open3d")
    p, _ = points_normals(a.input, False)
    pcd = open3d_cloud(o3d, p, None)
    pcd.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(a.k))
    pcd.orient_normals_consistent_tangent_plane(a.k)
    write_cloud(a.output, p, np.asarray(pcd.normals))


def ml_mesh(ml, p, n):
    if n is None:
        return ml.Mesh(vertex_matrix=p)
    return ml.Mesh(vertex_matrix=p, v_normals_matrix=n)


def ml_poisson(a):
    ml = need("pymeshlab")
    p, n = points_normals(a.input, True)
    ms = ml.MeshSet()
    ms.add_mesh(ml_mesh(ml, p, n))
    ms.generate_surface_reconstruction_screened_poisson(depth=a.depth)
    m = ms.current_mesh()
    write_mesh(a.output, m.vertex_matrix(), m.face_matrix())


def ml_bpa(a):
    ml = need("pymeshlab")
    p, n = points_normals(a.input, False)
    ms = ml.MeshSet()
    ms.add_mesh(ml_mesh(ml, p, n))
    ms.generate_surface_reconstruction_ball_pivoting()
    m = ms.current_mesh()
    write_mesh(a.output, m.vertex_matrix(), m.face_matrix())


def cgal_point_set(p):
    need("CGAL")
    from CGAL.CGAL_Kernel import Point_3
    from CGAL.CGAL_Point_set_3 import Point_set_3

    ps = Point_set_3()
    for x, y, z in p:
        ps.insert(Point_3(float(x), float(y), float(z)))
    return ps


def cgal_afront(a):
    p, _ = points_normals(a.input, False)
    ps = cgal_point_set(p)
    from CGAL.CGAL_Advancing_front_surface_reconstruction import (
        advancing_front_surface_reconstruction,
    )
    from CGAL.CGAL_Polyhedron_3 import Polyhedron_3

    poly = Polyhedron_3()
    advancing_front_surface_reconstruction(ps, poly)
    with tempfile.TemporaryDirectory() as d:
        off = os.path.join(d, "out.off")
        poly.write_to_file(off)
        verts, faces = read_off(off)
    write_mesh(a.output, verts, faces)


def read_off(path):
    with open(path) as f:
        words = f.read().split()
    if words[0] != "OFF":
        raise SystemExit(f"{path}: not OFF")
    nv, nf = int(words[1]), int(words[2])
    vals = words[4:]
    verts = np.array(vals[: 3 * nv], dtype=float).reshape(nv, 3)
    rest = vals[3 * nv :]
    faces, i = [], 0
    for _ in range(nf):
        k = int(rest[i])
        idx = [int(x) for x in rest[i + 1 : i + 1 + k]]
        for j in range(1, k - 1):
            faces.append([idx[0], idx[j], idx[j + 1]])
        i += 1 + k
    return verts, np.array(faces, dtype=int).reshape(-1, 3)


def cgal_normals(a, jet):
    p, _ = points_normals(a.input, False)
    ps = cgal_point_set(p)
    from CGAL import CGAL_Point_set_processing_3 as psp

    ps.add_normal_map()
    if jet:
        psp.jet_estimate_normals(ps, a.k)
    else:
        psp.pca_estimate_normals(ps, a.k)
    # MST orientation may drop points it cannot orient; they keep their unoriented normal.
    psp.mst_orient_normals(ps, a.k)
    n = np.array([[ps.normal(i).x(), ps.normal(i).y(), ps.normal(i).z()] for i in range(ps.size())])
    q = np.array([[ps.point(i).x(), ps.point(i).y(), ps.point(i).z()] for i in range(ps.size())])
    if len(q) != len(p):
        raise SystemExit(f"CGAL returned {len(q)} of {len(p)} points")
    write_cloud(a.output, q, n)


def check(_a):
    ok = True
    for m in ("open3d", "pymeshlab", "CGAL"):
        try:
            mod = __import__(m)
            print(f"{m}: {getattr(mod, '__version__', 'installed')}")
        except ImportError as e:
            ok = False
            print(f"{m}: missing ({e})")
    return 0 if ok else 3


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="peer", required=True)
    sub.add_parser("check").set_defaults(fn=check)

    def method(peer, name, fn, **opts):
        if peer not in peers:
            peers[peer] = sub.add_parser(peer).add_subparsers(dest="method", required=True)
        sp = peers[peer]
        m = sp.add_parser(name)
        m.add_argument("input")
        m.add_argument("output")
        for k, (kind, default) in opts.items():
            if kind == "list":
                m.add_argument("--" + k.replace("_", "-"), type=float, nargs="+", default=default)
            else:
                m.add_argument("--" + k.replace("_", "-"), type=kind, default=default)
        m.set_defaults(fn=fn)

    peers = {}
    method("open3d", "bpa", o3d_bpa, radii_spacing=("list", [1.25, 2.5, 5.0]))
    method("open3d", "poisson", o3d_poisson, depth=(int, 8), trim=(float, 0.0))
    method("open3d", "normals", o3d_normals, k=(int, 30))
    method("pymeshlab", "poisson", ml_poisson, depth=(int, 8))
    method("pymeshlab", "bpa", ml_bpa)
    method("cgal", "afront", cgal_afront)
    method("cgal", "jet-normals", lambda a: cgal_normals(a, True), k=(int, 18))
    method("cgal", "pca-normals", lambda a: cgal_normals(a, False), k=(int, 18))
    a = ap.parse_args()
    return a.fn(a) or 0


if __name__ == "__main__":
    sys.exit(main())
