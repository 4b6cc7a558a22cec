//! Reading and writing point clouds and triangle meshes: PLY, OBJ, OFF, STL, XYZ, PTS
//! (plain or Hoppe's A3d stream form, told apart by content) and Hoppe's `.m`.
//!
//! The format is chosen from the file extension (case-insensitive) or given explicitly
//! with [`Format`]. Every file function is a thin wrapper around an in-memory variant
//! ([`cloud_from_bytes`], [`mesh_to_bytes`], ...) so that parsers can be tested without
//! touching the file system.
//!
//! Parsers are hand-written and strict: malformed input (truncated data, wrong element
//! counts, non-numeric tokens, out-of-range face indices, non-finite coordinates, ...)
//! yields [`GeomError::Format`] naming the file, the line or byte offset, what was found
//! and what was expected. A file is never read partially without an error, and counts
//! declared in headers never drive an allocation larger than the file could justify:
//! files are loaded within bounds taken from the file itself (its size, a line length
//! limit, the stream limit; see [`MAX_STREAM_BYTES`], [`MAX_LINE_BYTES`],
//! [`MAX_PLY_HEADER_BYTES`]), and a count the file cannot hold is an error naming the
//! count and the bytes left. Messages escape control characters of the file
//! ([`crate::error::escape_control`]), and float colours outside 0..1 are refused, never
//! clamped.
//!
//! What each format stores:
//!
//! | format | clouds | meshes | normals | colours | source ids, channels |
//! |--------|--------|--------|---------|---------|----------------------|
//! | PLY    | yes    | yes    | yes     | yes     | yes                  |
//! | OBJ    | yes (vertex-only file) | yes | yes | yes (`v x y z r g b`) | no |
//! | OFF    | yes (vertex-only file) | yes | yes (NOFF) | yes (COFF) | no |
//! | STL    | read only (welded vertices) | yes | no | no | no |
//! | XYZ/PTS| yes    | no     | yes     | read only (PTS) | no        |
//! | M      | yes (vertex-only file) | yes | yes (`{normal=(..)}`) | no | no |
//!
//! Text formats write `f64` values with the shortest representation that parses back to
//! the same bits (at most 17 significant digits), so text round trips are exact.
//!
//! PLY headers can carry extra `comment` lines ([`write_cloud_with_comments`], read back
//! with [`read_ply_comments`]), e.g. the provenance of a generated cloud; the other
//! formats have no such place, and writing to them drops the comments.

use std::borrow::Cow;
use std::fmt;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;
use std::str::FromStr;

use glam::DVec3;

use crate::cloud::{Channel, PointCloud};
use crate::error::{GeomError, Location, Result, escape_control};
use crate::mesh::TriMesh;

pub use input::{MAX_LINE_BYTES, MAX_PLY_HEADER_BYTES, MAX_STREAM_BYTES};

mod input;
mod m;
mod obj;
mod off;
mod ply;
mod stl;
mod text;
mod xyz;

/// A supported file format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Format {
    /// Stanford PLY (ascii or binary), the only format keeping every cloud attribute.
    Ply,
    /// Wavefront OBJ (`v`, `vn`, `f`).
    Obj,
    /// Geomview OFF, with the COFF / NOFF / CNOFF variants.
    Off,
    /// STL, ascii or binary (32-bit floats).
    Stl,
    /// Plain text points: `x y z [nx ny nz]` per line.
    Xyz,
    /// Leica-style PTS: an optional count line, then `x y z [intensity] [r g b]` or
    /// `x y z nx ny nz` per line; or Hoppe's A3d stream (`p x y z`, `n nx ny nz`),
    /// recognised by its first record starting with a letter. Written in the plain form.
    Pts,
    /// Hoppe's `.m` mesh (`Vertex i x y z {normal=(..)}`, `Face j a b c`).
    M,
}

