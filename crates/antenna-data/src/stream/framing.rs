//! The framing: newline-delimited JSON, one object per line (see `docs/stream-protocol.md`).

use std::io::{self, BufRead};

use serde::Serialize;

/// The longest line, in bytes without its `\n`, the server accepts from a client (64 KiB).
pub const MAX_LINE_BYTES: usize = 64 * 1024;

/// What [`read_line_capped`] found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum LineRead {
    /// A complete line, without its `\n` (a trailing `\r` is removed too).
    Line(Vec<u8>),
    /// More than the limit arrived before a `\n`; the bytes read so far are discarded.
    TooLong,
    /// The peer closed its side; any unterminated bytes at the end are returned as a line first.
    Eof,
}

/// Reads one `\n`-terminated line of at most `max_bytes` bytes from `reader`.
///
/// Never buffers more than `max_bytes` plus one buffer of the reader, whatever the peer sends.
///
/// # Errors
/// The reader's I/O errors.
pub fn read_line_capped(reader: &mut impl BufRead, max_bytes: usize) -> io::Result<LineRead> {
    let mut line = Vec::new();
    loop {
        let available = match reader.fill_buf() {
            Ok(bytes) => bytes,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e),
        };
        if available.is_empty() {
            return Ok(if line.is_empty() {
                LineRead::Eof
            } else {
                LineRead::Line(trim_cr(line))
            });
        }
        let (chunk, found_newline) = match available.iter().position(|&b| b == b'\n') {
            Some(i) => (&available[..i], true),
            None => (available, false),
        };
        if line.len() + chunk.len() > max_bytes {
            let consumed = chunk.len() + usize::from(found_newline);
            reader.consume(consumed);
            return Ok(LineRead::TooLong);
        }
        line.extend_from_slice(chunk);
        let consumed = chunk.len() + usize::from(found_newline);
        reader.consume(consumed);
        if found_newline {
            return Ok(LineRead::Line(trim_cr(line)));
        }
    }
}

fn trim_cr(mut line: Vec<u8>) -> Vec<u8> {
    if line.last() == Some(&b'\r') {
        line.pop();
    }
    line
}

/// Encodes `message` as one line: compact JSON followed by `\n`.
///
/// # Errors
/// serde_json's error if the value cannot be represented (e.g. a map with non-string keys).
pub fn encode_line<T: Serialize>(message: &T) -> serde_json::Result<Vec<u8>> {
    let mut bytes = serde_json::to_vec(message)?;
    bytes.push(b'\n');
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splits_lines_and_reports_eof() {
        let mut input: &[u8] = b"{\"a\":1}\r\nxyz\n\ntail";
        assert_eq!(
            read_line_capped(&mut input, 100).unwrap(),
            LineRead::Line(b"{\"a\":1}".to_vec())
        );
        assert_eq!(
            read_line_capped(&mut input, 100).unwrap(),
            LineRead::Line(b"xyz".to_vec())
        );
        assert_eq!(
            read_line_capped(&mut input, 100).unwrap(),
            LineRead::Line(Vec::new())
        );
        assert_eq!(
            read_line_capped(&mut input, 100).unwrap(),
            LineRead::Line(b"tail".to_vec())
        );
        assert_eq!(read_line_capped(&mut input, 100).unwrap(), LineRead::Eof);
    }

    #[test]
    fn over_long_line_is_refused() {
        let mut input: &[u8] = b"0123456789\nok\n";
        assert_eq!(read_line_capped(&mut input, 4).unwrap(), LineRead::TooLong);
        let mut exact: &[u8] = b"0123\n";
        assert_eq!(
            read_line_capped(&mut exact, 4).unwrap(),
            LineRead::Line(b"0123".to_vec())
        );
    }

    #[test]
    fn encoded_line_ends_in_newline() {
        let bytes = encode_line(&serde_json::json!({"type": "x"})).unwrap();
        assert_eq!(bytes, b"{\"type\":\"x\"}\n");
    }
}
