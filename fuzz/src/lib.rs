//! The property every fuzz target checks, shared by the targets (one per format).

use reconbench_geom::io::{self, Format, Loaded};

/// Parses `data` as `format` with the in-memory reader the file readers use
/// (`io::any_from_bytes`) and panics, which libFuzzer reports as a finding, when a
/// reader breaks its contract: what is accepted must be bounded by the input (at most
/// one vertex per 3 bytes and one triangle per byte, the densest encodings), and an
/// error must be a single line without raw control characters. A panic inside the
/// reader is a finding by itself.
pub fn check(data: &[u8], format: Format) {
    match io::any_from_bytes(data, format, "fuzz-input") {
        Ok(loaded) => {
            let (v, f) = match &loaded {
                Loaded::Cloud(c) => (c.len(), 0),
                Loaded::Mesh(m) => (m.n_vertices(), m.n_faces()),
            };
            assert!(
                v <= data.len() / 3 && f <= data.len(),
                "{format}: {v} vertices and {f} faces from {} bytes",
                data.len()
            );
        }
        Err(e) => {
            let msg = e.to_string();
            assert!(
                !msg.chars().any(char::is_control),
                "{format}: raw control character in {msg:?}"
            );
        }
    }
}
