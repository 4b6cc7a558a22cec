//! Loading an input file into memory with a bound derived from the file, not from its
//! claims.
//!
//! Every file reader of this module goes through [`read_input`], which holds no more than
//! the input can justify:
//!
//! - a regular file is read up to its size (from its metadata), never beyond;
//! - a stream (a pipe, a FIFO, a device such as `/dev/zero`) is read up to
//!   [`MAX_STREAM_BYTES`]; a longer stream is an error, found once the limit is passed;
//! - in text formats (OBJ, OFF, XYZ, PTS, `.m`, ascii PLY and ascii STL) a line longer
//!   than [`MAX_LINE_BYTES`] is an error as soon as it is seen, so a file of zeros without
//!   line breaks is refused after 1 MiB instead of being buffered whole;
//! - a PLY header is read first (at most [`MAX_PLY_HEADER_BYTES`]); for a binary body
//!   its element counts are checked against the bytes the file holds (or the stream
//!   limit) before the body is read, and a body of fixed-size records is read to its
//!   exact length;
//! - a binary STL's triangle count is checked against the file size before the
//!   triangles are read.
//!
//! The parsers then work on the bytes in memory, and bound their own allocations by the
//! bytes they were given.

use std::fs::File;
use std::io::{ErrorKind, Read};
use std::path::Path;

use super::{Format, format_err, ply, stl};
use crate::error::{GeomError, Location, Result};

/// Longest line a text format may have, in bytes (1 MiB): far above any real record (a
/// polygon of 50,000 corners fits), small enough that an input without line breaks is
/// refused at once.
pub const MAX_LINE_BYTES: usize = 1 << 20;

/// Most bytes read from an input that is not a regular file (512 MiB): a stream has no
/// size to check header counts against, so it gets a fixed budget. Save larger inputs to
/// a file first.
pub const MAX_STREAM_BYTES: u64 = 512 << 20;

/// Longest PLY header, in bytes (1 MiB), comments included.
pub const MAX_PLY_HEADER_BYTES: usize = 1 << 20;

/// Bytes asked of the operating system per read.
const CHUNK: usize = 1 << 16;

/// Reads the input at `path` for a parser of `format`, within the bounds above.
pub(crate) fn read_input(path: &Path, format: Format) -> Result<Vec<u8>> {
    let input = Input::open(path, format)?;
    match format {
        Format::Ply => input.read_ply(),
        Format::Stl => input.read_stl(),
        _ => input.read_text(0),
    }
}

/// The header of a PLY file (up to and including its `end_header` line, or what there
/// is when the header is malformed), without reading the body.
pub(crate) fn read_ply_header(path: &Path) -> Result<Vec<u8>> {
    let mut input = Input::open(path, Format::Ply)?;
    let end = input.fill_ply_header()?;
    input.buf.truncate(end.unwrap_or(input.buf.len()));
    Ok(input.buf)
}

/// An input being read.
struct Input<'a> {
    path: &'a Path,
    format: Format,
    file: File,
    /// Size of a regular file; `None` for a stream.
    size: Option<u64>,
    buf: Vec<u8>,
    /// The last read returned nothing.
    eof: bool,
    chunk: Vec<u8>,
}

impl<'a> Input<'a> {
    fn open(path: &'a Path, format: Format) -> Result<Self> {
        let io = |source| GeomError::Io {
            path: path.to_path_buf(),
            source,
        };
        let file = File::open(path).map_err(io)?;
        let meta = file.metadata().map_err(io)?;
        if meta.is_dir() {
            return Err(format_err(
                path,
                Location::File,
                format!("is a directory; expected a {format} file"),
            ));
        }
        Ok(Self {
            path,
            format,
            file,
            size: meta.is_file().then_some(meta.len()),
            buf: Vec::new(),
            eof: false,
            chunk: vec![0; CHUNK],
        })
    }

    /// How many bytes may be read at most: the file size, or one byte past the stream
    /// limit (to tell a stream at the limit from a longer one).
    fn cap(&self) -> u64 {
        self.size.unwrap_or(MAX_STREAM_BYTES + 1)
    }

    /// True when nothing more will be read.
    fn done(&self) -> bool {
        self.eof || self.buf.len() as u64 >= self.cap()
    }

    fn len(&self) -> u64 {
        self.buf.len() as u64
    }

    /// Reads until the buffer holds `want` bytes (at most [`Self::cap`]) or the input
    /// ends. Capacity grows by doubling, never past the target, so a stream's buffer
    /// stays within its limit.
    fn fill_to(&mut self, want: u64) -> Result<()> {
        let target = want.min(self.cap());
        while !self.eof && self.len() < target {
            let room = (target - self.len()).min(CHUNK as u64) as usize;
            if self.buf.capacity() - self.buf.len() < room {
                let doubled = (self.buf.capacity() as u64 * 2).max(CHUNK as u64);
                let new_cap = doubled.min(target).max(self.len() + room as u64);
                self.reserve(new_cap - self.len())?;
            }
            let n = loop {
                match self.file.read(&mut self.chunk[..room]) {
                    Err(e) if e.kind() == ErrorKind::Interrupted => continue,
                    r => {
                        break r.map_err(|source| GeomError::Io {
                            path: self.path.to_path_buf(),
                            source,
                        })?;
                    }
                }
            };
            if n == 0 {
                self.eof = true;
            } else {
                self.buf.extend_from_slice(&self.chunk[..n]);
            }
        }
        if self.size.is_none() && self.len() > MAX_STREAM_BYTES {
            return Err(format_err(
                self.path,
                Location::File,
                format!(
                    "the input is a stream (not a regular file) of more than {MAX_STREAM_BYTES} \
                     bytes, the most read from a stream; save it to a file first"
                ),
            ));
        }
        Ok(())
    }

