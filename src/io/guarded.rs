//! Every file contactlab reads is opened here. A FIFO would block forever
//! (opening one for reading waits for a writer), a device such as
//! /dev/zero would be read until memory runs out, and a file far larger
//! than what it must hold would be read whole: so a file is read only if it
//! is a regular file, and small files only up to a limit. Larger data files
//! (matrices, CSV) are streamed line by line, with a limit on the length of
//! a line, so that a file without newlines is never held whole, and their
//! readers check what the file declares before they allocate for it.

use std::fs::File;
use std::io::{BufRead, BufReader, Read};
use std::path::Path;

/// The longest line a data file may have (a Matrix Market entry or a CSV
/// row is a few dozen bytes).
pub const MAX_LINE_BYTES: usize = 64 * 1024;

const NOT_REGULAR: &str = "it is not a regular file (a directory, FIFO or device); give a file";

/// Opens `path` for reading if it is a regular file; gives the file and its
/// length. The type is asked before opening (opening a FIFO blocks until a
/// writer comes), and again of the opened file, which was opened without
/// blocking, in case the path was replaced in between.
pub fn open(path: &Path) -> Result<(File, u64), String> {
    if !std::fs::metadata(path)
        .map_err(|e| e.to_string())?
        .is_file()
    {
        return Err(NOT_REGULAR.into());
    }
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(libc::O_NONBLOCK);
    }
    let file = options.open(path).map_err(|e| e.to_string())?;
    let meta = file.metadata().map_err(|e| e.to_string())?;
    if !meta.is_file() {
        return Err(NOT_REGULAR.into());
    }
    Ok((file, meta.len()))
}

/// Reads a regular file of at most `limit` bytes whole.
pub fn read_small(path: &Path, limit: u64) -> Result<Vec<u8>, String> {
    let (file, len) = open(path)?;
    if len > limit {
        return Err(format!(
            "it has {len} bytes, more than the limit of {limit} for this file"
        ));
    }
    let mut bytes = Vec::new();
    file.take(limit + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| e.to_string())?;
    if bytes.len() as u64 > limit {
        return Err(format!(
            "it holds more than the limit of {limit} bytes for this file"
        ));
    }
    Ok(bytes)
}

/// Reads a regular file of at most `limit` bytes whole as UTF-8 text, with
/// a leading byte-order mark (which some editors write) removed.
pub fn read_small_text(path: &Path, limit: u64) -> Result<String, String> {
    let bytes = read_small(path, limit)?;
    let text = String::from_utf8(bytes).map_err(|e| {
        format!(
            "it is not UTF-8 text (invalid byte at offset {})",
            e.utf8_error().valid_up_to()
        )
    })?;
    Ok(match text.strip_prefix('\u{feff}') {
        Some(rest) => rest.to_string(),
        None => text,
    })
}

/// A data file read line by line: each line at most [`MAX_LINE_BYTES`],
/// valid UTF-8, without its line ending; a leading byte-order mark is
/// dropped.
pub struct Lines<R> {
    reader: R,
    buffer: Vec<u8>,
    number: usize,
}

impl Lines<BufReader<File>> {
    /// Opens a regular file; gives its lines and its length in bytes.
    pub fn open(path: &Path) -> Result<(Self, u64), String> {
        let (file, len) = open(path)?;
        Ok((Self::new(BufReader::new(file)), len))
    }
}

impl<R: BufRead> Lines<R> {
    pub fn new(reader: R) -> Self {
        Self {
            reader,
            buffer: Vec::new(),
            number: 0,
        }
    }

    /// The number of the line last returned (1-based).
    pub fn number(&self) -> usize {
        self.number
    }

    /// The next line with its number (1-based), or None at the end of the
    /// file.
    pub fn next_numbered(&mut self) -> Result<Option<(usize, &str)>, String> {
        let number = self.number + 1;
        Ok(self.next_line()?.map(|l| (number, l)))
    }

    /// The next line, or None at the end of the file.
    pub fn next_line(&mut self) -> Result<Option<&str>, String> {
        self.buffer.clear();
        let limit = MAX_LINE_BYTES as u64 + 1;
        let read = (&mut self.reader)
            .take(limit)
            .read_until(b'\n', &mut self.buffer)
            .map_err(|e| e.to_string())?;
        if read == 0 {
            return Ok(None);
        }
        self.number += 1;
        if self.buffer.len() > MAX_LINE_BYTES {
            return Err(format!(
                "line {} is longer than {MAX_LINE_BYTES} bytes; is this the right file?",
                self.number
            ));
        }
        while matches!(self.buffer.last(), Some(b'\n' | b'\r')) {
            self.buffer.pop();
        }
        let mut text = std::str::from_utf8(&self.buffer)
            .map_err(|_| format!("line {} is not UTF-8 text", self.number))?;
        if self.number == 1 {
            text = text.strip_prefix('\u{feff}').unwrap_or(text);
        }
        Ok(Some(text))
    }
}

/// A CSV reader whose records may be at most [`MAX_LINE_BYTES`]
/// long, so that a file without line breaks is refused, not held whole.
pub fn csv_reader<R: Read>(source: R) -> csv::Reader<impl Read> {
    csv::ReaderBuilder::new()
        .buffer_capacity(8 * 1024)
        .from_reader(LineBounded::new(source))
}

/// A reader that fails once a line grows past [`MAX_LINE_BYTES`].
struct LineBounded<R> {
    inner: R,
    run: usize,
}

impl<R> LineBounded<R> {
    fn new(inner: R) -> Self {
        Self { inner, run: 0 }
    }
}

impl<R: std::io::Read> std::io::Read for LineBounded<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let got = self.inner.read(buf)?;
        for &b in &buf[..got] {
            self.run = if b == b'\n' { 0 } else { self.run + 1 };
            if self.run > MAX_LINE_BYTES {
                return Err(std::io::Error::new(
                    std::io::ErrorKind::InvalidData,
                    format!("a line is longer than {} bytes", MAX_LINE_BYTES),
                ));
            }
        }
        Ok(got)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_are_bounded_and_a_byte_order_mark_is_dropped() {
        let mut lines = Lines::new("\u{feff}1.5\r\n2\n\n3".as_bytes());
        let mut got = Vec::new();
        while let Some(l) = lines.next_line().unwrap() {
            got.push(l.to_string());
        }
        assert_eq!(got, ["1.5", "2", "", "3"]);
        let long = "9".repeat(MAX_LINE_BYTES + 10);
        let mut lines = Lines::new(long.as_bytes());
        assert!(lines.next_line().unwrap_err().contains("longer than"));
        let mut lines = Lines::new(&b"\xff\xfe\n"[..]);
        assert!(lines.next_line().unwrap_err().contains("UTF-8"));
    }

    #[test]
    fn only_regular_files_are_opened() {
        assert!(
            open(Path::new("/dev/zero"))
                .unwrap_err()
                .contains("regular")
        );
        assert!(open(Path::new("/")).unwrap_err().contains("regular"));
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("f");
        std::fs::write(&path, b"12345").unwrap();
        assert_eq!(read_small(&path, 5).unwrap(), b"12345");
        assert!(read_small(&path, 4).unwrap_err().contains("limit"));
    }
}
