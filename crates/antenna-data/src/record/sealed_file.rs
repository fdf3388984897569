//! [`SealedFile`]: the file under the MCAP writer, kept a complete MCAP file after every flush.
//!
//! The MCAP writer's bytes are held in memory between flushes. A flush writes them, followed
//! by a provisional end of file (a Data End record, a Footer without summary and the closing
//! magic, [`PROVISIONAL_TAIL_BYTES`] bytes), with one positional write where the previous
//! flush's provisional end began. So after each flush the file on disk is a whole MCAP file
//! without a summary, which every standard reader opens as it is (Python's `mcap`
//! `make_reader`, the Rust `mcap` crate, Foxglove): a process killed with `kill -9` between
//! flushes leaves such a file, losing only what it had not flushed. The next flush overwrites
//! the provisional end; closing writes the writer's real end (summary, footer) and cuts the
//! file to its length. Only a kill that lands inside the one write of a flush (a few
//! kilobytes) can leave a torn end, which [`super::TrialReader`] still reads up to the last
//! whole record.
//!
//! A flush reaches the operating system, not the disk: a sync through
//! [`SealedFile::sync_handle`] asks the disk
//! (`fdatasync`); a power cut may lose what was flushed but not synced.

use std::fs::File;
use std::io::{self, Seek, SeekFrom, Write};
use std::path::Path;

use mcap::records::op;

/// Length of the provisional end: Data End (1 + 8 + 4), Footer (1 + 8 + 20), magic (8).
pub const PROVISIONAL_TAIL_BYTES: usize = 50;

/// The provisional end of file: a Data End record without a data-section CRC (0: not
/// computed), a Footer saying there is no summary (offsets and CRC 0) and the magic.
fn provisional_tail() -> [u8; PROVISIONAL_TAIL_BYTES] {
    let mut tail = [0u8; PROVISIONAL_TAIL_BYTES];
    tail[0] = op::DATA_END;
    tail[1..9].copy_from_slice(&4u64.to_le_bytes());
    // tail[9..13]: data_section_crc = 0
    tail[13] = op::FOOTER;
    tail[14..22].copy_from_slice(&20u64.to_le_bytes());
    // tail[22..42]: summary_start = 0, summary_offset_start = 0, summary_crc = 0
    tail[42..].copy_from_slice(mcap::MAGIC);
    tail
}

/// A file written through an in-memory buffer, sealed with a provisional MCAP end at every
/// flush (see the module documentation).
#[derive(Debug)]
pub struct SealedFile {
    file: File,
    /// Bytes accepted and not yet written.
    pending: Vec<u8>,
    /// Bytes written to the file, not counting the provisional end.
    written: u64,
    /// Whether the file ends in a provisional end now.
    sealed: bool,
}

impl SealedFile {
    /// Creates `path`, which must not exist (a planted file or symbolic link is never
    /// overwritten), and makes its directory entry durable.
    ///
    /// # Errors
    /// The OS's, e.g. `AlreadyExists`.
    pub fn create_new(path: &Path) -> io::Result<Self> {
        let file = File::options().write(true).create_new(true).open(path)?;
        sync_parent_directory(path)?;
        Ok(Self {
            file,
            pending: Vec::new(),
            written: 0,
            sealed: false,
        })
    }

    /// Writes what is pending and, unless `finished`, the provisional end after it, in one
    /// positional write at the end of what is written.
    fn write_out(&mut self, finished: bool) -> io::Result<()> {
        if self.pending.is_empty() && (self.sealed || finished) {
            return Ok(());
        }
        let length = self.pending.len();
        if !finished {
            self.pending.extend_from_slice(&provisional_tail());
        }
        let result = write_all_at(&self.file, &self.pending, self.written);
        self.pending.truncate(length);
        result?;
        self.written += length as u64;
        self.pending.clear();
        self.sealed = !finished;
        Ok(())
    }

    /// Another handle on the same file, to sync it (`File::sync_data`) while this one is
    /// the MCAP writer's: a sync asks the disk to keep everything flushed so far.
    ///
    /// # Errors
    /// The OS's.
    pub fn sync_handle(&self) -> io::Result<File> {
        self.file.try_clone()
    }

    /// Writes what is pending without a provisional end (the MCAP writer has written its own
    /// end), cuts the file to its length and syncs it to the disk.
    ///
    /// # Errors
    /// The OS's.
    pub fn close(&mut self) -> io::Result<()> {
        self.write_out(true)?;
        self.file.set_len(self.written)?;
        self.file.sync_all()
    }
}

