//! Stanford PLY: ascii, binary little-endian and binary big-endian.
//!
//! Reading understands the `vertex` element (`x y z`, `nx ny nz`, `red green blue` as
//! uchar or as floats in 0..1, `source_id`, and any other scalar property as a channel:
//! float types become [`Channel::Scalar`], integer types [`Channel::Label`]) and the `face`
//! element (`vertex_indices` or `vertex_index` lists, any integer count and index types,
//! polygons fan-triangulated). Every other element (`edge`, `material`, ...) and every
//! other face property is parsed and skipped, so that the data after it stays aligned.
//!
//! The decoding logic is written once, generic over a [`Source`] of values: the ascii
//! source reads one record per line (so wrong counts are caught at the first misaligned
//! line), the binary source reads from a byte slice with explicit bounds checks.
//!
//! Writing uses `double` coordinates and normals, `uchar` colours, `uint source_id`,
//! `double`/`int` channels and `list uchar int vertex_indices`.

use std::io::{self, Write};
use std::path::Path;

use glam::DVec3;

use super::text::{Lines, Num, line_str, show};
use super::{Geometry, Parsed, PlyEncoding, format_err};
use crate::cloud::Channel;
use crate::error::{GeomError, Location, Result};

// ---------------------------------------------------------------------------------------
// Header.

/// A PLY scalar type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Ty {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Ty {
    fn parse(s: &str) -> Option<Ty> {
        Some(match s {
            "char" | "int8" => Ty::I8,
            "uchar" | "uint8" => Ty::U8,
            "short" | "int16" => Ty::I16,
            "ushort" | "uint16" => Ty::U16,
            "int" | "int32" => Ty::I32,
            "uint" | "uint32" => Ty::U32,
            "float" | "float32" => Ty::F32,
            "double" | "float64" => Ty::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Ty::I8 | Ty::U8 => 1,
            Ty::I16 | Ty::U16 => 2,
            Ty::I32 | Ty::U32 | Ty::F32 => 4,
            Ty::F64 => 8,
        }
    }

    fn is_float(self) -> bool {
        matches!(self, Ty::F32 | Ty::F64)
    }

    fn name(self) -> &'static str {
        match self {
            Ty::I8 => "char",
            Ty::U8 => "uchar",
            Ty::I16 => "short",
            Ty::U16 => "ushort",
            Ty::I32 => "int",
            Ty::U32 => "uint",
            Ty::F32 => "float",
            Ty::F64 => "double",
        }
    }

    /// Value range of an integer type.
    fn int_range(self) -> (i64, i64) {
        match self {
            Ty::I8 => (i8::MIN.into(), i8::MAX.into()),
            Ty::U8 => (0, u8::MAX.into()),
            Ty::I16 => (i16::MIN.into(), i16::MAX.into()),
            Ty::U16 => (0, u16::MAX.into()),
            Ty::I32 => (i32::MIN.into(), i32::MAX.into()),
            Ty::U32 => (0, u32::MAX.into()),
            Ty::F32 | Ty::F64 => (i64::MIN, i64::MAX),
        }
    }
}

const TYPE_NAMES: &str = "char, uchar, short, ushort, int, uint, float, double \
                          (or int8, uint8, int16, uint16, int32, uint32, float32, float64)";

#[derive(Debug, Clone, Copy)]
enum Kind {
    Scalar(Ty),
    List { count: Ty, item: Ty },
}

#[derive(Debug)]
struct Property {
    name: String,
    kind: Kind,
    line: usize,
}

#[derive(Debug)]
struct Element {
    name: String,
    count: usize,
    props: Vec<Property>,
    line: usize,
}

impl Element {
    /// Smallest possible binary record size (lists counted as empty).
    fn min_binary_size(&self) -> usize {
        self.props
            .iter()
            .map(|p| match p.kind {
                Kind::Scalar(t) => t.size(),
                Kind::List { count, .. } => count.size(),
            })
            .sum()
    }

    /// Binary record size when there are no lists.
    fn fixed_binary_size(&self) -> Option<usize> {
        self.props
            .iter()
            .all(|p| matches!(p.kind, Kind::Scalar(_)))
            .then(|| self.min_binary_size())
    }

    fn prop(&self, name: &str) -> Option<(usize, &Property)> {
        self.props.iter().enumerate().find(|(_, p)| p.name == name)
    }
}

#[derive(Debug)]
struct Header {
    encoding: PlyEncoding,
    elements: Vec<Element>,
    /// Byte offset of the body.
    body: usize,
    /// Number of header lines (the body's first line is `lines + 1`).
    lines: usize,
    /// Text of the `comment` lines, in order.
    comments: Vec<String>,
}

fn is_keyword_line(bytes: &[u8], kw: &[u8]) -> bool {
    bytes.starts_with(kw) && bytes.get(kw.len()).is_none_or(|b| b.is_ascii_whitespace())
}

