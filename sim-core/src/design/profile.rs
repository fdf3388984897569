//! Joint stiffness profiles along the antenna (docs/model.md section 5; thesis 3.3.2, 4.2.1).
//!
//! A chain of `N = n + 1` links (link 0 is the base link) has `n` joints. Joint `j`
//! (`j = 1..=n`) sits at the normalized position
//!
//! ```text
//! x_j = (l_0 + ... + l_(j-1)) / (l_0 + ... + l_n)   in (0, 1)
//! ```
//!
//! A profile shape `f` is normalized over the joints to `[k_min, k_max]`:
//!
//! ```text
//! k_j = k_min + (k_max - k_min) (f(x_j) - min f) / (max f - min f)
//! ```
//!
//! | name | f(x) |
//! |---|---|
//! | `constant` | `k_j = k_min` everywhere |
//! | `linear` | `1 - x` |
//! | `slow-exponential` | `exp(-2x)` |
//! | `fast-exponential` | `exp(-12x)` |
//! | `logarithmic` | `-ln x` |
//! | `slow-reciprocal` | `1/(x - 2)` |
//! | `fast-reciprocal` | `1/(x - 1.1)` |
//! | `cockroach` | `exp(-4.8x)` |
//! | `custom` | a list of `k_j`, used unchanged |
//!
//! Every shape but `constant` and `custom` is strictly decreasing on (0, 1), so the most
//! proximal joint gets `k_max` and the most distal one `k_min`. The exponentials, the
//! logarithm and `cockroach` are convex (below the `linear` profile at every interior
//! joint), the reciprocals concave (above it); the tests check exactly that.
//!
//! Returned vectors are indexed by joint: element `j - 1` is joint `j`'s stiffness.

use std::fmt;
use std::str::FromStr;

/// The thesis's robot's softest joint stiffness (thesis 4.2.1.1), N m/rad.
pub const SEED_K_MIN_N_M_PER_RAD: f64 = 0.004;
/// The thesis's robot's stiffest joint stiffness (thesis 4.2.1.1), N m/rad.
pub const SEED_K_MAX_N_M_PER_RAD: f64 = 0.082;

/// Errors from building a stiffness profile.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ProfileError {
    /// Fewer than two links: a chain of `N = n + 1` links needs `n >= 1` joints.
    #[error("link_lengths_m has {count} link(s); at least 2 are needed (one joint)")]
    TooFewLinks {
        /// Number of links given.
        count: usize,
    },
    /// A link length is not a finite positive number.
    #[error("link_lengths_m[{index}] = {value_m} m is not finite and positive")]
    InvalidLinkLength {
        /// Index into `link_lengths_m`.
        index: usize,
        /// The offending length, m.
        value_m: f64,
    },
    /// `k_min` or `k_max` is not a finite positive number.
    #[error("{field} = {value_n_m_per_rad} N m/rad is not finite and positive")]
    InvalidStiffnessBound {
        /// `"k_min_n_m_per_rad"` or `"k_max_n_m_per_rad"`.
        field: &'static str,
        /// The offending value, N m/rad.
        value_n_m_per_rad: f64,
    },
    /// `k_min > k_max`.
    #[error(
        "k_min_n_m_per_rad = {k_min_n_m_per_rad} exceeds k_max_n_m_per_rad = {k_max_n_m_per_rad}"
    )]
    InvertedRange {
        /// Lower bound given, N m/rad.
        k_min_n_m_per_rad: f64,
        /// Upper bound given, N m/rad.
        k_max_n_m_per_rad: f64,
    },
    /// A custom list whose length is not the number of joints.
    #[error("custom profile has {found} value(s) but the chain has {expected} joint(s)")]
    CustomLengthMismatch {
        /// Number of joints (`link_lengths_m.len() - 1`).
        expected: usize,
        /// Number of custom values given.
        found: usize,
    },
    /// A custom stiffness value is not a finite positive number.
    #[error("custom stiffness [{index}] = {value_n_m_per_rad} N m/rad is not finite and positive")]
    InvalidCustomStiffness {
        /// Index into the custom list (joint `index + 1`).
        index: usize,
        /// The offending value, N m/rad.
        value_n_m_per_rad: f64,
    },
    /// A profile name that is not one of the names in the table.
    #[error("unknown stiffness profile name {name:?}")]
    UnknownName {
        /// The name that was parsed.
        name: String,
    },
    /// `"custom"` was parsed without a list (`"custom:0.01,0.02"` is the form).
    #[error("profile \"custom\" needs its values, e.g. \"custom:0.01,0.02\"")]
    CustomWithoutValues,
    /// A token of a `"custom:..."` list is not a number.
    #[error("custom value #{index} {token:?} is not a number")]
    InvalidCustomToken {
        /// Position of the token in the list.
        index: usize,
        /// The token that failed to parse.
        token: String,
    },
}

