//! Property tests: random clouds survive PLY round trips bit for bit, in ascii and both
//! binary encodings, and no byte-level corruption of a PLY file makes the reader panic.

use proptest::prelude::*;
use reconbench_geom::io::{
    Format, PlyEncoding, WriteOptions, cloud_from_bytes, cloud_to_bytes, mesh_from_bytes,
    mesh_to_bytes,
};
use reconbench_geom::{Channel, DVec3, PointCloud, TriMesh};

/// Any finite f64, including subnormals, negative zero and extreme magnitudes.
fn finite() -> impl Strategy<Value = f64> {
    prop_oneof![
        any::<f64>().prop_filter("finite", |x| x.is_finite()),
        -1e3..1e3f64,
        Just(-0.0),
    ]
}

fn vec3() -> impl Strategy<Value = DVec3> {
    (finite(), finite(), finite()).prop_map(|(x, y, z)| DVec3::new(x, y, z))
}

prop_compose! {
    fn cloud()(n in 0usize..40)(
        positions in prop::collection::vec(vec3(), n),
        normals in prop::option::of(prop::collection::vec(vec3(), n)),
        colors in prop::option::of(prop::collection::vec(any::<[u8; 3]>(), n)),
        ids in prop::option::of(prop::collection::vec(any::<u32>(), n)),
        scalar in prop::option::of(prop::collection::vec(finite(), n)),
        label in prop::option::of(prop::collection::vec(any::<i32>(), n)),
    ) -> PointCloud {
        let mut c = PointCloud::new(positions).unwrap();
        c.set_normals(normals).unwrap();
        c.set_colors(colors).unwrap();
        c.set_source_ids(ids).unwrap();
        if let Some(s) = scalar {
            c.set_channel("roughness", Channel::Scalar(s)).unwrap();
        }
        if let Some(l) = label {
            c.set_channel("segment", Channel::Label(l.into_iter().map(i64::from).collect()))
                .unwrap();
        }
        c
    }
}

fn bits(c: &PointCloud) -> Vec<[u64; 3]> {
    c.positions()
        .iter()
        .chain(c.normals().unwrap_or(&[]))
        .map(|p| p.to_array().map(f64::to_bits))
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn ply_round_trip_is_exact(c in cloud(), enc in prop_oneof![
        Just(PlyEncoding::Ascii),
        Just(PlyEncoding::BinaryLittleEndian),
        Just(PlyEncoding::BinaryBigEndian),
    ]) {
        let opts = WriteOptions { ply_encoding: enc, ..WriteOptions::default() };
        let bytes = cloud_to_bytes(&c, Format::Ply, &opts).unwrap();
        let back = cloud_from_bytes(&bytes, Format::Ply, "prop.ply").unwrap();
        prop_assert_eq!(bits(&back), bits(&c));
        prop_assert_eq!(back, c);
    }

    #[test]
    fn corrupted_ply_never_panics(
        c in cloud(),
        ascii in any::<bool>(),
        edits in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..4),
        cut in any::<prop::sample::Index>(),
    ) {
        let enc = if ascii { PlyEncoding::Ascii } else { PlyEncoding::BinaryLittleEndian };
        let opts = WriteOptions { ply_encoding: enc, ..WriteOptions::default() };
        let mut bytes = cloud_to_bytes(&c, Format::Ply, &opts).unwrap();
        for (at, b) in edits {
            let i = at.index(bytes.len());
            bytes[i] = b;
        }
        let end = cut.index(bytes.len() + 1);
        // Ok or Err are both acceptable; a panic fails the test.
        let _ = cloud_from_bytes(&bytes[..end], Format::Ply, "fuzz.ply");
        let _ = cloud_from_bytes(&bytes, Format::Ply, "fuzz.ply");
    }

    #[test]
    fn corrupted_files_of_every_format_never_panic(
        format in prop::sample::select(Format::ALL.to_vec()),
        binary in any::<bool>(),
        edits in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 0..4),
        cut in any::<prop::sample::Index>(),
    ) {
        let c = PointCloud::new((0..5).map(|i| DVec3::new(i as f64, 0.5, -1.0)).collect())
            .unwrap()
            .with_normals(vec![DVec3::Z; 5])
            .unwrap();
        let m = TriMesh::new(c.positions().to_vec(), vec![[0, 1, 2], [2, 3, 4], [4, 0, 1]])
            .unwrap();
        let opts = WriteOptions {
            ply_encoding: if binary { PlyEncoding::BinaryBigEndian } else { PlyEncoding::Ascii },
            stl_binary: binary,
        };
        let mut bytes = if format.stores_faces() {
            mesh_to_bytes(&m, format, &opts).unwrap()
        } else {
            cloud_to_bytes(&c, format, &opts).unwrap()
        };
        let unedited = bytes.clone();
        for (at, b) in &edits {
            let i = at.index(bytes.len());
            bytes[i] = *b;
        }
        let end = cut.index(bytes.len() + 1);
        for data in [&bytes[..end], &bytes[..]] {
            let _ = cloud_from_bytes(data, format, "fuzz");
            let _ = mesh_from_bytes(data, format, "fuzz");
        }
        // Unedited and uncut, the file reads back.
        if format.stores_faces() {
            prop_assert_eq!(mesh_from_bytes(&unedited, format, "ok").unwrap().n_faces(), 3);
        } else {
            prop_assert_eq!(cloud_from_bytes(&unedited, format, "ok").unwrap(), c);
        }
    }
}