impl Format {
    /// Every format, in the order used by messages.
    pub const ALL: [Format; 7] = [
        Format::Ply,
        Format::Obj,
        Format::Off,
        Format::Stl,
        Format::Xyz,
        Format::Pts,
        Format::M,
    ];

    /// Lower-case name, which is also the file extension.
    pub fn name(self) -> &'static str {
        match self {
            Format::Ply => "ply",
            Format::Obj => "obj",
            Format::Off => "off",
            Format::Stl => "stl",
            Format::Xyz => "xyz",
            Format::Pts => "pts",
            Format::M => "m",
        }
    }

    /// True for the formats that can hold faces (PLY, OBJ, OFF, STL, M).
    pub fn stores_faces(self) -> bool {
        matches!(
            self,
            Format::Ply | Format::Obj | Format::Off | Format::Stl | Format::M
        )
    }

    /// True for the formats that can be written from a point cloud (everything but STL).
    pub fn stores_clouds(self) -> bool {
        self != Format::Stl
    }

    /// The format named by the extension of `path` (case-insensitive).
    pub fn from_path(path: impl AsRef<Path>) -> Result<Format> {
        let path = path.as_ref();
        let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
        Format::ALL
            .into_iter()
            .find(|f| f.name().eq_ignore_ascii_case(ext))
            .ok_or_else(|| GeomError::UnsupportedFormat {
                path: path.to_path_buf(),
                message: if ext.is_empty() {
                    format!(
                        "no file extension to choose a format from; expected one of {}",
                        format_list()
                    )
                } else {
                    format!(
                        "unknown file extension '.{ext}'; expected one of {}",
                        format_list()
                    )
                },
            })
    }
}

/// "ply, obj, off, stl, xyz, pts".
fn format_list() -> String {
    Format::ALL.map(Format::name).join(", ")
}

impl fmt::Display for Format {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Format {
    type Err = GeomError;

    /// Parses a format name as given to a `--format` flag (case-insensitive, an optional
    /// leading dot is accepted).
    fn from_str(s: &str) -> Result<Self> {
        let t = s.trim().trim_start_matches('.');
        Format::ALL
            .into_iter()
            .find(|f| f.name().eq_ignore_ascii_case(t))
            .ok_or_else(|| GeomError::InvalidParameter {
                name: "format",
                message: format!("unknown format '{s}'; expected one of {}", format_list()),
            })
    }
}

/// How a PLY file encodes its data.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum PlyEncoding {
    /// Human-readable text, one element per line.
    Ascii,
    /// Binary, little-endian: compact, fast and exact (the default).
    #[default]
    BinaryLittleEndian,
    /// Binary, big-endian.
    BinaryBigEndian,
}

impl PlyEncoding {
    /// The keyword of the PLY `format` header line.
    pub fn name(self) -> &'static str {
        match self {
            PlyEncoding::Ascii => "ascii",
            PlyEncoding::BinaryLittleEndian => "binary_little_endian",
            PlyEncoding::BinaryBigEndian => "binary_big_endian",
        }
    }
}

impl fmt::Display for PlyEncoding {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for PlyEncoding {
    type Err = GeomError;

    /// Accepts the header keywords and the short forms `binary` / `le` (little-endian)
    /// and `be`, case-insensitively.
    fn from_str(s: &str) -> Result<Self> {
        match s.trim().to_ascii_lowercase().as_str() {
            "ascii" => Ok(PlyEncoding::Ascii),
            "binary_little_endian" | "binary" | "le" => Ok(PlyEncoding::BinaryLittleEndian),
            "binary_big_endian" | "be" => Ok(PlyEncoding::BinaryBigEndian),
            _ => Err(GeomError::InvalidParameter {
                name: "ply encoding",
                message: format!(
                    "unknown PLY encoding '{s}'; expected ascii, binary_little_endian or \
                     binary_big_endian"
                ),
            }),
        }
    }
}

/// Choices for writing that the format alone does not fix.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct WriteOptions {
    /// Encoding of PLY output.
    pub ply_encoding: PlyEncoding,
    /// Binary (true) or ascii STL output.
    pub stl_binary: bool,
}

