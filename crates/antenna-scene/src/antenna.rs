//! `[antenna]` and `[antenna.stiffness]` (the fixed core of docs/scene-format.md) with
//! `[antenna.hairs]`: the chain, validated key by key.

use std::ops::Range;

use nalgebra::Vector2;
use serde::Deserialize;
use sim_core::{Chain, JointLimit, StiffnessProfile};
use toml::Spanned;

use super::hairs::{HairSpec, RawHairs};
use super::source::{Source, finite, list_of_len, positive};
use super::{DEFAULT_JOINT_LIMITS_DEG, MAX_LINKS, StiffnessSpec};
use crate::error::{SceneError, SceneErrorKind};

pub(crate) const ANTENNA: &str = "[antenna]";
const STIFFNESS: &str = "[antenna.stiffness]";

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawAntenna {
    links: Spanned<i64>,
    link_length_m: Option<Spanned<f64>>,
    link_lengths_m: Option<Spanned<Vec<f64>>>,
    base_angle_deg: Option<Spanned<f64>>,
    joint_limits_deg: Option<Spanned<Vec<f64>>>,
    rest_angles_deg: Option<Spanned<Vec<f64>>>,
    stiffness: Option<Spanned<RawStiffness>>,
    hairs: Option<Spanned<RawHairs>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawStiffness {
    profile: Option<Spanned<String>>,
    min_n_m_per_rad: Option<Spanned<f64>>,
    max_n_m_per_rad: Option<Spanned<f64>>,
    values_n_m_per_rad: Option<Spanned<Vec<f64>>>,
}

/// The validated `[antenna]` table: the chain (hairs included) and how its stiffness and
/// hairs were given.
pub(crate) struct Antenna {
    pub(crate) chain: Chain,
    pub(crate) stiffness: StiffnessSpec,
    pub(crate) hairs: Option<HairSpec>,
}

impl RawAntenna {
    /// Where `base_angle_deg` is written, if it is (a follow scene refuses it).
    pub(crate) fn base_angle_span(&self) -> Option<Range<usize>> {
        self.base_angle_deg.as_ref().map(Spanned::span)
    }

    pub(crate) fn validate(
        self,
        source: &Source<'_>,
        antenna_span: Range<usize>,
    ) -> Result<Antenna, SceneError> {
        let antenna = self;
        // links -> n flexible joints.
        let links_value = *antenna.links.get_ref();
        let links = usize::try_from(links_value)
            .ok()
            .filter(|&l| (2..=MAX_LINKS).contains(&l))
            .ok_or_else(|| {
                source.invalid(
                    antenna.links.span(),
                    ANTENNA,
                    "links",
                    format!(
                        "{links_value} is out of range: a chain needs 2..={MAX_LINKS} links \
                         (the base link and at least one flexible joint)"
                    ),
                )
            })?;
        let n = links - 1;

        // Link lengths: one for all or one per link.
        let link_lengths_m = match (&antenna.link_length_m, &antenna.link_lengths_m) {
            (Some(one), Some(many)) => {
                // Report the later of the two in the file.
                let (key, other, span) = if many.span().start > one.span().start {
                    ("link_lengths_m", "link_length_m", many.span())
                } else {
                    ("link_length_m", "link_lengths_m", one.span())
                };
                return Err(source.error(
                    Some(span),
                    SceneErrorKind::Conflict {
                        key: key.to_string(),
                        other: other.to_string(),
                        table: ANTENNA.to_string(),
                    },
                ));
            }
            (Some(one), None) => vec![positive(source, ANTENNA, "link_length_m", one)?; links],
            (None, Some(many)) => {
                let lengths = list_of_len(
                    source,
                    ANTENNA,
                    "link_lengths_m",
                    many,
                    links,
                    "one per link, links included the base link",
                )?;
                if let Some((i, l)) = lengths.iter().enumerate().find(|(_, l)| **l <= 0.0) {
                    return Err(source.invalid(
                        many.span(),
                        ANTENNA,
                        "link_lengths_m",
                        format!("value #{} is {l}; every length must be > 0", i + 1),
                    ));
                }
                lengths
            }
            (None, None) => {
                return Err(source.error(
                    Some(antenna_span.clone()),
                    SceneErrorKind::MissingKey {
                        key: "link_length_m` or `link_lengths_m".to_string(),
                        table: ANTENNA.to_string(),
                    },
                ));
            }
        };

        let base_angle_deg = match &antenna.base_angle_deg {
            Some(v) => finite(source, ANTENNA, "base_angle_deg", v)?,
            None => 0.0,
        };

        let [cw_deg, ccw_deg] = match &antenna.joint_limits_deg {
            Some(list) => {
                let v = list_of_len(
                    source,
                    ANTENNA,
                    "joint_limits_deg",
                    list,
                    2,
                    "[clockwise, counter-clockwise]",
                )?;
                if v[0] > v[1] {
                    return Err(source.invalid(
                        list.span(),
                        ANTENNA,
                        "joint_limits_deg",
                        format!(
                            "the clockwise limit {} exceeds the counter-clockwise limit {}",
                            v[0], v[1]
                        ),
                    ));
                }
                [v[0], v[1]]
            }
            None => DEFAULT_JOINT_LIMITS_DEG,
        };
        let limit = JointLimit::new(cw_deg.to_radians(), ccw_deg.to_radians());

        let rest_angles_rad: Vec<f64> = match &antenna.rest_angles_deg {
            Some(list) => list_of_len(
                source,
                ANTENNA,
                "rest_angles_deg",
                list,
                n,
                "one per flexible joint, links - 1",
            )?
            .into_iter()
            .map(f64::to_radians)
            .collect(),
            None => vec![0.0; n],
        };

        let Some(stiffness) = &antenna.stiffness else {
            return Err(source.error(
                Some(antenna_span.clone()),
                SceneErrorKind::MissingKey {
                    key: "stiffness".to_string(),
                    table: ANTENNA.to_string(),
                },
            ));
        };
        let (spec, k) = stiffness_values(source, stiffness, &link_lengths_m)?;

        let hairs = match &antenna.hairs {
            Some(raw) => Some(
                raw.get_ref()
                    .validate(source, raw.span(), &link_lengths_m)?,
            ),
            None => None,
        };
        let mut builder = Chain::builder(n)
            .link_lengths_m(link_lengths_m.clone())
            .base_angle_rad(base_angle_deg.to_radians())
            .joint_limit(limit)
            .stiffnesses_nm_per_rad(k)
            .rest_angles_rad(rest_angles_rad);
        if let Some(spec) = &hairs {
            for (link, hair) in spec.hairs(&link_lengths_m) {
                builder = builder.hair(link, hair);
            }
        }
        let chain = builder.build().map_err(|e| {
            let (table, key) = match (&hairs, &e) {
                (Some(_), sim_core::ChainError::HairOutOfRange { .. }) => {
                    ("[antenna.hairs]", "hairs")
                }
                _ => (ANTENNA, "antenna"),
            };
            source.invalid(antenna_span.clone(), table, key, e.to_string())
        })?;
        Ok(Antenna {
            chain,
            stiffness: spec,
            hairs,
        })
    }
}

/// A pin farther from the end of the base link than the flagellum's length cannot be reached.
pub(crate) fn check_reach(
    source: &Source<'_>,
    chain: &Chain,
    base_position_m: Vector2<f64>,
    pin_m: Vector2<f64>,
    span: Range<usize>,
) -> Result<(), SceneError> {
    let l0 = chain.link_lengths_m()[0];
    let (s, c) = chain.base_angle_rad().sin_cos();
    let frame0 = base_position_m + l0 * Vector2::new(c, s);
    let reach_m: f64 = chain.link_lengths_m()[1..].iter().sum();
    let distance_m = (pin_m - frame0).norm();
    if distance_m > reach_m {
        return Err(source.invalid(
            span,
            "[tip_pin]",
            "position_m",
            format!(
                "the pin is {distance_m:.6} m from the end of the base link at \
                 [{:.6}, {:.6}], farther than the flexible links reach ({reach_m:.6} m)",
                frame0.x, frame0.y
            ),
        ));
    }
    Ok(())
}

/// The stiffness values, one per flexible joint, and how they were given.
fn stiffness_values(
    source: &Source<'_>,
    stiffness: &Spanned<RawStiffness>,
    link_lengths_m: &[f64],
) -> Result<(StiffnessSpec, Vec<f64>), SceneError> {
    let table_span = stiffness.span();
    let raw = stiffness.get_ref();
    let n = link_lengths_m.len() - 1;
    let profile = raw.profile.as_ref();
    let custom = profile.is_some_and(|p| p.get_ref().trim() == "custom");

    if let Some(values) = &raw.values_n_m_per_rad {
        if let Some(p) = profile.filter(|_| !custom) {
            return Err(conflict(source, values, p, "values_n_m_per_rad", "profile"));
        }
        for (key, bound) in [
            ("min_n_m_per_rad", &raw.min_n_m_per_rad),
            ("max_n_m_per_rad", &raw.max_n_m_per_rad),
        ] {
            if let Some(b) = bound {
                return Err(conflict(source, values, b, "values_n_m_per_rad", key));
            }
        }
        let k = list_of_len(
            source,
            STIFFNESS,
            "values_n_m_per_rad",
            values,
            n,
            "one per flexible joint, links - 1",
        )?;
        if let Some((i, v)) = k.iter().enumerate().find(|(_, v)| **v <= 0.0) {
            return Err(source.invalid(
                values.span(),
                STIFFNESS,
                "values_n_m_per_rad",
                format!("value #{} is {v}; every stiffness must be > 0", i + 1),
            ));
        }
        return Ok((StiffnessSpec::Values, k));
    }

    let Some(profile) = profile else {
        return Err(source.error(
            Some(table_span),
            SceneErrorKind::MissingKey {
                key: "profile` or `values_n_m_per_rad".to_string(),
                table: STIFFNESS.to_string(),
            },
        ));
    };
    let names: Vec<&str> = StiffnessProfile::NAMED.iter().map(|p| p.name()).collect();
    if custom || profile.get_ref().trim().starts_with("custom:") {
        return Err(source.invalid(
            profile.span(),
            STIFFNESS,
            "profile",
            "a custom profile is a list: give it as values_n_m_per_rad (one per flexible \
             joint), with profile = \"custom\" or without a profile",
        ));
    }
    let parsed: StiffnessProfile = profile.get_ref().parse().map_err(|e| {
        source.invalid(
            profile.span(),
            STIFFNESS,
            "profile",
            format!("{e}; known profiles: {}, custom", names.join(", ")),
        )
    })?;
    let bound = |key: &str, value: &Option<Spanned<f64>>| match value {
        Some(v) => positive(source, STIFFNESS, key, v),
        None => Err(source.error(
            Some(table_span.clone()),
            SceneErrorKind::MissingKey {
                key: key.to_string(),
                table: STIFFNESS.to_string(),
            },
        )),
    };
    let min = bound("min_n_m_per_rad", &raw.min_n_m_per_rad)?;
    let max = bound("max_n_m_per_rad", &raw.max_n_m_per_rad)?;
    if min > max
        && let Some(max_span) = raw.max_n_m_per_rad.as_ref().map(Spanned::span)
    {
        return Err(source.invalid(
            max_span,
            STIFFNESS,
            "max_n_m_per_rad",
            format!("{max} is below min_n_m_per_rad = {min}"),
        ));
    }
    let k = parsed
        .stiffness_n_m_per_rad(link_lengths_m, min, max)
        .map_err(|e| source.invalid(profile.span(), STIFFNESS, "profile", e.to_string()))?;
    Ok((
        StiffnessSpec::Profile {
            profile: parsed,
            min_n_m_per_rad: min,
            max_n_m_per_rad: max,
        },
        k,
    ))
}

fn conflict<A, B>(
    source: &Source<'_>,
    a: &Spanned<A>,
    b: &Spanned<B>,
    a_key: &str,
    b_key: &str,
) -> SceneError {
    let (key, other, span) = if a.span().start > b.span().start {
        (a_key, b_key, a.span())
    } else {
        (b_key, a_key, b.span())
    };
    source.error(
        Some(span),
        SceneErrorKind::Conflict {
            key: key.to_string(),
            other: other.to_string(),
            table: STIFFNESS.to_string(),
        },
    )
}
