//! Encoding for raw MCAP writing: a message type's schema ([`ChannelSchema`]) and a message's
//! bytes ([`encode`], [`encode_into`]).

use std::borrow::Cow;

use foxglove::Encode;

/// Why a message could not be encoded.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum EncodeError {
    /// The message type has no schema to put in a file.
    #[error("{type_name} has no schema")]
    NoSchema {
        /// The Rust type.
        type_name: &'static str,
    },
    /// The encoder failed.
    #[error("encoding {type_name}: {message}")]
    Encode {
        /// The Rust type.
        type_name: &'static str,
        /// What the encoder said.
        message: String,
    },
}

/// What an MCAP channel of a message type needs: its schema (name, encoding and data, for
/// protobuf a self-contained `FileDescriptorSet`) and its message encoding.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ChannelSchema {
    /// The schema's name, e.g. `foxglove.FrameTransforms`.
    pub name: String,
    /// The schema encoding, e.g. `protobuf`.
    pub encoding: String,
    /// The schema's data.
    pub data: Cow<'static, [u8]>,
    /// The message encoding, e.g. `protobuf`.
    pub message_encoding: String,
}

impl ChannelSchema {
    /// The schema of `M`'s messages.
    ///
    /// # Errors
    /// [`EncodeError::NoSchema`] for a type without one.
    pub fn of<M: Encode>() -> Result<Self, EncodeError> {
        let schema = M::get_schema().ok_or(EncodeError::NoSchema {
            type_name: std::any::type_name::<M>(),
        })?;
        Ok(Self {
            name: schema.name,
            encoding: schema.encoding,
            data: schema.data,
            message_encoding: M::get_message_encoding(),
        })
    }
}

/// `message`'s bytes, appended to `buf`.
///
/// # Errors
/// [`EncodeError::Encode`] if the encoder fails (it does not for the standard schemas into a
/// growing buffer).
pub fn encode_into<M: Encode>(message: &M, buf: &mut Vec<u8>) -> Result<(), EncodeError> {
    if let Some(len) = message.encoded_len() {
        buf.reserve(len);
    }
    message.encode(buf).map_err(|e| EncodeError::Encode {
        type_name: std::any::type_name::<M>(),
        message: e.to_string(),
    })
}

/// `message`'s bytes.
///
/// # Errors
/// See [`encode_into`].
pub fn encode<M: Encode>(message: &M) -> Result<Vec<u8>, EncodeError> {
    let mut buf = Vec::new();
    encode_into(message, &mut buf)?;
    Ok(buf)
}