impl Default for WriteOptions {
    /// Binary little-endian PLY and binary STL: compact and fast.
    fn default() -> Self {
        Self {
            ply_encoding: PlyEncoding::BinaryLittleEndian,
            stl_binary: true,
        }
    }
}

// ---------------------------------------------------------------------------------------
// Public entry points.

/// Reads a point cloud, choosing the format from the extension. For a mesh file this is
/// its vertices, with vertex normals and colours when the file has them; faces are still
/// parsed and validated.
pub fn read_cloud(path: impl AsRef<Path>) -> Result<PointCloud> {
    let path = path.as_ref();
    read_cloud_as(path, Format::from_path(path)?)
}

/// Reads a point cloud in the given format, whatever the extension.
pub fn read_cloud_as(path: impl AsRef<Path>, format: Format) -> Result<PointCloud> {
    let path = path.as_ref();
    let bytes = input::read_input(path, format)?;
    cloud_from_bytes(&bytes, format, path)
}

/// Reads a triangle mesh, choosing the format from the extension. Polygons are
/// fan-triangulated; a file without faces is an error.
pub fn read_mesh(path: impl AsRef<Path>) -> Result<TriMesh> {
    let path = path.as_ref();
    read_mesh_as(path, Format::from_path(path)?)
}

/// Reads a triangle mesh in the given format, whatever the extension.
pub fn read_mesh_as(path: impl AsRef<Path>, format: Format) -> Result<TriMesh> {
    let path = path.as_ref();
    let bytes = input::read_input(path, format)?;
    mesh_from_bytes(&bytes, format, path)
}

/// Parses a point cloud from memory; `name` is the path reported in errors.
pub fn cloud_from_bytes(
    bytes: &[u8],
    format: Format,
    name: impl AsRef<Path>,
) -> Result<PointCloud> {
    let path = name.as_ref();
    parse(bytes, format, path)?.into_cloud(path)
}

/// Parses a triangle mesh from memory; `name` is the path reported in errors.
pub fn mesh_from_bytes(bytes: &[u8], format: Format, name: impl AsRef<Path>) -> Result<TriMesh> {
    let path = name.as_ref();
    if !format.stores_faces() {
        return Err(GeomError::UnsupportedFormat {
            path: path.to_path_buf(),
            message: format!(
                "format {format} stores point clouds without faces; read it as a point cloud, \
                 or use ply, obj, off or stl for meshes"
            ),
        });
    }
    parse(bytes, format, path)?.into_mesh(path)
}

/// What [`read_any`] found in a file.
#[derive(Debug, Clone, PartialEq)]
pub enum Loaded {
    /// The file has faces: a mesh, with vertex normals and colours if present.
    Mesh(TriMesh),
    /// The file has no faces (or its format cannot hold any): a point cloud with all its
    /// attributes.
    Cloud(PointCloud),
}

/// Reads whatever the file holds, choosing the format from the extension: a mesh if it
/// has at least one face, else a point cloud. For tools (`info`, `convert`) that accept
/// both.
pub fn read_any(path: impl AsRef<Path>) -> Result<Loaded> {
    let path = path.as_ref();
    read_any_as(path, Format::from_path(path)?)
}

/// [`read_any`] in the given format, whatever the extension.
pub fn read_any_as(path: impl AsRef<Path>, format: Format) -> Result<Loaded> {
    let path = path.as_ref();
    let bytes = input::read_input(path, format)?;
    any_from_bytes(&bytes, format, path)
}

/// [`read_any`] from memory; `name` is the path reported in errors.
pub fn any_from_bytes(bytes: &[u8], format: Format, name: impl AsRef<Path>) -> Result<Loaded> {
    let path = name.as_ref();
    let parsed = parse(bytes, format, path)?;
    if parsed.faces.is_empty() {
        parsed.into_cloud(path).map(Loaded::Cloud)
    } else {
        parsed.into_mesh(path).map(Loaded::Mesh)
    }
}