fn parse_header(bytes: &[u8], path: &Path) -> Result<Header> {
    let err = |line: usize, msg: String| format_err(path, Location::Line(line), msg);
    let mut lines = Lines::new(bytes);
    match lines.next() {
        Some((_, l)) if l.trim_ascii() == b"ply" => {}
        Some((n, l)) => {
            let found = String::from_utf8_lossy(&l[..l.len().min(32)]).into_owned();
            return Err(err(
                n,
                format!(
                    "found {} where a PLY file starts with the line 'ply'",
                    show(&found)
                ),
            ));
        }
        None => return Err(err(1, "expected the line 'ply'".into())),
    }
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut comments = Vec::new();
    loop {
        let Some((n, raw)) = lines.next() else {
            return Err(err(
                lines.line_number(),
                "the header ends without an 'end_header' line".into(),
            ));
        };
        // Comments may hold anything, including non-UTF-8 bytes: keep them unchecked.
        if is_keyword_line(raw, b"comment") {
            let text = &raw[b"comment".len()..];
            let text = text.strip_prefix(b" ").unwrap_or(text);
            comments.push(String::from_utf8_lossy(text).into_owned());
            continue;
        }
        if is_keyword_line(raw, b"obj_info") {
            continue;
        }
        let line = line_str(path, n, raw)?;
        let toks: Vec<&str> = line.split_ascii_whitespace().collect();
        match toks.as_slice() {
            [] => {}
            ["end_header"] => break,
            ["format", enc, version] => {
                if encoding.is_some() {
                    return Err(err(n, "found a second 'format' line".into()));
                }
                encoding = Some(match *enc {
                    "ascii" => PlyEncoding::Ascii,
                    "binary_little_endian" => PlyEncoding::BinaryLittleEndian,
                    "binary_big_endian" => PlyEncoding::BinaryBigEndian,
                    other => {
                        return Err(err(
                            n,
                            format!(
                                "unknown PLY encoding {}; expected ascii, \
                                 binary_little_endian or binary_big_endian",
                                show(other)
                            ),
                        ));
                    }
                });
                if !matches!(*version, "1.0" | "1") {
                    return Err(err(
                        n,
                        format!("unsupported PLY version {}; expected 1.0", show(version)),
                    ));
                }
            }
            ["element", name, count] => {
                let count = count.parse::<usize>().map_err(|_| {
                    err(
                        n,
                        format!(
                            "element '{name}' has count {}; expected a non-negative integer",
                            show(count)
                        ),
                    )
                })?;
                if elements.iter().any(|e| e.name == *name) {
                    return Err(err(n, format!("element '{name}' is declared twice")));
                }
                elements.push(Element {
                    name: (*name).to_string(),
                    count,
                    props: Vec::new(),
                    line: n,
                });
            }
            ["property", rest @ ..] => {
                let Some(el) = elements.last_mut() else {
                    return Err(err(n, "found a property before any 'element' line".into()));
                };
                let ty = |s: &str| {
                    Ty::parse(s).ok_or_else(|| {
                        err(
                            n,
                            format!(
                                "unknown property type {}; expected one of {TYPE_NAMES}",
                                show(s)
                            ),
                        )
                    })
                };
                let (name, kind) = match rest {
                    ["list", count, item, name] => {
                        let count = ty(count)?;
                        if count.is_float() {
                            return Err(err(
                                n,
                                format!(
                                    "list '{name}' has count type {}; expected an integer type",
                                    count.name()
                                ),
                            ));
                        }
                        (
                            name,
                            Kind::List {
                                count,
                                item: ty(item)?,
                            },
                        )
                    }
                    [t, name] if *t != "list" => (name, Kind::Scalar(ty(t)?)),
                    _ => {
                        return Err(err(
                            n,
                            format!(
                                "malformed property line {}; expected 'property <type> <name>' \
                                 or 'property list <count type> <item type> <name>'",
                                show(line.trim())
                            ),
                        ));
                    }
                };
                if el.props.iter().any(|p| p.name == **name) {
                    return Err(err(
                        n,
                        format!(
                            "property '{name}' is declared twice in element '{}'",
                            el.name
                        ),
                    ));
                }
                el.props.push(Property {
                    name: (*name).to_string(),
                    kind,
                    line: n,
                });
            }
            [kw, ..] => {
                return Err(err(
                    n,
                    format!(
                        "unexpected header line starting with {}; expected format, element, \
                         property, comment, obj_info or end_header",
                        show(kw)
                    ),
                ));
            }
        }
    }
    let end_line = lines.line_number();
    let encoding = encoding.ok_or_else(|| {
        err(
            end_line,
            "the header has no 'format' line; expected e.g. 'format binary_little_endian 1.0'"
                .into(),
        )
    })?;
    if let Some(e) = elements.iter().find(|e| e.count > 0 && e.props.is_empty()) {
        return Err(err(
            e.line,
            format!(
                "element '{}' has {} records but no properties",
                e.name, e.count
            ),
        ));
    }
    Ok(Header {
        encoding,
        elements,
        body: lines.offset(),
        lines: end_line,
        comments,
    })
}

/// The header's comment lines (the data after the header is not read).
pub(crate) fn header_comments(bytes: &[u8], path: &Path) -> Result<Vec<String>> {
    parse_header(bytes, path).map(|h| h.comments)
}

/// How far a buffer holds a PLY header.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum HeaderEnd {
    /// The header ends with its `end_header` line; the body starts at this offset.
    Found(usize),
    /// The first line is not `ply`: no point reading further.
    NotPly,
    /// No `end_header` line yet.
    Incomplete,
}

/// Finds the end of the header in the start of a PLY file (only lines ended by a line
/// break count, since more bytes may follow).
pub(crate) fn header_end(bytes: &[u8]) -> HeaderEnd {
    let first = bytes.trim_ascii_start();
    if first.len() >= 3 && !first.starts_with(b"ply") {
        return HeaderEnd::NotPly;
    }
    let mut start = 0;
    while let Some(i) = bytes[start..].iter().position(|&b| b == b'\n') {
        let line = bytes[start..start + i].trim_ascii();
        let next = start + i + 1;
        if start == 0 && line != b"ply" {
            return HeaderEnd::NotPly;
        }
        if line == b"end_header" {
            return HeaderEnd::Found(next);
        }
        start = next;
    }
    HeaderEnd::Incomplete
}

