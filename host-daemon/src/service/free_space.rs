//! Free space under the data directory: the [`FreeSpace`] probe the daemon asks before a trial
//! and once a second during it ([`StatvfsFreeSpace`], the file system's own count, by
//! default; tests give a fake one).

use std::io;
use std::path::Path;

/// Where the daemon learns how much room its recordings have.
pub trait FreeSpace: Send + Sync + std::fmt::Debug {
    /// Bytes an unprivileged process may still write on the file system holding `dir`.
    ///
    /// # Errors
    /// The OS's, e.g. for a directory that does not exist.
    fn free_bytes(&self, dir: &Path) -> io::Result<u64>;
}

/// The file system's count (`statvfs`: available blocks times the fragment size).
#[derive(Debug, Clone, Copy, Default)]
pub struct StatvfsFreeSpace;

impl FreeSpace for StatvfsFreeSpace {
    #[cfg(target_os = "linux")]
    fn free_bytes(&self, dir: &Path) -> io::Result<u64> {
        let stat = rustix::fs::statvfs(dir).map_err(io::Error::from)?;
        Ok(stat.f_bavail.saturating_mul(stat.f_frsize))
    }

    #[cfg(not(target_os = "linux"))]
    fn free_bytes(&self, _dir: &Path) -> io::Result<u64> {
        Ok(u64::MAX)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_temp_directory_has_some_room_and_a_missing_one_is_an_error() {
        let free = StatvfsFreeSpace.free_bytes(&std::env::temp_dir()).unwrap();
        assert!(free > 0);
        assert!(
            StatvfsFreeSpace
                .free_bytes(Path::new("/no/such/directory/here"))
                .is_err()
        );
    }
}
