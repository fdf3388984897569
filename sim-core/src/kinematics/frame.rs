//! Frame indices: the thesis's `-1..=n` numbering as a small type.

use crate::KinematicsError;

/// A coordinate frame of the chain, numbered as in the thesis (2.2.1, Definition 2.2.1):
/// `-1` is the ground frame `C_G` at the base attachment, `i` in `0..=n` is the frame `C_i`
/// at the distal end of link `i` (x-axis along the link). `C_n` is the tip.
///
/// A `Frame` is only a number; functions that take one check it against the chain and
/// return [`KinematicsError::FrameOutOfRange`] if it does not fit.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Frame(isize);

impl Frame {
    /// The ground frame `C_G = C_{-1}`.
    pub const GROUND: Frame = Frame(-1);

    /// The frame with the thesis's index `index` (`-1` for ground).
    pub const fn new(index: isize) -> Frame {
        Frame(index)
    }

    /// The frame `C_i` at the distal end of link `i`.
    pub const fn link(i: usize) -> Frame {
        if i > isize::MAX as usize {
            Frame(isize::MAX)
        } else {
            Frame(i as isize)
        }
    }

    /// The thesis's index of this frame (`-1` for ground).
    pub const fn index(self) -> isize {
        self.0
    }

    /// Position in a per-frame list (ground first): `index + 1`. Only meaningful for a valid
    /// frame.
    pub(crate) const fn slot(self) -> usize {
        (self.0 + 1) as usize
    }

    /// Checks `-1 <= index <= n`.
    pub(crate) fn check(self, n: usize, argument: &'static str) -> Result<Frame, KinematicsError> {
        if self.0 >= -1 && (self.0 as i128) <= n as i128 {
            Ok(self)
        } else {
            Err(KinematicsError::FrameOutOfRange {
                argument,
                index: self.0,
                n,
            })
        }
    }
}

impl From<isize> for Frame {
    fn from(index: isize) -> Frame {
        Frame(index)
    }
}
