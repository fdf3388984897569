//! `[antenna.hairs]`: anisotropic hairs on the flagellar links (docs/model.md 7), one hair
//! description for the links it names; unset keys take [`Hair::seed`]'s values.

use std::fmt;
use std::ops::Range;

use serde::Deserialize;
use serde::de::{self, Deserializer, SeqAccess, Visitor};
use sim_core::{Hair, HairDirection, HairSide};
use toml::Spanned;

use super::source::{Source, non_negative, one_of, positive};
use crate::error::SceneError;

const HAIRS: &str = "[antenna.hairs]";

/// The names `direction` accepts, in [`HairDirection`] order.
pub const HAIR_DIRECTION_NAMES: &[&str] = &["distal", "proximal"];
/// The names `side` accepts, in [`HairSide`] order.
pub const HAIR_SIDE_NAMES: &[&str] = &["left", "right"];

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawHairs {
    links: Option<Spanned<RawHairLinks>>,
    direction: Option<Spanned<String>>,
    side: Option<Spanned<String>>,
    length_m: Option<Spanned<f64>>,
    open_angle_deg: Option<Spanned<f64>>,
    pivot_from_distal_end_m: Option<Spanned<f64>>,
    lateral_offset_m: Option<Spanned<f64>>,
    preload_n_m: Option<Spanned<f64>>,
    stiffness_n_m_per_rad: Option<Spanned<f64>>,
    root_stiffness_n_m_per_rad: Option<Spanned<f64>>,
}

/// `links`: `"all"` or a list of link numbers.
#[derive(Debug)]
enum RawHairLinks {
    All,
    List(Vec<i64>),
}

impl<'de> Deserialize<'de> for RawHairLinks {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct LinksVisitor;
        impl<'de> Visitor<'de> for LinksVisitor {
            type Value = RawHairLinks;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                write!(f, "\"all\" or a list of flagellar link numbers (1..n)")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<RawHairLinks, E> {
                if v == "all" {
                    Ok(RawHairLinks::All)
                } else {
                    Err(E::invalid_value(de::Unexpected::Str(v), &self))
                }
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<RawHairLinks, A::Error> {
                let mut links = Vec::new();
                while let Some(l) = seq.next_element::<i64>()? {
                    links.push(l);
                }
                Ok(RawHairLinks::List(links))
            }
        }
        deserializer.deserialize_any(LinksVisitor)
    }
}

/// A validated `[antenna.hairs]` table: which links carry a hair and the hair's parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct HairSpec {
    /// The flagellar links carrying a hair (`1..=n`, increasing).
    pub links: Vec<usize>,
    /// The hair (its `pivot_from_distal_end_m` applies only when `pivot_given`).
    pub hair: Hair,
    /// Whether `pivot_from_distal_end_m` was given; otherwise each hair pivots at the middle
    /// of its own link.
    pub pivot_given: bool,
}

impl HairSpec {
    /// The hair of each link in [`Self::links`], for links of `link_lengths_m` (`n + 1`
    /// entries).
    pub fn hairs(&self, link_lengths_m: &[f64]) -> Vec<(usize, Hair)> {
        self.links
            .iter()
            .map(|&link| {
                let mut hair = self.hair;
                if !self.pivot_given {
                    hair.pivot_from_distal_end_m =
                        0.5 * link_lengths_m.get(link).copied().unwrap_or_default();
                }
                (link, hair)
            })
            .collect()
    }

    /// The same hairs on other links.
    pub fn on_links(&self, links: Vec<usize>) -> HairSpec {
        HairSpec {
            links,
            ..self.clone()
        }
    }
}

impl RawHairs {
    pub(crate) fn validate(
        &self,
        source: &Source<'_>,
        table_span: Range<usize>,
        link_lengths_m: &[f64],
    ) -> Result<HairSpec, SceneError> {
        let n = link_lengths_m.len() - 1;
        let links: Vec<usize> = match &self.links {
            None => (1..=n).collect(),
            Some(spanned) => match spanned.get_ref() {
                RawHairLinks::All => (1..=n).collect(),
                RawHairLinks::List(list) => {
                    let mut links = Vec::with_capacity(list.len());
                    for &l in list {
                        let link = usize::try_from(l)
                            .ok()
                            .filter(|l| (1..=n).contains(l))
                            .ok_or_else(|| {
                                source.invalid(
                                    spanned.span(),
                                    HAIRS,
                                    "links",
                                    format!(
                                        "link {l} is not a flagellar link (1..={n}; the base \
                                         link 0 carries no hair)"
                                    ),
                                )
                            })?;
                        if links.contains(&link) {
                            return Err(source.invalid(
                                spanned.span(),
                                HAIRS,
                                "links",
                                format!("link {link} is listed twice"),
                            ));
                        }
                        links.push(link);
                    }
                    links.sort_unstable();
                    links
                }
            },
        };
        let mut hair = Hair::seed(link_lengths_m.get(1).copied().unwrap_or_default());
        if let Some(d) = &self.direction {
            hair.direction = match one_of(source, HAIRS, "direction", d, HAIR_DIRECTION_NAMES)? {
                0 => HairDirection::Distal,
                _ => HairDirection::Proximal,
            };
        }
        if let Some(s) = &self.side {
            hair.side = match one_of(source, HAIRS, "side", s, HAIR_SIDE_NAMES)? {
                0 => HairSide::Left,
                _ => HairSide::Right,
            };
        }
        if let Some(v) = &self.length_m {
            hair.length_m = positive(source, HAIRS, "length_m", v)?;
        }
        if let Some(v) = &self.open_angle_deg {
            let deg = positive(source, HAIRS, "open_angle_deg", v)?;
            if deg >= 180.0 {
                return Err(source.invalid(
                    v.span(),
                    HAIRS,
                    "open_angle_deg",
                    format!("{deg} must be below 180"),
                ));
            }
            hair.open_angle_rad = deg.to_radians();
        }
        if let Some(v) = &self.lateral_offset_m {
            hair.lateral_offset_m = non_negative(source, HAIRS, "lateral_offset_m", v)?;
        }
        if let Some(v) = &self.preload_n_m {
            hair.preload_nm = non_negative(source, HAIRS, "preload_n_m", v)?;
        }
        if let Some(v) = &self.stiffness_n_m_per_rad {
            hair.stiffness_nm_per_rad = non_negative(source, HAIRS, "stiffness_n_m_per_rad", v)?;
        }
        if let Some(v) = &self.root_stiffness_n_m_per_rad {
            hair.root_stiffness_nm_per_rad =
                Some(positive(source, HAIRS, "root_stiffness_n_m_per_rad", v)?);
        }
        let pivot_given = self.pivot_from_distal_end_m.is_some();
        if let Some(v) = &self.pivot_from_distal_end_m {
            let d = non_negative(source, HAIRS, "pivot_from_distal_end_m", v)?;
            if let Some(&link) = links.iter().find(|&&l| d > link_lengths_m[l]) {
                return Err(source.invalid(
                    v.span(),
                    HAIRS,
                    "pivot_from_distal_end_m",
                    format!(
                        "{d} m is beyond the proximal end of link {link} ({} m long)",
                        link_lengths_m[link]
                    ),
                ));
            }
            hair.pivot_from_distal_end_m = d;
        }
        if links.is_empty() {
            return Err(source.invalid(
                self.links.as_ref().map_or(table_span, Spanned::span),
                HAIRS,
                "links",
                "no link listed: remove the table for an antenna without hairs",
            ));
        }
        Ok(HairSpec {
            links,
            hair,
            pivot_given,
        })
    }
}
