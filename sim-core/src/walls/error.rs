//! Typed errors for invalid wall descriptions ([`WallError`]).

/// An invalid wall or surface description, found by a constructor.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum WallError {
    /// A value is NaN or infinite.
    #[error("{field}[{index}] is not finite ({value})")]
    NotFinite {
        /// Which argument (`"vertices_m.x"`, `"angle_rad"`, ...).
        field: &'static str,
        /// Vertex or boundary index (0 for scalars).
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// A polyline with fewer than two vertices.
    #[error("a polyline needs at least 2 vertices, got {count}")]
    TooFewVertices {
        /// The number of vertices given.
        count: usize,
    },
    /// Two consecutive polyline vertices coincide.
    #[error("polyline edge {index} (vertex {index} to {next}) has zero length", next = index + 1)]
    ZeroLengthEdge {
        /// The edge index (from vertex `index` to `index + 1`).
        index: usize,
    },
    /// The polyline turns back on itself by 180 degrees at a vertex.
    #[error("polyline doubles back on itself at vertex {vertex}")]
    EdgeDoublesBack {
        /// The interior vertex where the two edges are antiparallel.
        vertex: usize,
    },
    /// Two non-adjacent polyline edges (end rays included) cross or touch.
    #[error("polyline edges {first} and {second} cross")]
    EdgesCross {
        /// The lower edge index.
        first: usize,
        /// The higher edge index.
        second: usize,
    },
    /// A sinusoid with a negative amplitude.
    #[error("sinusoid amplitude must be >= 0, got {amplitude_m} m")]
    NegativeAmplitude {
        /// The offending amplitude in metres.
        amplitude_m: f64,
    },
    /// A sinusoid with a zero or negative spatial frequency.
    #[error("sinusoid frequency must be > 0, got {frequency_per_m} cycles/m")]
    NonPositiveFrequency {
        /// The offending frequency in cycles per metre.
        frequency_per_m: f64,
    },
    /// A negative (or NaN) friction coefficient.
    #[error("friction coefficient must be finite and >= 0, got {mu}")]
    NegativeFriction {
        /// The offending coefficient.
        mu: f64,
    },
    /// A negative (or NaN) holding strength of a rough surface.
    #[error("{field} must be >= 0, got {value_n} N")]
    NegativeHold {
        /// `"hold_shear_n"` or `"hold_tension_n"`.
        field: &'static str,
        /// The offending force in newtons.
        value_n: f64,
    },
    /// Surface zone boundaries that do not strictly increase.
    #[error("surface zone boundary {index} does not exceed the previous one")]
    ZonesNotIncreasing {
        /// The index of the offending boundary.
        index: usize,
    },
}

/// `Ok` if `value` is finite, else [`WallError::NotFinite`].
pub(crate) fn finite(field: &'static str, index: usize, value: f64) -> Result<(), WallError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(WallError::NotFinite {
            field,
            index,
            value,
        })
    }
}