/// What a binary body must hold, from the header alone.
#[derive(Debug)]
pub(crate) struct BodyNeeds {
    /// Per element: name, record count, smallest record size in bytes.
    elements: Vec<(String, usize, usize)>,
    /// Every record has a fixed size (no lists): the body size is known exactly.
    pub exact: bool,
    /// Byte offset of the body.
    body: usize,
}

impl BodyNeeds {
    /// Fewest bytes the body can have.
    pub fn min_bytes(&self) -> u64 {
        let total: u128 = self
            .elements
            .iter()
            .map(|&(_, count, min)| count as u128 * min as u128)
            .sum();
        u64::try_from(total).unwrap_or(u64::MAX)
    }

    /// Refuses a header whose counts need more than the `avail` bytes after the header
    /// (the rest of a regular file, or what the stream limit leaves), naming the first
    /// element that does not fit, its count and the bytes left for it.
    pub fn check(&self, avail: u64, stream: bool, path: &Path) -> Result<()> {
        let mut used: u128 = 0;
        for (name, count, min) in &self.elements {
            let need = *count as u128 * *min as u128;
            if used + need > avail as u128 {
                let left = avail as u128 - used;
                let before = if used > 0 {
                    " and the elements before it"
                } else {
                    ""
                };
                let place = if stream {
                    format!(
                        "within the {} bytes read from a stream (not a regular file)",
                        super::MAX_STREAM_BYTES
                    )
                } else {
                    "in the file".to_string()
                };
                return Err(format_err(
                    path,
                    Location::Byte(self.body as u64 + used as u64),
                    format!(
                        "element '{name}' declares {count} records of {}{min} bytes \
                         ({need} bytes), but only {left} bytes remain after the header{before} \
                         {place}; the file is truncated or the count is wrong",
                        if self.exact { "" } else { "at least " },
                    ),
                ));
            }
            used += need;
        }
        Ok(())
    }

    /// For a body of fixed-size records, refuses bytes after the last record before the
    /// body is parsed (`avail` bytes follow the header; of a stream, only the first byte
    /// after the records is read, so the message says "at least").
    pub fn check_no_trailing(&self, avail: u64, stream: bool, path: &Path) -> Result<()> {
        let need = self.min_bytes();
        if avail > need {
            let last = self.elements.last().map_or("(none)", |e| e.0.as_str());
            let extra = if stream {
                format!("at least {}", avail - need)
            } else {
                (avail - need).to_string()
            };
            return Err(format_err(
                path,
                Location::Byte(self.body as u64 + need),
                format!(
                    "found {extra} bytes after the last record of element '{last}'; expected \
                     the end of the file (the header's element counts may be too small)"
                ),
            ));
        }
        Ok(())
    }
}

/// Parses a complete header and returns what its binary body must hold; `None` for an
/// ascii body.
pub(crate) fn body_needs(header: &[u8], path: &Path) -> Result<Option<BodyNeeds>> {
    let h = parse_header(header, path)?;
    if h.encoding == PlyEncoding::Ascii {
        return Ok(None);
    }
    Ok(Some(BodyNeeds {
        body: h.body,
        exact: h.elements.iter().all(|e| e.fixed_binary_size().is_some()),
        elements: h
            .elements
            .into_iter()
            .map(|e| {
                let min = e.min_binary_size();
                (e.name, e.count, min)
            })
            .collect(),
    }))
}

// ---------------------------------------------------------------------------------------
// Value sources.

/// A decoded scalar.
#[derive(Debug, Clone, Copy)]
enum Val {
    F(f64),
    I(i64),
}

impl Val {
    fn as_f64(self) -> f64 {
        match self {
            Val::F(v) => v,
            Val::I(v) => v as f64,
        }
    }
}

/// Where the records come from: the ascii and binary bodies.
trait Source {
    /// Starts record `rec` of `el`.
    fn begin(&mut self, el: &Element, rec: usize) -> Result<()>;
    /// Reads the next value, of type `ty`, for property `prop`.
    fn value(&mut self, ty: Ty, el: &Element, rec: usize, prop: &str) -> Result<Val>;
    /// Ends a record (the ascii source checks that the line is used up).
    fn end(&mut self, el: &Element, rec: usize) -> Result<()>;
    /// Location of the current record, for errors found after decoding it.
    fn loc(&self) -> Location;
    /// Prepares reading `el`: checks what can be checked up front and returns a safe
    /// capacity for its records (bounded by the bytes left, whatever the header says).
    fn start_element(&mut self, el: &Element) -> Result<usize>;
    /// Skips every record of `el` at once if it can (fixed-size binary records).
    fn skip_element(&mut self, el: &Element) -> Result<bool>;
    /// Checks that nothing follows the last element.
    fn finish(&mut self, last: Option<&Element>) -> Result<()>;
}

struct AsciiSource<'a> {
    path: &'a Path,
    lines: Lines<'a>,
    tokens: std::str::SplitAsciiWhitespace<'a>,
    line: usize,
    used: usize,
}

impl AsciiSource<'_> {
    fn err(&self, msg: String) -> GeomError {
        format_err(self.path, Location::Line(self.line), msg)
    }
}