/// Writes a point cloud, choosing the format from the extension, with default options.
pub fn write_cloud(path: impl AsRef<Path>, cloud: &PointCloud) -> Result<()> {
    let path = path.as_ref();
    write_cloud_with(
        path,
        cloud,
        Format::from_path(path)?,
        &WriteOptions::default(),
    )
}

/// Writes a point cloud in the given format. STL cannot hold a cloud; OBJ and OFF write a
/// vertex-only file; XYZ/PTS keep positions and normals only.
pub fn write_cloud_with(
    path: impl AsRef<Path>,
    cloud: &PointCloud,
    format: Format,
    options: &WriteOptions,
) -> Result<()> {
    let path = path.as_ref();
    write_file(path, &Geometry::from_cloud(cloud), format, options)
}

/// [`write_cloud`] with extra PLY header comments: each string becomes one
/// `comment <text>` line after the writer's own comment (a string holding a line break is
/// refused). Formats other than PLY have no header comments; for them the comments are
/// not written.
pub fn write_cloud_with_comments(
    path: impl AsRef<Path>,
    cloud: &PointCloud,
    comments: &[String],
) -> Result<()> {
    let path = path.as_ref();
    let mut g = Geometry::from_cloud(cloud);
    g.comments = comments;
    write_file(path, &g, Format::from_path(path)?, &WriteOptions::default())
}

/// Writes a triangle mesh, choosing the format from the extension, with default options.
pub fn write_mesh(path: impl AsRef<Path>, mesh: &TriMesh) -> Result<()> {
    let path = path.as_ref();
    write_mesh_with(
        path,
        mesh,
        Format::from_path(path)?,
        &WriteOptions::default(),
    )
}

/// Writes a triangle mesh in the given format (PLY, OBJ, OFF or STL).
pub fn write_mesh_with(
    path: impl AsRef<Path>,
    mesh: &TriMesh,
    format: Format,
    options: &WriteOptions,
) -> Result<()> {
    let path = path.as_ref();
    write_file(path, &Geometry::from_mesh(mesh), format, options)
}

/// Encodes a point cloud in memory (see [`write_cloud_with`]).
pub fn cloud_to_bytes(
    cloud: &PointCloud,
    format: Format,
    options: &WriteOptions,
) -> Result<Vec<u8>> {
    to_bytes(&Geometry::from_cloud(cloud), format, options)
}

/// Encodes a point cloud in memory with extra PLY header comments (see
/// [`write_cloud_with_comments`]).
pub fn cloud_to_bytes_with_comments(
    cloud: &PointCloud,
    format: Format,
    options: &WriteOptions,
    comments: &[String],
) -> Result<Vec<u8>> {
    let mut g = Geometry::from_cloud(cloud);
    g.comments = comments;
    to_bytes(&g, format, options)
}

/// The `comment` lines of a PLY file's header, in order, without the keyword (and the
/// one separating space). Reads and checks the header only, not the data after it.
pub fn read_ply_comments(path: impl AsRef<Path>) -> Result<Vec<String>> {
    let path = path.as_ref();
    let header = input::read_ply_header(path)?;
    ply_comments_from_bytes(&header, path)
}

/// [`read_ply_comments`] from memory (the header, or the whole file); `name` is the path
/// reported in errors.
pub fn ply_comments_from_bytes(bytes: &[u8], name: impl AsRef<Path>) -> Result<Vec<String>> {
    let path = name.as_ref();
    if bytes.is_empty() {
        return Err(format_err(
            path,
            Location::File,
            "the file is empty; expected ply data",
        ));
    }
    ply::header_comments(bytes, path)
}