/// A joint stiffness profile (docs/model.md section 5).
#[derive(Debug, Clone, PartialEq)]
pub enum StiffnessProfile {
    /// `k_j = k_min` at every joint.
    Constant,
    /// `f(x) = 1 - x`.
    Linear,
    /// `f(x) = exp(-2x)`.
    SlowExponential,
    /// `f(x) = exp(-12x)`.
    FastExponential,
    /// `f(x) = -ln x`.
    Logarithmic,
    /// `f(x) = 1/(x - 2)`.
    SlowReciprocal,
    /// `f(x) = 1/(x - 1.1)`.
    FastReciprocal,
    /// `f(x) = exp(-4.8x)`: the cockroach radius taper `0.95 exp(-0.012 x%)` of thesis 4.1.4.3
    /// raised to the fourth power (`EI ~ r^4`).
    Cockroach,
    /// Joint stiffnesses given directly, N m/rad, one per joint (joint `j` at index `j - 1`);
    /// returned unchanged (not normalized, not clamped to `[k_min, k_max]`).
    Custom(Vec<f64>),
}

impl StiffnessProfile {
    /// The eight named (non-custom) profiles, in the order of the docs/model.md table.
    pub const NAMED: [StiffnessProfile; 8] = [
        StiffnessProfile::Constant,
        StiffnessProfile::Linear,
        StiffnessProfile::SlowExponential,
        StiffnessProfile::FastExponential,
        StiffnessProfile::Logarithmic,
        StiffnessProfile::SlowReciprocal,
        StiffnessProfile::FastReciprocal,
        StiffnessProfile::Cockroach,
    ];

    /// The kebab-case name exactly as in the docs/model.md table (`"custom"` for a custom list).
    pub fn name(&self) -> &'static str {
        match self {
            Self::Constant => "constant",
            Self::Linear => "linear",
            Self::SlowExponential => "slow-exponential",
            Self::FastExponential => "fast-exponential",
            Self::Logarithmic => "logarithmic",
            Self::SlowReciprocal => "slow-reciprocal",
            Self::FastReciprocal => "fast-reciprocal",
            Self::Cockroach => "cockroach",
            Self::Custom(_) => "custom",
        }
    }

    /// The un-normalized shape `f(x)` for `x` in (0, 1); `None` for `constant` and `custom`,
    /// which are not shapes.
    pub fn shape(&self, x: f64) -> Option<f64> {
        match self {
            Self::Constant | Self::Custom(_) => None,
            Self::Linear => Some(1.0 - x),
            Self::SlowExponential => Some((-2.0 * x).exp()),
            Self::FastExponential => Some((-12.0 * x).exp()),
            Self::Logarithmic => Some(-x.ln()),
            Self::SlowReciprocal => Some(1.0 / (x - 2.0)),
            Self::FastReciprocal => Some(1.0 / (x - 1.1)),
            Self::Cockroach => Some((-4.8 * x).exp()),
        }
    }

    /// Joint stiffnesses, N m/rad, one per joint (element `j - 1` is joint `j`).
    ///
    /// `link_lengths_m` lists the `N = n + 1` link lengths from the base link outwards.
    /// Named shapes are normalized to `[k_min_n_m_per_rad, k_max_n_m_per_rad]`; with a single
    /// joint (where `max f = min f`) a decreasing shape gives that joint `k_max`, the value every
    /// decreasing shape gives its most proximal joint. `constant` gives `k_min` everywhere and
    /// `custom` returns its list unchanged after validation.
    ///
    /// # Errors
    /// [`ProfileError`] for fewer than two links, a non-positive or non-finite link length or
    /// bound, `k_min > k_max`, or a custom list of the wrong length or with a bad value.
    pub fn stiffness_n_m_per_rad(
        &self,
        link_lengths_m: &[f64],
        k_min_n_m_per_rad: f64,
        k_max_n_m_per_rad: f64,
    ) -> Result<Vec<f64>, ProfileError> {
        let positions = joint_positions(link_lengths_m)?;
        validate_bound("k_min_n_m_per_rad", k_min_n_m_per_rad)?;
        validate_bound("k_max_n_m_per_rad", k_max_n_m_per_rad)?;
        if k_min_n_m_per_rad > k_max_n_m_per_rad {
            return Err(ProfileError::InvertedRange {
                k_min_n_m_per_rad,
                k_max_n_m_per_rad,
            });
        }
        match self {
            Self::Constant => Ok(vec![k_min_n_m_per_rad; positions.len()]),
            Self::Custom(values) => {
                if values.len() != positions.len() {
                    return Err(ProfileError::CustomLengthMismatch {
                        expected: positions.len(),
                        found: values.len(),
                    });
                }
                for (index, &value) in values.iter().enumerate() {
                    if !(value.is_finite() && value > 0.0) {
                        return Err(ProfileError::InvalidCustomStiffness {
                            index,
                            value_n_m_per_rad: value,
                        });
                    }
                }
                Ok(values.clone())
            }
            _ => {
                // Every named shape is finite on (0, 1), so `shape` is `Some` and finite here.
                let f: Vec<f64> = positions
                    .iter()
                    .map(|&x| self.shape(x).unwrap_or(0.0))
                    .collect();
                let f_min = f.iter().copied().fold(f64::INFINITY, f64::min);
                let f_max = f.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                let span = f_max - f_min;
                let k_span = k_max_n_m_per_rad - k_min_n_m_per_rad;
                Ok(f.iter()
                    .map(|&fj| {
                        if span > 0.0 {
                            k_min_n_m_per_rad + k_span * (fj - f_min) / span
                        } else {
                            k_max_n_m_per_rad
                        }
                    })
                    .collect())
            }
        }
    }
}