impl Source for AsciiSource<'_> {
    fn begin(&mut self, el: &Element, rec: usize) -> Result<()> {
        match self.lines.next_nonblank(self.path)? {
            Some((n, s)) => {
                self.line = n;
                self.tokens = s.split_ascii_whitespace();
                self.used = 0;
                Ok(())
            }
            None => {
                self.line = self.lines.line_number().max(1);
                Err(self.err(format!(
                    "the file ends after {rec} of the {} '{}' records declared in the header",
                    el.count, el.name
                )))
            }
        }
    }

    fn value(&mut self, ty: Ty, el: &Element, rec: usize, prop: &str) -> Result<Val> {
        let Some(tok) = self.tokens.next() else {
            return Err(self.err(format!(
                "{} {rec}: the line ends after {} values, before property '{prop}'; \
                 expected one record per line with all properties of element '{}'",
                el.name, self.used, el.name
            )));
        };
        self.used += 1;
        if ty.is_float() {
            tok.parse::<f64>().map(Val::F).map_err(|_| {
                self.err(format!(
                    "{} {rec}: property '{prop}' ({}) is {}; expected a number",
                    el.name,
                    ty.name(),
                    show(tok)
                ))
            })
        } else {
            let v = tok.parse::<i64>().map_err(|_| {
                self.err(format!(
                    "{} {rec}: property '{prop}' ({}) is {}; expected an integer",
                    el.name,
                    ty.name(),
                    show(tok)
                ))
            })?;
            let (lo, hi) = ty.int_range();
            if v < lo || v > hi {
                return Err(self.err(format!(
                    "{} {rec}: property '{prop}' is {v}, out of the range {lo}..={hi} of type {}",
                    el.name,
                    ty.name()
                )));
            }
            Ok(Val::I(v))
        }
    }

    fn end(&mut self, el: &Element, rec: usize) -> Result<()> {
        let extra = self.tokens.clone().count();
        if extra > 0 {
            return Err(self.err(format!(
                "{} {rec} has {} values on its line but its properties take {}; \
                 the header's element counts or properties may be wrong",
                el.name,
                self.used + extra,
                self.used
            )));
        }
        Ok(())
    }

    fn loc(&self) -> Location {
        Location::Line(self.line)
    }

    fn start_element(&mut self, el: &Element) -> Result<usize> {
        // Every record is a line with at least one character and a separator per
        // property (the last line may lack its line break).
        let left = self.lines.remaining();
        let per = 2 * el.props.len().max(1);
        let need = (el.count as u128 * per as u128).saturating_sub(1);
        if need > left as u128 {
            self.line = self.lines.line_number() + 1;
            return Err(self.err(format!(
                "element '{}' declares {} records of {} properties, at least {need} bytes \
                 as ascii, but only {left} bytes remain; the file is truncated or the count \
                 is wrong",
                el.name,
                el.count,
                el.props.len()
            )));
        }
        Ok(el.count.min(left / per + 1))
    }

    fn skip_element(&mut self, _el: &Element) -> Result<bool> {
        Ok(false)
    }

    fn finish(&mut self, last: Option<&Element>) -> Result<()> {
        if let Some((n, s)) = self.lines.next_nonblank(self.path)? {
            self.line = n;
            return Err(self.err(format!(
                "found {} after the last record of element '{}'; the header's element \
                 counts may be too small",
                show(s.trim()),
                last.map_or("(none)", |e| e.name.as_str())
            )));
        }
        Ok(())
    }
}

struct BinarySource<'a> {
    path: &'a Path,
    data: &'a [u8],
    pos: usize,
    record_start: usize,
    big: bool,
}

impl BinarySource<'_> {
    fn err(&self, at: usize, msg: String) -> GeomError {
        format_err(self.path, Location::Byte(at as u64), msg)
    }

    fn left(&self) -> usize {
        self.data.len() - self.pos
    }

    /// The error for a value that runs past the end of the data (kept out of the hot
    /// path of [`Source::value`]).
    #[cold]
    #[inline(never)]
    fn truncated(&self, ty: Ty, el: &Element, rec: usize, prop: &str) -> GeomError {
        self.err(
            self.pos,
            format!(
                "the file ends inside {} {rec} of {} (property '{prop}' needs {} bytes, \
                 {} remain); the file is truncated or the header counts are wrong",
                el.name,
                el.count,
                ty.size(),
                self.left()
            ),
        )
    }
}

/// Copies the first `N` bytes of `b` (callers guarantee the length).
fn arr<const N: usize>(b: &[u8]) -> [u8; N] {
    let mut a = [0u8; N];
    a.copy_from_slice(&b[..N]);
    a
}

fn decode(ty: Ty, b: &[u8], big: bool) -> Val {
    macro_rules! rd {
        ($t:ty, $n:expr) => {{
            let a = arr::<$n>(b);
            if big {
                <$t>::from_be_bytes(a)
            } else {
                <$t>::from_le_bytes(a)
            }
        }};
    }
    match ty {
        Ty::I8 => Val::I(i64::from(b[0] as i8)),
        Ty::U8 => Val::I(i64::from(b[0])),
        Ty::I16 => Val::I(i64::from(rd!(i16, 2))),
        Ty::U16 => Val::I(i64::from(rd!(u16, 2))),
        Ty::I32 => Val::I(i64::from(rd!(i32, 4))),
        Ty::U32 => Val::I(i64::from(rd!(u32, 4))),
        Ty::F32 => Val::F(f64::from(rd!(f32, 4))),
        Ty::F64 => Val::F(rd!(f64, 8)),
    }
}