/// Content hash of a file's bytes: FNV-1a 64, as 16 hex digits. Used to tie a generated
/// cloud to the mesh it came from (and cell keys to their data files).
pub fn content_hash(bytes: &[u8]) -> String {
    format!("{:016x}", fnv1a64(bytes))
}

/// FNV-1a, 64 bit: a hash that does not depend on the platform or the Rust release.
pub fn fnv1a64(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

/// Encodes a triangle mesh in memory (see [`write_mesh_with`]).
pub fn mesh_to_bytes(mesh: &TriMesh, format: Format, options: &WriteOptions) -> Result<Vec<u8>> {
    to_bytes(&Geometry::from_mesh(mesh), format, options)
}

// ---------------------------------------------------------------------------------------
// Shared plumbing.

/// Placeholder path for errors of in-memory encoding.
const MEMORY: &str = "<memory>";

/// A [`GeomError::Format`] for `path`. The message is stored with control characters
/// escaped ([`escape_control`]): messages quote file content, which may be hostile.
pub(crate) fn format_err(path: &Path, location: Location, message: impl Into<String>) -> GeomError {
    let message = message.into();
    GeomError::Format {
        path: path.to_path_buf(),
        location,
        message: match escape_control(&message) {
            Cow::Borrowed(_) => message,
            Cow::Owned(escaped) => escaped,
        },
    }
}

fn io_err(path: &Path) -> impl Fn(std::io::Error) -> GeomError + '_ {
    move |source| GeomError::Io {
        path: path.to_path_buf(),
        source,
    }
}

fn parse(bytes: &[u8], format: Format, path: &Path) -> Result<Parsed> {
    if bytes.is_empty() {
        return Err(format_err(
            path,
            Location::File,
            format!("the file is empty; expected {format} data"),
        ));
    }
    match format {
        Format::Ply => ply::parse(bytes, path),
        Format::Obj => obj::parse(bytes, path),
        Format::Off => off::parse(bytes, path),
        Format::Stl => stl::parse(bytes, path),
        Format::Xyz => xyz::parse(bytes, path, false),
        Format::Pts => xyz::parse(bytes, path, true),
        Format::M => m::parse(bytes, path),
    }
}

/// Everything a parser extracts from a file, before it becomes a cloud or a mesh.
/// Parsers guarantee finite positions and normals and in-range face indices.
#[derive(Debug, Default)]
pub(crate) struct Parsed {
    pub positions: Vec<DVec3>,
    pub normals: Option<Vec<DVec3>>,
    pub colors: Option<Vec<[u8; 3]>>,
    pub source_ids: Option<Vec<u32>>,
    pub channels: Vec<(String, Channel)>,
    pub faces: Vec<[u32; 3]>,
}

impl Parsed {
    fn into_cloud(self, path: &Path) -> Result<PointCloud> {
        let wrap = wrap_err(path);
        let mut cloud = PointCloud::new(self.positions).map_err(&wrap)?;
        cloud.set_normals(self.normals).map_err(&wrap)?;
        cloud.set_colors(self.colors).map_err(&wrap)?;
        cloud.set_source_ids(self.source_ids).map_err(&wrap)?;
        for (name, ch) in self.channels {
            cloud.set_channel(name, ch).map_err(&wrap)?;
        }
        Ok(cloud)
    }

    fn into_mesh(self, path: &Path) -> Result<TriMesh> {
        if self.faces.is_empty() {
            return Err(format_err(
                path,
                Location::File,
                format!(
                    "found {} vertices but no faces; a mesh needs at least one face \
                     (read the file as a point cloud instead)",
                    self.positions.len()
                ),
            ));
        }
        let wrap = wrap_err(path);
        let mut mesh = TriMesh::new(self.positions, self.faces).map_err(&wrap)?;
        mesh.set_vertex_normals(self.normals).map_err(&wrap)?;
        mesh.set_vertex_colors(self.colors).map_err(&wrap)?;
        Ok(mesh)
    }
}

