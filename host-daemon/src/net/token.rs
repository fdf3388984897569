//! The control token and its constant-time comparison.

use std::fmt;

/// The secret a client must send with every control command. Its `Debug` output is redacted.
#[derive(Clone, PartialEq, Eq)]
pub struct ControlToken(String);

/// The token was empty.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("the control token must not be empty")]
pub struct EmptyToken;

impl ControlToken {
    /// Wraps a non-empty secret.
    ///
    /// # Errors
    /// [`EmptyToken`] for an empty string (an empty token would let anyone control the rig).
    pub fn new(secret: impl Into<String>) -> Result<Self, EmptyToken> {
        let secret = secret.into();
        if secret.is_empty() {
            Err(EmptyToken)
        } else {
            Ok(Self(secret))
        }
    }

    /// Whether `candidate` is this token, in time that depends only on the lengths.
    pub fn matches(&self, candidate: &str) -> bool {
        constant_time_eq(self.0.as_bytes(), candidate.as_bytes())
    }
}

impl fmt::Debug for ControlToken {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("ControlToken(<redacted>)")
    }
}

/// Compares every byte position up to the longer length, so the time taken does not reveal
/// the length of the common prefix.
fn constant_time_eq(expected: &[u8], candidate: &[u8]) -> bool {
    let n = expected.len().max(candidate.len());
    let mut diff = u8::from(expected.len() != candidate.len());
    for i in 0..n {
        let a = expected.get(i).copied().unwrap_or(0);
        let b = candidate.get(i).copied().unwrap_or(0xFF);
        diff |= a ^ b;
    }
    std::hint::black_box(diff) == 0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn compares_exactly() {
        let t = ControlToken::new("s3cret").unwrap();
        assert!(t.matches("s3cret"));
        assert!(!t.matches("s3cre"));
        assert!(!t.matches("s3cret "));
        assert!(!t.matches(""));
        assert!(!t.matches("S3cret"));
        assert_eq!(ControlToken::new(""), Err(EmptyToken));
        assert!(!format!("{t:?}").contains("s3cret"));
    }
}