impl Source for BinarySource<'_> {
    fn begin(&mut self, _el: &Element, _rec: usize) -> Result<()> {
        self.record_start = self.pos;
        Ok(())
    }

    #[inline]
    fn value(&mut self, ty: Ty, el: &Element, rec: usize, prop: &str) -> Result<Val> {
        let size = ty.size();
        match self.data.get(self.pos..self.pos + size) {
            Some(b) => {
                self.pos += size;
                Ok(decode(ty, b, self.big))
            }
            None => Err(self.truncated(ty, el, rec, prop)),
        }
    }

    fn end(&mut self, _el: &Element, _rec: usize) -> Result<()> {
        Ok(())
    }

    fn loc(&self) -> Location {
        Location::Byte(self.record_start as u64)
    }

    fn start_element(&mut self, el: &Element) -> Result<usize> {
        let min = el.min_binary_size();
        let need = (el.count as u128) * (min as u128);
        if need > self.left() as u128 {
            return Err(self.err(
                self.pos,
                format!(
                    "element '{}' declares {} records of {}{min} bytes ({need} bytes), \
                     but only {} bytes remain; the file is truncated or the count is wrong",
                    el.name,
                    el.count,
                    if el.fixed_binary_size().is_some() {
                        ""
                    } else {
                        "at least "
                    },
                    self.left()
                ),
            ));
        }
        Ok(el.count.min(self.left() / min.max(1)))
    }

    fn skip_element(&mut self, el: &Element) -> Result<bool> {
        match el.fixed_binary_size() {
            // `start_element` checked that the bytes are there.
            Some(size) => {
                self.pos += el.count * size;
                Ok(true)
            }
            None => Ok(false),
        }
    }

    fn finish(&mut self, last: Option<&Element>) -> Result<()> {
        if self.pos != self.data.len() {
            return Err(self.err(
                self.pos,
                format!(
                    "found {} bytes after the last record of element '{}'; expected the end \
                     of the file (the header's element counts may be too small)",
                    self.left(),
                    last.map_or("(none)", |e| e.name.as_str())
                ),
            ));
        }
        Ok(())
    }
}

// ---------------------------------------------------------------------------------------
// Decoding.

/// What a vertex property feeds.
#[derive(Debug, Clone, Copy)]
enum VDest {
    Pos(usize),
    Normal(usize),
    Color(usize),
    SourceId,
    Channel(usize),
    Skip,
}

/// A channel being filled.
enum ChanBuf {
    Scalar(Vec<f64>),
    Label(Vec<i64>),
}

/// Names the reader interprets; channels with these names cannot be written.
const RESERVED: [&str; 13] = [
    "x",
    "y",
    "z",
    "nx",
    "ny",
    "nz",
    "red",
    "green",
    "blue",
    "diffuse_red",
    "diffuse_green",
    "diffuse_blue",
    "source_id",
];

fn header_err(path: &Path, line: usize, msg: String) -> GeomError {
    format_err(path, Location::Line(line), msg)
}

/// Where each vertex property goes, and which optional attributes the file has.
struct VertexLayout {
    dests: Vec<VDest>,
    /// Channel names, and whether each is a float (scalar) channel.
    channels: Vec<(String, bool)>,
    normals: bool,
    colors: bool,
}

/// Maps each vertex property to its destination.
fn vertex_layout(el: &Element, path: &Path) -> Result<VertexLayout> {
    let mut dests = vec![VDest::Skip; el.props.len()];
    let scalar = |name: &str| -> Result<Option<usize>> {
        match el.prop(name) {
            Some((i, p)) => match p.kind {
                Kind::Scalar(_) => Ok(Some(i)),
                Kind::List { .. } => Err(header_err(
                    path,
                    p.line,
                    format!("vertex property '{name}' is a list; expected a scalar"),
                )),
            },
            None => Ok(None),
        }
    };
    for (k, axis) in ["x", "y", "z"].into_iter().enumerate() {
        let i = scalar(axis)?.ok_or_else(|| {
            header_err(
                path,
                el.line,
                format!("the vertex element has no '{axis}' property; expected x, y and z"),
            )
        })?;
        dests[i] = VDest::Pos(k);
    }
    let triple = |names: [&str; 3]| -> Result<Option<[usize; 3]>> {
        let found = [scalar(names[0])?, scalar(names[1])?, scalar(names[2])?];
        Ok(match found {
            [Some(a), Some(b), Some(c)] => Some([a, b, c]),
            _ => None,
        })
    };
    let normals = triple(["nx", "ny", "nz"])?;
    if let Some(idx) = normals {
        for (k, i) in idx.into_iter().enumerate() {
            dests[i] = VDest::Normal(k);
        }
    }
    let colors = match triple(["red", "green", "blue"])? {
        Some(c) => Some(c),
        None => triple(["diffuse_red", "diffuse_green", "diffuse_blue"])?,
    };
    if let Some(idx) = colors {
        for (k, i) in idx.into_iter().enumerate() {
            dests[i] = VDest::Color(k);
        }
    }
    if let Some(i) = scalar("source_id")? {
        dests[i] = VDest::SourceId;
    }
    let mut channels = Vec::new();
    for (i, p) in el.props.iter().enumerate() {
        if let (VDest::Skip, Kind::Scalar(t)) = (dests[i], p.kind) {
            dests[i] = VDest::Channel(channels.len());
            channels.push((p.name.clone(), t.is_float()));
        }
    }
    Ok(VertexLayout {
        dests,
        channels,
        normals: normals.is_some(),
        colors: colors.is_some(),
    })
}