    /// Reserves `additional` bytes, as an error rather than an abort when the memory is
    /// not there.
    fn reserve(&mut self, additional: u64) -> Result<()> {
        let (path, total) = (self.path, self.len().saturating_add(additional));
        let fail = || {
            format_err(
                path,
                Location::File,
                format!("cannot allocate {total} bytes to read the file"),
            )
        };
        let n = usize::try_from(additional).map_err(|_| fail())?;
        self.buf.try_reserve_exact(n).map_err(|_| fail())
    }

    /// Reads everything that is left (a regular file in one allocation of its size).
    fn read_all(mut self) -> Result<Vec<u8>> {
        if let Some(size) = self.size {
            self.reserve(size.saturating_sub(self.len()))?;
        }
        self.fill_to(u64::MAX)?;
        Ok(self.buf)
    }

    /// Reads the rest as text, refusing a line longer than [`MAX_LINE_BYTES`] as soon as
    /// it is seen. `line_start` is where the current line starts.
    fn read_text(mut self, mut line_start: usize) -> Result<Vec<u8>> {
        let mut scanned = line_start;
        loop {
            if let Some(i) = self.buf[scanned..].iter().rposition(|&b| b == b'\n') {
                line_start = scanned + i + 1;
            }
            scanned = self.buf.len();
            if scanned - line_start > MAX_LINE_BYTES {
                return Err(self.long_line(line_start));
            }
            if self.done() {
                return Ok(self.buf);
            }
            self.fill_to(self.len() + CHUNK as u64)?;
        }
    }

    fn long_line(&self, line_start: usize) -> GeomError {
        let line = 1 + self.buf[..line_start]
            .iter()
            .filter(|&&b| b == b'\n')
            .count();
        format_err(
            self.path,
            Location::Line(line),
            format!(
                "the line is longer than {MAX_LINE_BYTES} bytes (no line break in {} bytes); \
                 expected a {} text file (is this a binary file, or the wrong format?)",
                self.buf.len() - line_start,
                self.format
            ),
        )
    }

    /// Reads until the PLY header is complete; returns the offset of the body, or `None`
    /// when the input ends first or does not start like a PLY file (the parser then
    /// reports what is wrong).
    fn fill_ply_header(&mut self) -> Result<Option<usize>> {
        loop {
            match ply::header_end(&self.buf) {
                ply::HeaderEnd::Found(end) => return Ok(Some(end)),
                ply::HeaderEnd::NotPly => return Ok(None),
                ply::HeaderEnd::Incomplete => {}
            }
            if self.done() {
                return Ok(None);
            }
            if self.buf.len() > MAX_PLY_HEADER_BYTES {
                return Err(format_err(
                    self.path,
                    Location::File,
                    format!(
                        "no 'end_header' line in the first {MAX_PLY_HEADER_BYTES} bytes; \
                         expected a PLY header of at most that size"
                    ),
                ));
            }
            self.fill_to(self.len() + CHUNK as u64)?;
        }
    }

    fn read_ply(mut self) -> Result<Vec<u8>> {
        let Some(body) = self.fill_ply_header()? else {
            return Ok(self.buf);
        };
        let needs = ply::body_needs(&self.buf[..body], self.path)?;
        let Some(needs) = needs else {
            return self.read_text(body);
        };
        let avail = self
            .size
            .unwrap_or(MAX_STREAM_BYTES)
            .saturating_sub(body as u64);
        needs.check(avail, self.size.is_none(), self.path)?;
        match (needs.exact, self.size) {
            (false, _) => self.read_all(),
            (true, Some(size)) => {
                needs.check_no_trailing(size - body as u64, false, self.path)?;
                self.read_all()
            }
            (true, None) => {
                // One byte more than needed, so that trailing data is seen.
                let want = body as u64 + needs.min_bytes() + 1;
                self.reserve(want.saturating_sub(self.len()))?;
                self.fill_to(want)?;
                needs.check_no_trailing(self.len() - body as u64, true, self.path)?;
                Ok(self.buf)
            }
        }
    }

    fn read_stl(mut self) -> Result<Vec<u8>> {
        self.fill_to(stl::PREFIX as u64)?;
        let Some(n) = stl::declared_triangles(&self.buf) else {
            return Ok(self.buf);
        };
        let expected = stl::binary_size(n);
        let maybe_ascii = stl::may_be_ascii(&self.buf);
        match self.size {
            Some(size) if size == expected => self.read_all(),
            Some(size) if !maybe_ascii => Err(stl::size_error(n, size, false, self.path)),
            Some(_) => self.read_text(0),
            None if maybe_ascii => self.read_text(0),
            None if expected > MAX_STREAM_BYTES => Err(format_err(
                self.path,
                Location::Byte(stl::PREFIX as u64 - 4),
                format!(
                    "binary STL header declares {n} triangles, which take {expected} bytes, \
                     more than the {MAX_STREAM_BYTES} bytes read from a stream"
                ),
            )),
            None => {
                self.fill_to(expected + 1)?;
                Ok(self.buf)
            }
        }
    }
}