impl fmt::Display for StiffnessProfile {
    /// Writes the name; a custom profile writes `custom:k1,k2,...` so that it parses back.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Custom(values) => {
                write!(f, "custom:")?;
                for (i, v) in values.iter().enumerate() {
                    if i > 0 {
                        write!(f, ",")?;
                    }
                    write!(f, "{v}")?;
                }
                Ok(())
            }
            other => f.write_str(other.name()),
        }
    }
}

impl FromStr for StiffnessProfile {
    type Err = ProfileError;

    /// Parses a table name (`"slow-exponential"`, ...) or `"custom:k1,k2,..."` (N m/rad).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let trimmed = s.trim();
        if let Some(list) = trimmed.strip_prefix("custom:") {
            let values = list
                .split(',')
                .enumerate()
                .map(|(index, token)| {
                    token
                        .trim()
                        .parse::<f64>()
                        .map_err(|_| ProfileError::InvalidCustomToken {
                            index,
                            token: token.to_string(),
                        })
                })
                .collect::<Result<Vec<f64>, _>>()?;
            return Ok(Self::Custom(values));
        }
        if trimmed == "custom" {
            return Err(ProfileError::CustomWithoutValues);
        }
        Self::NAMED
            .iter()
            .find(|p| p.name() == trimmed)
            .cloned()
            .ok_or_else(|| ProfileError::UnknownName {
                name: trimmed.to_string(),
            })
    }
}

/// Normalized joint positions `x_j`, one per joint (element `j - 1` is joint `j`), each in (0, 1).
///
/// # Errors
/// [`ProfileError::TooFewLinks`] for fewer than two links,
/// [`ProfileError::InvalidLinkLength`] for a non-positive or non-finite length.
pub fn joint_positions(link_lengths_m: &[f64]) -> Result<Vec<f64>, ProfileError> {
    if link_lengths_m.len() < 2 {
        return Err(ProfileError::TooFewLinks {
            count: link_lengths_m.len(),
        });
    }
    for (index, &value_m) in link_lengths_m.iter().enumerate() {
        if !(value_m.is_finite() && value_m > 0.0) {
            return Err(ProfileError::InvalidLinkLength { index, value_m });
        }
    }
    let total_m: f64 = link_lengths_m.iter().sum();
    let mut prefix_m = 0.0;
    Ok(link_lengths_m[..link_lengths_m.len() - 1]
        .iter()
        .map(|&l| {
            prefix_m += l;
            prefix_m / total_m
        })
        .collect())
}