/// Reads a list length (an integer that must not be negative).
fn list_len<S: Source>(
    src: &mut S,
    count: Ty,
    el: &Element,
    rec: usize,
    prop: &str,
    path: &Path,
) -> Result<usize> {
    match src.value(count, el, rec, prop)? {
        Val::I(n) if n >= 0 => Ok(n as usize),
        v => Err(format_err(
            path,
            src.loc(),
            format!(
                "{} {rec}: list '{prop}' has length {}; expected a non-negative count",
                el.name,
                v.as_f64()
            ),
        )),
    }
}

/// Reads and discards one property value (scalar or list).
fn skip_prop<S: Source>(
    src: &mut S,
    p: &Property,
    el: &Element,
    rec: usize,
    path: &Path,
) -> Result<()> {
    match p.kind {
        Kind::Scalar(t) => {
            src.value(t, el, rec, &p.name)?;
        }
        Kind::List { count, item } => {
            let n = list_len(src, count, el, rec, &p.name, path)?;
            for _ in 0..n {
                src.value(item, el, rec, &p.name)?;
            }
        }
    }
    Ok(())
}

fn skip_element<S: Source>(src: &mut S, el: &Element, path: &Path) -> Result<()> {
    src.start_element(el)?;
    if src.skip_element(el)? {
        return Ok(());
    }
    for rec in 0..el.count {
        src.begin(el, rec)?;
        for p in &el.props {
            skip_prop(src, p, el, rec, path)?;
        }
        src.end(el, rec)?;
    }
    Ok(())
}

fn to_color(v: Val, ty: Ty) -> std::result::Result<u8, String> {
    match (v, ty) {
        (Val::F(f), _) if f.is_finite() => super::text::unit_to_u8(f),
        (Val::F(f), _) => Err(format!("colour component {f} is not finite")),
        // 16-bit colours are scaled down; other integer types must already be 0..=255.
        (Val::I(i), Ty::U16) => Ok(((i as f64) / 257.0).round() as u8),
        (Val::I(i), _) => u8::try_from(i)
            .map_err(|_| format!("colour component {i} is out of range; expected 0..=255")),
    }
}

fn to_source_id(v: Val) -> std::result::Result<u32, String> {
    let bad = || {
        format!(
            "source_id {} is not an integer in 0..=4294967295",
            v.as_f64()
        )
    };
    match v {
        Val::I(i) => u32::try_from(i).map_err(|_| bad()),
        Val::F(f) if f.fract() == 0.0 && (0.0..=u32::MAX as f64).contains(&f) => Ok(f as u32),
        Val::F(_) => Err(bad()),
    }
}

fn read_vertices<S: Source>(
    src: &mut S,
    el: &Element,
    out: &mut Parsed,
    path: &Path,
) -> Result<()> {
    let VertexLayout {
        dests,
        channels: chan_specs,
        normals: has_normals,
        colors: has_colors,
    } = vertex_layout(el, path)?;
    let cap = src.start_element(el)?;
    let mut positions = Vec::with_capacity(cap);
    let mut normals = has_normals.then(|| Vec::with_capacity(cap));
    let mut colors = has_colors.then(|| Vec::with_capacity(cap));
    let mut source_ids = dests
        .iter()
        .any(|d| matches!(d, VDest::SourceId))
        .then(|| Vec::with_capacity(cap));
    let mut chans: Vec<ChanBuf> = chan_specs
        .iter()
        .map(|&(_, float)| {
            if float {
                ChanBuf::Scalar(Vec::with_capacity(cap))
            } else {
                ChanBuf::Label(Vec::with_capacity(cap))
            }
        })
        .collect();
    let err = |src: &S, rec: usize, msg: String| {
        format_err(path, src.loc(), format!("vertex {rec}: {msg}"))
    };
    for rec in 0..el.count {
        src.begin(el, rec)?;
        let mut p = [0.0f64; 3];
        let mut n = [0.0f64; 3];
        let mut c = [0u8; 3];
        let mut sid = 0u32;
        for (prop, dest) in el.props.iter().zip(&dests) {
            let Kind::Scalar(ty) = prop.kind else {
                skip_prop(src, prop, el, rec, path)?;
                continue;
            };
            let v = src.value(ty, el, rec, &prop.name)?;
            match *dest {
                VDest::Pos(k) => p[k] = v.as_f64(),
                VDest::Normal(k) => n[k] = v.as_f64(),
                VDest::Color(k) => c[k] = to_color(v, ty).map_err(|m| err(src, rec, m))?,
                VDest::SourceId => sid = to_source_id(v).map_err(|m| err(src, rec, m))?,
                VDest::Channel(k) => match (&mut chans[k], v) {
                    (ChanBuf::Scalar(buf), v) => {
                        let f = v.as_f64();
                        if !f.is_finite() {
                            return Err(err(
                                src,
                                rec,
                                format!(
                                    "property '{}' is {f}; expected a finite number",
                                    prop.name
                                ),
                            ));
                        }
                        buf.push(f);
                    }
                    (ChanBuf::Label(buf), Val::I(i)) => buf.push(i),
                    // Integer types always decode to `Val::I`.
                    (ChanBuf::Label(buf), Val::F(f)) => buf.push(f as i64),
                },
                VDest::Skip => {}
            }
        }
        src.end(el, rec)?;
        if !p.iter().all(|x| x.is_finite()) {
            return Err(err(
                src,
                rec,
                format!(
                    "non-finite coordinate ({}, {}, {}); expected finite numbers",
                    p[0], p[1], p[2]
                ),
            ));
        }
        positions.push(DVec3::from_array(p));
        if let Some(normals) = &mut normals {
            if !n.iter().all(|x| x.is_finite()) {
                return Err(err(
                    src,
                    rec,
                    format!(
                        "non-finite normal ({}, {}, {}); expected finite numbers",
                        n[0], n[1], n[2]
                    ),
                ));
            }
            normals.push(DVec3::from_array(n));
        }
        if let Some(colors) = &mut colors {
            colors.push(c);
        }
        if let Some(ids) = &mut source_ids {
            ids.push(sid);
        }
    }
    out.positions = positions;
    out.normals = normals;
    out.colors = colors;
    out.source_ids = source_ids;
    out.channels = chan_specs
        .into_iter()
        .zip(chans)
        .map(|((name, _), buf)| {
            let ch = match buf {
                ChanBuf::Scalar(v) => Channel::Scalar(v),
                ChanBuf::Label(v) => Channel::Label(v),
            };
            (name, ch)
        })
        .collect();
    Ok(())
}

