//! `[solver]` (the fixed core of docs/scene-format.md): the equilibrium solver's tolerance,
//! iterations and start, for scenes without walls.

use std::fmt;

use serde::Deserialize;
use serde::de::{self, Deserializer, SeqAccess, Visitor};
use sim_core::Chain;
use toml::Spanned;

use super::source::{Source, list_of_len, positive, quoted_list};
use super::{START_NAMES, SolverSettings, Start};
use crate::error::SceneError;

pub(crate) const SOLVER: &str = "[solver]";

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawSolver {
    pub(crate) tolerance: Option<Spanned<f64>>,
    pub(crate) max_iterations: Option<Spanned<i64>>,
    pub(crate) initial: Option<Spanned<RawInitial>>,
}

/// `initial`: a name or a list of angles in degrees.
#[derive(Debug)]
pub(crate) enum RawInitial {
    Name(Start),
    AnglesDeg(Vec<f64>),
}

impl<'de> Deserialize<'de> for RawInitial {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct InitialVisitor;
        impl<'de> Visitor<'de> for InitialVisitor {
            type Value = RawInitial;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                write!(
                    f,
                    "one of {} or a list of joint angles in degrees",
                    quoted_list(START_NAMES)
                )
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<RawInitial, E> {
                let start = match v {
                    "straight" => Start::Straight,
                    "C" => Start::C,
                    "S" => Start::S,
                    "mirror-C" => Start::MirrorC,
                    "mirror-S" => Start::MirrorS,
                    _ => return Err(E::invalid_value(de::Unexpected::Str(v), &self)),
                };
                Ok(RawInitial::Name(start))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<RawInitial, A::Error> {
                let mut angles = Vec::new();
                while let Some(a) = seq.next_element::<f64>()? {
                    angles.push(a);
                }
                Ok(RawInitial::AnglesDeg(angles))
            }
        }
        deserializer.deserialize_any(InitialVisitor)
    }
}

// ---------------------------------------------------------------------------------------

impl RawSolver {
    pub(crate) fn validate(
        &self,
        source: &Source<'_>,
        chain: &Chain,
    ) -> Result<SolverSettings, SceneError> {
        let tolerance = self
            .tolerance
            .as_ref()
            .map(|t| positive(source, SOLVER, "tolerance", t))
            .transpose()?;
        let max_iterations = match &self.max_iterations {
            Some(m) => {
                let v = *m.get_ref();
                let ok = usize::try_from(v).ok().filter(|&v| v >= 1);
                Some(ok.ok_or_else(|| {
                    source.invalid(
                        m.span(),
                        SOLVER,
                        "max_iterations",
                        format!("{v} must be >= 1"),
                    )
                })?)
            }
            None => None,
        };
        let initial = match &self.initial {
            None => Start::Straight,
            Some(spanned) => match spanned.get_ref() {
                RawInitial::Name(start) => start.clone(),
                RawInitial::AnglesDeg(angles) => {
                    let n = chain.n();
                    let list = Spanned::new(spanned.span(), angles.clone());
                    let deg = list_of_len(
                        source,
                        SOLVER,
                        "initial",
                        &list,
                        n,
                        "one angle in degrees per flexible joint, links - 1",
                    )?;
                    let rad: Vec<f64> = deg.iter().map(|d| d.to_radians()).collect();
                    let limits = &chain.joint_limits()[1..];
                    if let Some(i) = (0..n).find(|&i| !limits[i].contains(rad[i])) {
                        return Err(source.invalid(
                            spanned.span(),
                            SOLVER,
                            "initial",
                            format!(
                                "angle #{} = {} deg is outside the joint limits [{}, {}] deg",
                                i + 1,
                                deg[i],
                                limits[i].cw_rad.to_degrees(),
                                limits[i].ccw_rad.to_degrees()
                            ),
                        ));
                    }
                    Start::AnglesRad(rad)
                }
            },
        };
        Ok(SolverSettings {
            tolerance,
            max_iterations,
            initial,
        })
    }
}