/// Turns a validation error of the core types into a format error naming the file.
fn wrap_err(path: &Path) -> impl Fn(GeomError) -> GeomError + '_ {
    move |e| match e {
        e @ GeomError::Format { .. } => e,
        other => format_err(path, Location::File, other.to_string()),
    }
}

/// A borrowed view of what is to be written, common to clouds and meshes.
#[derive(Debug)]
pub(crate) struct Geometry<'a> {
    pub positions: &'a [DVec3],
    pub normals: Option<&'a [DVec3]>,
    pub colors: Option<&'a [[u8; 3]]>,
    pub source_ids: Option<&'a [u32]>,
    pub channels: Vec<(&'a str, &'a Channel)>,
    /// `None` for a point cloud.
    pub faces: Option<&'a [[u32; 3]]>,
    /// Extra header comment lines (PLY only).
    pub comments: &'a [String],
}

impl<'a> Geometry<'a> {
    fn from_cloud(c: &'a PointCloud) -> Self {
        Self {
            positions: c.positions(),
            normals: c.normals(),
            colors: c.colors(),
            source_ids: c.source_ids(),
            channels: c.channels().iter().map(|(k, v)| (k.as_str(), v)).collect(),
            faces: None,
            comments: &[],
        }
    }

    fn from_mesh(m: &'a TriMesh) -> Self {
        Self {
            positions: m.vertices(),
            normals: m.vertex_normals(),
            colors: m.vertex_colors(),
            source_ids: None,
            channels: Vec::new(),
            faces: Some(m.faces()),
            comments: &[],
        }
    }

    fn what(&self) -> &'static str {
        if self.faces.is_some() {
            "mesh"
        } else {
            "point cloud"
        }
    }
}

/// Refuses combinations the format cannot represent, before anything is written.
fn check_writable(g: &Geometry, format: Format, options: &WriteOptions, path: &Path) -> Result<()> {
    let unsupported = |message: String| GeomError::UnsupportedFormat {
        path: path.to_path_buf(),
        message,
    };
    if g.faces.is_none() && !format.stores_clouds() {
        return Err(unsupported(format!(
            "format {format} stores meshes; use ply or xyz for a point cloud"
        )));
    }
    if g.faces.is_some() && !format.stores_faces() {
        return Err(unsupported(format!(
            "format {format} stores point clouds; use ply, obj, off or stl for a mesh"
        )));
    }
    match format {
        Format::Ply => ply::check_writable(g, path),
        Format::Stl => stl::check_writable(g, options.stl_binary, path),
        _ => Ok(()),
    }
}

fn encode(
    w: &mut dyn Write,
    g: &Geometry,
    format: Format,
    options: &WriteOptions,
) -> std::io::Result<()> {
    match format {
        Format::Ply => ply::write(w, g, options.ply_encoding),
        Format::Obj => obj::write(w, g),
        Format::Off => off::write(w, g),
        Format::Stl => stl::write(w, g, options.stl_binary),
        Format::Xyz => xyz::write(w, g, false),
        Format::Pts => xyz::write(w, g, true),
        Format::M => m::write(w, g),
    }
}

fn to_bytes(g: &Geometry, format: Format, options: &WriteOptions) -> Result<Vec<u8>> {
    let path = Path::new(MEMORY);
    check_writable(g, format, options, path)?;
    let mut out = Vec::new();
    encode(&mut out, g, format, options).map_err(io_err(path))?;
    Ok(out)
}

fn write_file(path: &Path, g: &Geometry, format: Format, options: &WriteOptions) -> Result<()> {
    // Validate first so that a refused write leaves no partial file behind.
    check_writable(g, format, options, path)?;
    let file = File::create(path).map_err(io_err(path))?;
    let mut w = BufWriter::with_capacity(1 << 20, file);
    encode(&mut w, g, format, options).map_err(io_err(path))?;
    w.flush().map_err(io_err(path))?;
    Ok(())
}