impl Write for SealedFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.pending.extend_from_slice(buf);
        Ok(buf.len())
    }

    /// Writes everything so far, sealed with the provisional end.
    fn flush(&mut self) -> io::Result<()> {
        self.write_out(false)
    }
}

impl Seek for SealedFile {
    /// Only reports the position: the MCAP writer is told not to seek
    /// (`WriteOptions::disable_seeking`), so it asks for nothing else.
    fn seek(&mut self, pos: SeekFrom) -> io::Result<u64> {
        let position = self.written + self.pending.len() as u64;
        match pos {
            SeekFrom::Current(0) | SeekFrom::End(0) => Ok(position),
            SeekFrom::Start(p) if p == position => Ok(position),
            _ => Err(io::Error::new(
                io::ErrorKind::Unsupported,
                "a trial file is written in order, without seeking",
            )),
        }
    }
}

#[cfg(unix)]
fn write_all_at(file: &File, bytes: &[u8], offset: u64) -> io::Result<()> {
    std::os::unix::fs::FileExt::write_all_at(file, bytes, offset)
}

#[cfg(not(unix))]
fn write_all_at(file: &File, bytes: &[u8], offset: u64) -> io::Result<()> {
    let mut file = file;
    file.seek(SeekFrom::Start(offset))?;
    file.write_all(bytes)
}

/// Syncs the directory holding `path`, so that the new file's name survives a power cut.
#[cfg(unix)]
fn sync_parent_directory(path: &Path) -> io::Result<()> {
    let dir = match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    };
    File::open(dir)?.sync_all()
}

#[cfg(not(unix))]
fn sync_parent_directory(_path: &Path) -> io::Result<()> {
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp(name: &str) -> std::path::PathBuf {
        let path = std::env::temp_dir().join(format!("sealed-{name}-{}", std::process::id()));
        let _ = std::fs::remove_file(&path);
        path
    }

    #[test]
    fn every_flush_ends_the_file_with_one_provisional_tail() {
        let path = temp("tail");
        let mut file = SealedFile::create_new(&path).unwrap();
        file.write_all(b"abc").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"");
        file.flush().unwrap();
        let mut expected = b"abc".to_vec();
        expected.extend_from_slice(&provisional_tail());
        assert_eq!(std::fs::read(&path).unwrap(), expected);
        file.write_all(b"defg").unwrap();
        assert_eq!(file.stream_position().unwrap(), 7);
        file.flush().unwrap();
        file.flush().unwrap();
        let mut expected = b"abcdefg".to_vec();
        expected.extend_from_slice(&provisional_tail());
        assert_eq!(std::fs::read(&path).unwrap(), expected);
        file.sync_handle().unwrap().sync_data().unwrap();
        file.write_all(b"h").unwrap();
        file.close().unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"abcdefgh");
        std::fs::remove_file(&path).unwrap();
    }

    #[test]
    fn never_overwrites_and_never_seeks() {
        let path = temp("exists");
        std::fs::write(&path, b"precious").unwrap();
        let error = SealedFile::create_new(&path).unwrap_err();
        assert_eq!(error.kind(), io::ErrorKind::AlreadyExists);
        assert_eq!(std::fs::read(&path).unwrap(), b"precious");
        std::fs::remove_file(&path).unwrap();
        let mut file = SealedFile::create_new(&path).unwrap();
        file.write_all(b"xy").unwrap();
        assert_eq!(file.seek(SeekFrom::Start(2)).unwrap(), 2);
        assert!(file.seek(SeekFrom::Start(0)).is_err());
        std::fs::remove_file(&path).unwrap();
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn a_full_disk_is_an_error_not_a_panic() {
        // /dev/full takes the open and refuses every write with ENOSPC.
        let file = File::options().write(true).open("/dev/full").unwrap();
        let mut sealed = SealedFile {
            file,
            pending: Vec::new(),
            written: 0,
            sealed: false,
        };
        sealed.write_all(b"data").unwrap();
        let error = sealed.flush().unwrap_err();
        assert_eq!(error.raw_os_error(), Some(28), "{error}"); // ENOSPC
        // Nothing counts as written; the pending bytes are kept for a retry.
        assert_eq!(sealed.stream_position().unwrap(), 4);
    }
}