fn validate_bound(field: &'static str, value: f64) -> Result<(), ProfileError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(ProfileError::InvalidStiffnessBound {
            field,
            value_n_m_per_rad: value,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const K_MIN: f64 = SEED_K_MIN_N_M_PER_RAD;
    const K_MAX: f64 = SEED_K_MAX_N_M_PER_RAD;

    /// The thesis's robot: a base link and nine 40 mm segments.
    fn seed_links() -> Vec<f64> {
        vec![0.04; 10]
    }

    fn decreasing() -> impl Iterator<Item = StiffnessProfile> {
        StiffnessProfile::NAMED
            .into_iter()
            .filter(|p| *p != StiffnessProfile::Constant)
    }

    fn below_linear(p: &StiffnessProfile) -> bool {
        matches!(
            p,
            StiffnessProfile::SlowExponential
                | StiffnessProfile::FastExponential
                | StiffnessProfile::Logarithmic
                | StiffnessProfile::Cockroach
        )
    }

    #[test]
    fn names_round_trip_and_match_table() {
        let expected = [
            "constant",
            "linear",
            "slow-exponential",
            "fast-exponential",
            "logarithmic",
            "slow-reciprocal",
            "fast-reciprocal",
            "cockroach",
        ];
        for (p, name) in StiffnessProfile::NAMED.iter().zip(expected) {
            assert_eq!(p.name(), name);
            assert_eq!(name.parse::<StiffnessProfile>().unwrap(), *p);
            assert_eq!(p.to_string(), name);
        }
        let custom: StiffnessProfile = "custom:0.01, 0.02,0.5".parse().unwrap();
        assert_eq!(custom, StiffnessProfile::Custom(vec![0.01, 0.02, 0.5]));
        assert_eq!(custom.name(), "custom");
        assert_eq!(
            custom.to_string().parse::<StiffnessProfile>().unwrap(),
            custom
        );
    }

    #[test]
    fn bad_names_are_typed_errors() {
        assert_eq!(
            "exponential".parse::<StiffnessProfile>(),
            Err(ProfileError::UnknownName {
                name: "exponential".into()
            })
        );
        assert_eq!(
            "custom".parse::<StiffnessProfile>(),
            Err(ProfileError::CustomWithoutValues)
        );
        assert_eq!(
            "custom:0.1,x".parse::<StiffnessProfile>(),
            Err(ProfileError::InvalidCustomToken {
                index: 1,
                token: "x".into()
            })
        );
    }

    #[test]
    fn joint_positions_follow_prefix_sums() {
        let x = joint_positions(&[1.0, 2.0, 3.0, 4.0]).unwrap();
        assert_eq!(x.len(), 3);
        for (got, want) in x.iter().zip([0.1, 0.3, 0.6]) {
            assert!((got - want).abs() < 1e-15, "{got} vs {want}");
        }
        let seed = joint_positions(&seed_links()).unwrap();
        assert_eq!(seed.len(), 9);
        assert!((seed[0] - 0.1).abs() < 1e-15 && (seed[8] - 0.9).abs() < 1e-15);
    }

    #[test]
    fn endpoints_hit_k_min_and_k_max() {
        for p in decreasing() {
            let k = p
                .stiffness_n_m_per_rad(&seed_links(), K_MIN, K_MAX)
                .unwrap();
            assert_eq!(k.len(), 9);
            assert!((k[0] - K_MAX).abs() < 1e-15, "{}: first {}", p.name(), k[0]);
            assert!((k[8] - K_MIN).abs() < 1e-15, "{}: last {}", p.name(), k[8]);
        }
    }

    #[test]
    fn constant_is_k_min_everywhere() {
        let k = StiffnessProfile::Constant
            .stiffness_n_m_per_rad(&seed_links(), K_MIN, K_MAX)
            .unwrap();
        assert_eq!(k, vec![K_MIN; 9]);
    }

    #[test]
    fn seed_linear_profile_golden() {
        // x_j = j/10, j = 1..9; linear normalization gives k_max - (j-1)/8 (k_max - k_min).
        let k = StiffnessProfile::Linear
            .stiffness_n_m_per_rad(&seed_links(), K_MIN, K_MAX)
            .unwrap();
        for (j, kj) in k.iter().enumerate() {
            let want = K_MAX - j as f64 / 8.0 * (K_MAX - K_MIN);
            assert!((kj - want).abs() < 1e-15, "joint {}: {kj} vs {want}", j + 1);
        }
    }

    #[test]
    fn single_joint_gets_k_max() {
        let k = StiffnessProfile::FastReciprocal
            .stiffness_n_m_per_rad(&[0.04, 0.04], K_MIN, K_MAX)
            .unwrap();
        assert_eq!(k, vec![K_MAX]);
    }

    #[test]
    fn custom_is_returned_unchanged_and_validated() {
        let values = vec![0.05, 0.03, 0.2];
        let p = StiffnessProfile::Custom(values.clone());
        assert_eq!(
            p.stiffness_n_m_per_rad(&[0.1; 4], K_MIN, K_MAX).unwrap(),
            values
        );
        assert_eq!(
            p.stiffness_n_m_per_rad(&[0.1; 3], K_MIN, K_MAX),
            Err(ProfileError::CustomLengthMismatch {
                expected: 2,
                found: 3
            })
        );
        let bad = StiffnessProfile::Custom(vec![0.05, f64::NAN]);
        assert!(matches!(
            bad.stiffness_n_m_per_rad(&[0.1; 3], K_MIN, K_MAX),
            Err(ProfileError::InvalidCustomStiffness { index: 1, .. })
        ));
    }

    #[test]
    fn bad_inputs_are_typed_errors() {
        let p = StiffnessProfile::Linear;
        assert_eq!(
            p.stiffness_n_m_per_rad(&seed_links(), 0.09, 0.08),
            Err(ProfileError::InvertedRange {
                k_min_n_m_per_rad: 0.09,
                k_max_n_m_per_rad: 0.08
            })
        );
        assert!(matches!(
            p.stiffness_n_m_per_rad(&seed_links(), 0.0, 0.08),
            Err(ProfileError::InvalidStiffnessBound {
                field: "k_min_n_m_per_rad",
                ..
            })
        ));
        assert!(matches!(
            p.stiffness_n_m_per_rad(&seed_links(), 0.004, f64::NAN),
            Err(ProfileError::InvalidStiffnessBound {
                field: "k_max_n_m_per_rad",
                ..
            })
        ));
        assert!(matches!(
            p.stiffness_n_m_per_rad(&seed_links(), -1.0, 0.08),
            Err(ProfileError::InvalidStiffnessBound { .. })
        ));
        assert_eq!(
            p.stiffness_n_m_per_rad(&[0.04], K_MIN, K_MAX),
            Err(ProfileError::TooFewLinks { count: 1 })
        );
        assert!(matches!(
            p.stiffness_n_m_per_rad(&[0.04, -0.01, 0.04], K_MIN, K_MAX),
            Err(ProfileError::InvalidLinkLength { index: 1, .. })
        ));
        assert!(matches!(
            p.stiffness_n_m_per_rad(&[0.04, 0.04, f64::NAN], K_MIN, K_MAX),
            Err(ProfileError::InvalidLinkLength { index: 2, .. })
        ));
    }

    proptest! {
        /// docs/model.md section 5: exponentials (and cockroach) and logarithmic below linear,
        /// reciprocals above it, at every interior joint, for any link lengths.
        #[test]
        fn qualitative_order_against_linear(
            lengths in prop::collection::vec(0.005f64..0.2, 4..16),
            k_min in 0.001f64..0.05,
            extra in 0.001f64..0.1,
        ) {
            let k_max = k_min + extra;
            let linear = StiffnessProfile::Linear
                .stiffness_n_m_per_rad(&lengths, k_min, k_max).unwrap();
            for p in decreasing().filter(|p| *p != StiffnessProfile::Linear) {
                let k = p.stiffness_n_m_per_rad(&lengths, k_min, k_max).unwrap();
                for j in 1..k.len() - 1 {
                    if below_linear(&p) {
                        prop_assert!(k[j] < linear[j], "{} joint {}: {} !< {}", p.name(), j + 1, k[j], linear[j]);
                    } else {
                        prop_assert!(k[j] > linear[j], "{} joint {}: {} !> {}", p.name(), j + 1, k[j], linear[j]);
                    }
                }
            }
        }

        /// Every non-constant named profile is strictly decreasing from k_max to k_min.
        #[test]
        fn decreasing_shapes_are_monotone_and_in_range(
            lengths in prop::collection::vec(0.005f64..0.2, 2..16),
            k_min in 0.001f64..0.05,
            extra in 0.001f64..0.1,
        ) {
            let k_max = k_min + extra;
            for p in decreasing() {
                let k = p.stiffness_n_m_per_rad(&lengths, k_min, k_max).unwrap();
                prop_assert!((k[0] - k_max).abs() <= 1e-12 * k_max);
                for w in k.windows(2) {
                    prop_assert!(w[1] < w[0], "{}: {:?}", p.name(), k);
                }
                for &kj in &k {
                    prop_assert!(kj >= k_min * (1.0 - 1e-12) && kj <= k_max * (1.0 + 1e-12));
                }
            }
        }
    }
}