fn read_faces<S: Source>(
    src: &mut S,
    el: &Element,
    n_vertices: usize,
    out: &mut Parsed,
    path: &Path,
) -> Result<()> {
    let found = el
        .prop("vertex_indices")
        .or_else(|| el.prop("vertex_index"));
    let Some((list_at, list_prop)) = found else {
        return Err(header_err(
            path,
            el.line,
            "the face element has no 'vertex_indices' (or 'vertex_index') list".into(),
        ));
    };
    let Kind::List { item, .. } = list_prop.kind else {
        return Err(header_err(
            path,
            list_prop.line,
            format!(
                "face property '{}' is a scalar; expected a list",
                list_prop.name
            ),
        ));
    };
    if item.is_float() {
        return Err(header_err(
            path,
            list_prop.line,
            format!(
                "face list '{}' has item type {}; expected an integer type",
                list_prop.name,
                item.name()
            ),
        ));
    }
    let cap = src.start_element(el)?;
    let mut faces = Vec::with_capacity(cap);
    let mut corners: Vec<u32> = Vec::new();
    for rec in 0..el.count {
        src.begin(el, rec)?;
        for (i, prop) in el.props.iter().enumerate() {
            let Kind::List { count, item } = prop.kind else {
                skip_prop(src, prop, el, rec, path)?;
                continue;
            };
            if i != list_at {
                skip_prop(src, prop, el, rec, path)?;
                continue;
            }
            let len = list_len(src, count, el, rec, &prop.name, path)?;
            if len < 3 {
                return Err(format_err(
                    path,
                    src.loc(),
                    format!("face {rec} has {len} vertex indices; expected at least 3"),
                ));
            }
            corners.clear();
            for _ in 0..len {
                let v = src.value(item, el, rec, &prop.name)?;
                let idx = match v {
                    Val::I(i) => i,
                    Val::F(f) => f as i64,
                };
                if idx < 0 || idx as u64 >= n_vertices as u64 {
                    return Err(format_err(
                        path,
                        src.loc(),
                        format!(
                            "face {rec} refers to vertex {idx}; expected an index below the \
                             {n_vertices} vertices declared in the header"
                        ),
                    ));
                }
                corners.push(idx as u32);
            }
            for k in 1..corners.len() - 1 {
                faces.push([corners[0], corners[k], corners[k + 1]]);
            }
        }
        src.end(el, rec)?;
    }
    out.faces = faces;
    Ok(())
}

fn decode_body<S: Source>(src: &mut S, header: &Header, path: &Path) -> Result<Parsed> {
    let vertex = header.elements.iter().find(|e| e.name == "vertex");
    let Some(vertex) = vertex else {
        return Err(format_err(
            path,
            Location::Line(header.lines),
            "the header declares no 'vertex' element".to_string(),
        ));
    };
    let mut out = Parsed::default();
    for el in &header.elements {
        match el.name.as_str() {
            "vertex" => read_vertices(src, el, &mut out, path)?,
            "face" => read_faces(src, el, vertex.count, &mut out, path)?,
            _ => skip_element(src, el, path)?,
        }
    }
    src.finish(header.elements.last())?;
    Ok(out)
}

/// Parses a whole PLY file.
pub(crate) fn parse(bytes: &[u8], path: &Path) -> Result<Parsed> {
    let header = parse_header(bytes, path)?;
    match header.encoding {
        PlyEncoding::Ascii => {
            let mut src = AsciiSource {
                path,
                lines: Lines::starting_at(bytes, header.body, header.lines),
                tokens: "".split_ascii_whitespace(),
                line: header.lines,
                used: 0,
            };
            decode_body(&mut src, &header, path)
        }
        enc => {
            let mut src = BinarySource {
                path,
                data: bytes,
                pos: header.body,
                record_start: header.body,
                big: enc == PlyEncoding::BinaryBigEndian,
            };
            decode_body(&mut src, &header, path)
        }
    }
}

// ---------------------------------------------------------------------------------------
// Writing.

