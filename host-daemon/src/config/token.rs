//! The control token: at least [`MIN_TOKEN_CHARS`] characters, generated from the operating
//! system's random source when none is configured, compared in constant time, never shown
//! by `Debug`.

use std::fmt;

/// The shortest token accepted, in characters.
pub const MIN_TOKEN_CHARS: usize = 16;

/// Random bytes in a generated token (128 bits), written as 32 hexadecimal digits.
pub const GENERATED_TOKEN_BYTES: usize = 16;

/// The secret a client must send with every control command but `stop_all`. Its `Debug`
/// output is redacted and it has no `Display`: it is shown only where asked for by
/// [`ControlToken::expose`].
#[derive(Clone, PartialEq, Eq)]
pub struct ControlToken(String);

/// Why a token was refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum TokenError {
    /// Too short to resist guessing.
    #[error(
        "a control token needs at least {MIN_TOKEN_CHARS} characters, this one has {chars} \
         (leave it out and antennad generates one; or use 32 random hexadecimal digits, e.g. \
         `openssl rand -hex 16`)"
    )]
    TooShort {
        /// Its length in characters.
        chars: usize,
    },
    /// Leading or trailing white space or control characters, which clients lose or mangle.
    #[error("a control token must not hold control characters or start or end with white space")]
    BadCharacters,
    /// The operating system's random source failed.
    #[error("the operating system's random source failed: {0}")]
    Random(String),
}

impl ControlToken {
    /// Wraps a secret of at least [`MIN_TOKEN_CHARS`] characters.
    ///
    /// # Errors
    /// [`TokenError::TooShort`], [`TokenError::BadCharacters`].
    pub fn new(secret: impl Into<String>) -> Result<Self, TokenError> {
        let secret = secret.into();
        let chars = secret.chars().count();
        if chars < MIN_TOKEN_CHARS {
            return Err(TokenError::TooShort { chars });
        }
        if secret.trim() != secret || secret.chars().any(char::is_control) {
            return Err(TokenError::BadCharacters);
        }
        Ok(Self(secret))
    }

    /// A new token of [`GENERATED_TOKEN_BYTES`] bytes from the operating system's random
    /// source (`getrandom`), as hexadecimal digits.
    ///
    /// # Errors
    /// [`TokenError::Random`] if the random source fails.
    pub fn generate() -> Result<Self, TokenError> {
        let mut bytes = [0u8; GENERATED_TOKEN_BYTES];
        getrandom::fill(&mut bytes).map_err(|e| TokenError::Random(e.to_string()))?;
        let hex = bytes.iter().map(|b| format!("{b:02x}")).collect::<String>();
        Self::new(hex)
    }

    /// Whether `candidate` is this token, in time that depends only on the lengths.
    pub fn matches(&self, candidate: &str) -> bool {
        constant_time_eq(self.0.as_bytes(), candidate.as_bytes())
    }

    /// The secret itself: for the one place that must show it (`antennad` printing a
    /// generated token once at start, a client sending it).
    pub fn expose(&self) -> &str {
        &self.0
    }
}

impl fmt::Debug for ControlToken {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("ControlToken(<redacted>)")
    }
}

impl<'de> serde::Deserialize<'de> for ControlToken {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let secret = String::deserialize(deserializer)?;
        Self::new(secret).map_err(serde::de::Error::custom)
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
        let t = ControlToken::new("s3cret-s3cret-s3").unwrap();
        assert!(t.matches("s3cret-s3cret-s3"));
        assert!(!t.matches("s3cret-s3cret-s"));
        assert!(!t.matches("s3cret-s3cret-s3 "));
        assert!(!t.matches(""));
        assert!(!t.matches("S3cret-s3cret-s3"));
        assert!(!format!("{t:?}").contains("s3cret"));
    }

    #[test]
    fn short_and_odd_tokens_are_refused() {
        assert_eq!(
            ControlToken::new(""),
            Err(TokenError::TooShort { chars: 0 })
        );
        assert_eq!(
            ControlToken::new("a"),
            Err(TokenError::TooShort { chars: 1 })
        );
        assert_eq!(
            ControlToken::new("fifteen-chars-x"),
            Err(TokenError::TooShort { chars: 15 })
        );
        assert!(ControlToken::new("sixteen-chars-xy").is_ok());
        assert_eq!(
            ControlToken::new(" sixteen-chars-xy"),
            Err(TokenError::BadCharacters)
        );
        assert_eq!(
            ControlToken::new("sixteen\nchars-xyz"),
            Err(TokenError::BadCharacters)
        );
    }

    #[test]
    fn generated_tokens_are_128_random_bits() {
        let a = ControlToken::generate().unwrap();
        let b = ControlToken::generate().unwrap();
        assert_eq!(a.expose().len(), 2 * GENERATED_TOKEN_BYTES);
        assert!(a.expose().chars().all(|c| c.is_ascii_hexdigit()));
        assert_ne!(a, b);
    }
}
