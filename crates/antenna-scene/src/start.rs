//! `[start]`: how the antenna is put against the walls before a sweep (and before the
//! equilibrium of `antenna solve` on a scene with walls): at rest, at given angles, by an
//! approach, or with the tip placed on a wall (sim-core's [`Placement`]).

use std::ops::Range;

use serde::Deserialize;
use sim_core::Chain;
use sim_core::sweep::{Placement, initial_guess_by_name};
use toml::Spanned;

use super::START_NAMES;
use super::source::{Source, count, finite, list_of_len, non_negative, not_for, one_of};
use crate::error::SceneError;

const START: &str = "[start]";

/// The names `placement` accepts.
pub const PLACEMENT_NAMES: &[&str] = &["rest", "angles", "approach", "tip-on-wall"];
/// The keys each placement takes, in [`PLACEMENT_NAMES`] order.
const PLACEMENT_KEYS: [&[&str]; 4] = [
    &[],
    &["angles_deg"],
    &["wall", "distance_m", "along_m", "steps"],
    &["wall", "ahead_m", "shape"],
];
/// The approach's steps when `steps` is not given.
pub const DEFAULT_APPROACH_STEPS: usize = 100;
/// Most approach steps.
pub const MAX_APPROACH_STEPS: usize = 1_000_000;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawStart {
    placement: Option<Spanned<String>>,
    angles_deg: Option<Spanned<Vec<f64>>>,
    wall: Option<Spanned<i64>>,
    distance_m: Option<Spanned<f64>>,
    along_m: Option<Spanned<f64>>,
    steps: Option<Spanned<i64>>,
    ahead_m: Option<Spanned<f64>>,
    shape: Option<Spanned<String>>,
}

impl RawStart {
    /// Where `placement` is written, if it is.
    pub(crate) fn placement_span(&self) -> Option<Range<usize>> {
        self.placement.as_ref().map(Spanned::span)
    }

    /// The placement for `chain` among `walls` walls; `span` is the table's.
    pub(crate) fn validate(
        &self,
        source: &Source<'_>,
        span: Range<usize>,
        chain: &Chain,
        walls: usize,
    ) -> Result<Placement, SceneError> {
        let which = match &self.placement {
            Some(p) => one_of(source, START, "placement", p, PLACEMENT_NAMES)?,
            None => 0,
        };
        let name = PLACEMENT_NAMES[which];
        let takes = PLACEMENT_KEYS[which];
        let given: [(&str, Option<Range<usize>>); 7] = [
            ("angles_deg", self.angles_deg.as_ref().map(Spanned::span)),
            ("wall", self.wall.as_ref().map(Spanned::span)),
            ("distance_m", self.distance_m.as_ref().map(Spanned::span)),
            ("along_m", self.along_m.as_ref().map(Spanned::span)),
            ("steps", self.steps.as_ref().map(Spanned::span)),
            ("ahead_m", self.ahead_m.as_ref().map(Spanned::span)),
            ("shape", self.shape.as_ref().map(Spanned::span)),
        ];
        for (key, at) in given {
            if let Some(at) = at
                && !takes.contains(&key)
            {
                return Err(not_for(
                    source,
                    at,
                    START,
                    key,
                    &format!("placement \"{name}\""),
                    takes,
                ));
            }
        }
        let wall = || -> Result<usize, SceneError> {
            let (index, at) = match &self.wall {
                Some(w) => (count(source, START, "wall", w, 0, usize::MAX)?, w.span()),
                None => (0, span.clone()),
            };
            if index >= walls {
                let key = if self.wall.is_some() {
                    "wall"
                } else {
                    "placement"
                };
                let at = match (&self.wall, &self.placement) {
                    (None, Some(p)) => p.span(),
                    _ => at,
                };
                return Err(source.invalid(
                    at,
                    START,
                    key,
                    format!(
                        "placement \"{name}\" needs wall {index}, but the scene has {walls} \
                         [[walls]] table(s) (wall 0 is the first)"
                    ),
                ));
            }
            Ok(index)
        };
        Ok(match which {
            0 => Placement::Rest,
            1 => {
                let Some(list) = &self.angles_deg else {
                    return Err(source.missing(span, START, "angles_deg"));
                };
                let n = chain.n();
                let deg = list_of_len(
                    source,
                    START,
                    "angles_deg",
                    list,
                    n,
                    "one angle in degrees per flexible joint, links - 1",
                )?;
                let limits = &chain.joint_limits()[1..];
                let rad: Vec<f64> = deg.iter().map(|d| d.to_radians()).collect();
                if let Some(i) = (0..n).find(|&i| !limits[i].contains(rad[i])) {
                    return Err(source.invalid(
                        list.span(),
                        START,
                        "angles_deg",
                        format!(
                            "angle #{} = {} deg is outside the joint limits [{}, {}] deg",
                            i + 1,
                            deg[i],
                            limits[i].cw_rad.to_degrees(),
                            limits[i].ccw_rad.to_degrees()
                        ),
                    ));
                }
                Placement::Angles(rad)
            }
            2 => {
                let wall = wall()?;
                let Some(distance) = &self.distance_m else {
                    return Err(source.missing(span, START, "distance_m"));
                };
                let distance_m = non_negative(source, START, "distance_m", distance)?;
                let steps = match &self.steps {
                    Some(s) => count(source, START, "steps", s, 1, MAX_APPROACH_STEPS)?,
                    None => DEFAULT_APPROACH_STEPS,
                };
                let along_m = match &self.along_m {
                    Some(a) => finite(source, START, "along_m", a)?,
                    None => 0.0,
                };
                Placement::Approach {
                    wall,
                    distance_m,
                    along_m,
                    steps,
                }
            }
            _ => {
                let wall = wall()?;
                let ahead_m = match &self.ahead_m {
                    Some(a) => finite(source, START, "ahead_m", a)?,
                    None => 0.0,
                };
                let start = match &self.shape {
                    Some(s) => {
                        let i = one_of(source, START, "shape", s, START_NAMES)?;
                        initial_guess_by_name(START_NAMES[i])
                    }
                    None => initial_guess_by_name("C"),
                };
                let Some(start) = start else {
                    return Err(source.invalid(
                        span,
                        START,
                        "shape",
                        "sim-core does not know this start",
                    ));
                };
                Placement::TipOnWall {
                    wall,
                    ahead_m,
                    start,
                }
            }
        })
    }
}