/// Refuses channels PLY cannot store faithfully.
pub(crate) fn check_writable(g: &Geometry, path: &Path) -> Result<()> {
    let unsupported = |message: String| GeomError::UnsupportedFormat {
        path: path.to_path_buf(),
        message,
    };
    if let Some(c) = g.comments.iter().find(|c| c.contains(['\n', '\r'])) {
        return Err(unsupported(format!(
            "header comment {} holds a line break; a PLY comment is one line",
            show(c)
        )));
    }
    for &(name, ch) in &g.channels {
        if RESERVED.contains(&name) {
            return Err(unsupported(format!(
                "channel '{name}' has the name of a standard PLY vertex property; rename it"
            )));
        }
        if let Channel::Label(v) = ch
            && let Some(i) = v.iter().position(|&x| i32::try_from(x).is_err())
        {
            return Err(unsupported(format!(
                "label channel '{name}' value {} at point {i} does not fit the 32-bit \
                 PLY int type",
                v[i]
            )));
        }
    }
    Ok(())
}

fn write_header(w: &mut dyn Write, g: &Geometry, enc: PlyEncoding) -> io::Result<()> {
    let mut h = String::new();
    h.push_str("ply\n");
    h.push_str(&format!("format {} 1.0\n", enc.name()));
    h.push_str(&format!("comment written by reconbench ({})\n", g.what()));
    for c in g.comments {
        h.push_str(&format!("comment {c}\n"));
    }
    h.push_str(&format!("element vertex {}\n", g.positions.len()));
    h.push_str("property double x\nproperty double y\nproperty double z\n");
    if g.normals.is_some() {
        h.push_str("property double nx\nproperty double ny\nproperty double nz\n");
    }
    if g.colors.is_some() {
        h.push_str("property uchar red\nproperty uchar green\nproperty uchar blue\n");
    }
    if g.source_ids.is_some() {
        h.push_str("property uint source_id\n");
    }
    for &(name, ch) in &g.channels {
        let ty = match ch {
            Channel::Scalar(_) => "double",
            Channel::Label(_) => "int",
        };
        h.push_str(&format!("property {ty} {name}\n"));
    }
    if let Some(faces) = g.faces {
        h.push_str(&format!("element face {}\n", faces.len()));
        let idx = if g.positions.len() > i32::MAX as usize {
            "uint"
        } else {
            "int"
        };
        h.push_str(&format!("property list uchar {idx} vertex_indices\n"));
    }
    h.push_str("end_header\n");
    w.write_all(h.as_bytes())
}

/// Flush threshold of the binary record buffer.
const CHUNK: usize = 1 << 16;

fn write_binary(w: &mut dyn Write, g: &Geometry, big: bool) -> io::Result<()> {
    macro_rules! put {
        ($buf:expr, $v:expr) => {
            if big {
                $buf.extend_from_slice(&$v.to_be_bytes())
            } else {
                $buf.extend_from_slice(&$v.to_le_bytes())
            }
        };
    }
    let mut buf: Vec<u8> = Vec::with_capacity(CHUNK + 256);
    for (i, p) in g.positions.iter().enumerate() {
        put!(buf, p.x);
        put!(buf, p.y);
        put!(buf, p.z);
        if let Some(n) = g.normals {
            put!(buf, n[i].x);
            put!(buf, n[i].y);
            put!(buf, n[i].z);
        }
        if let Some(c) = g.colors {
            buf.extend_from_slice(&c[i]);
        }
        if let Some(s) = g.source_ids {
            put!(buf, s[i]);
        }
        for &(_, ch) in &g.channels {
            match ch {
                Channel::Scalar(v) => put!(buf, v[i]),
                // Range checked by `check_writable`.
                Channel::Label(v) => put!(buf, v[i] as i32),
            }
        }
        if buf.len() >= CHUNK {
            w.write_all(&buf)?;
            buf.clear();
        }
    }
    for f in g.faces.unwrap_or(&[]) {
        buf.push(3);
        for &v in f {
            put!(buf, v);
        }
        if buf.len() >= CHUNK {
            w.write_all(&buf)?;
            buf.clear();
        }
    }
    w.write_all(&buf)
}

fn write_ascii(w: &mut dyn Write, g: &Geometry) -> io::Result<()> {
    for (i, p) in g.positions.iter().enumerate() {
        write!(w, "{} {} {}", Num(p.x), Num(p.y), Num(p.z))?;
        if let Some(n) = g.normals {
            write!(w, " {} {} {}", Num(n[i].x), Num(n[i].y), Num(n[i].z))?;
        }
        if let Some(c) = g.colors {
            write!(w, " {} {} {}", c[i][0], c[i][1], c[i][2])?;
        }
        if let Some(s) = g.source_ids {
            write!(w, " {}", s[i])?;
        }
        for &(_, ch) in &g.channels {
            match ch {
                Channel::Scalar(v) => write!(w, " {}", Num(v[i]))?,
                Channel::Label(v) => write!(w, " {}", v[i])?,
            }
        }
        w.write_all(b"\n")?;
    }
    for f in g.faces.unwrap_or(&[]) {
        writeln!(w, "3 {} {} {}", f[0], f[1], f[2])?;
    }
    Ok(())
}

/// Writes a PLY file (call [`check_writable`] first).
pub(crate) fn write(w: &mut dyn Write, g: &Geometry, enc: PlyEncoding) -> io::Result<()> {
    write_header(w, g, enc)?;
    match enc {
        PlyEncoding::Ascii => write_ascii(w, g),
        PlyEncoding::BinaryLittleEndian => write_binary(w, g, false),
        PlyEncoding::BinaryBigEndian => write_binary(w, g, true),
    }
}
