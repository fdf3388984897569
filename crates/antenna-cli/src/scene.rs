//! Scene files: the TOML description of one antenna, its base, and what acts on it
//! (`shared/spec/scene-format.md`), parsed with serde and validated into a [`Scene`].
//!
//! Every error names the file, the key and, where the parser knows it, the line and column;
//! see [`SceneError`]. Unknown keys are errors that list the keys allowed in their table.
//!
//! ```
//! use antenna_cli::scene::{Scene, Start};
//!
//! let text = r#"
//! [antenna]
//! links = 9
//! link_length_m = 0.04
//! base_angle_deg = 30.0
//! joint_limits_deg = [-90.0, 90.0]
//!
//! [antenna.stiffness]
//! profile = "fast-exponential"
//! min_n_m_per_rad = 0.004
//! max_n_m_per_rad = 0.082
//!
//! [tip_pin]
//! position_m = [0.26, 0.10]
//!
//! [solver]
//! initial = "C"
//! "#;
//! let scene = Scene::parse(text, "scene.toml").unwrap();
//! assert_eq!(scene.chain.n(), 8); // 9 links = base link + 8 flexible joints
//! assert_eq!(scene.solver.initial, Start::C);
//!
//! let error = Scene::parse("[antenna]\nlinks = 9\nfoo = 1\n", "scene.toml").unwrap_err();
//! assert!(error.to_string().starts_with("scene.toml:3:1: unknown key `foo` in [antenna]; allowed: links,"));
//! ```

use std::fmt;
use std::ops::Range;
use std::path::Path;

use nalgebra::Vector2;
use serde::Deserialize;
use serde::de::{self, Deserializer, SeqAccess, Visitor};
use sim_core::{Chain, JointLimit, StiffnessProfile};
use toml::Spanned;

use crate::error::{Location, SceneError, SceneErrorKind};

/// Keys allowed at the top level of a scene file.
pub const TOP_LEVEL_KEYS: &[&str] = &["antenna", "base", "tip_load", "tip_pin", "solver"];
/// Keys allowed in `[antenna]`.
pub const ANTENNA_KEYS: &[&str] = &[
    "links",
    "link_length_m",
    "link_lengths_m",
    "base_angle_deg",
    "joint_limits_deg",
    "rest_angles_deg",
    "stiffness",
];
/// Keys allowed in `[antenna.stiffness]`.
pub const STIFFNESS_KEYS: &[&str] = &[
    "profile",
    "min_n_m_per_rad",
    "max_n_m_per_rad",
    "values_n_m_per_rad",
];
/// Keys allowed in `[base]`.
pub const BASE_KEYS: &[&str] = &["position_m"];
/// Keys allowed in `[tip_load]`.
pub const TIP_LOAD_KEYS: &[&str] = &["force_n"];
/// Keys allowed in `[tip_pin]`.
pub const TIP_PIN_KEYS: &[&str] = &["position_m"];
/// Keys allowed in `[solver]`.
pub const SOLVER_KEYS: &[&str] = &["tolerance", "max_iterations", "initial"];

/// Every table with its allowed keys, for naming the table of an unknown key.
const TABLES: &[(&str, &[&str])] = &[
    ("the top level", TOP_LEVEL_KEYS),
    ("[antenna]", ANTENNA_KEYS),
    ("[antenna.stiffness]", STIFFNESS_KEYS),
    ("[base]", BASE_KEYS),
    ("[tip_load]", TIP_LOAD_KEYS),
    ("[tip_pin]", TIP_PIN_KEYS),
    ("[solver]", SOLVER_KEYS),
];

/// Joint limits used when `joint_limits_deg` is absent, degrees.
pub const DEFAULT_JOINT_LIMITS_DEG: [f64; 2] = [-90.0, 90.0];
/// Most links a scene may have.
pub const MAX_LINKS: usize = 100_000;

/// The names `initial` accepts (besides a list of angles).
pub const START_NAMES: &[&str] = &["straight", "C", "S", "mirror-C", "mirror-S"];

/// Where the solver starts (`[solver] initial`).
#[derive(Debug, Clone, PartialEq)]
pub enum Start {
    /// `"straight"`: every flexible joint at its rest angle (clamped into its limits).
    Straight,
    /// `"C"`: every flexible joint bent the same way.
    C,
    /// `"S"`: the first half bent one way, the rest the other.
    S,
    /// `"mirror-C"`: the C start with every flexible joint's sign flipped.
    MirrorC,
    /// `"mirror-S"`: the S start with every flexible joint's sign flipped.
    MirrorS,
    /// A list of `n` flexible joint angles (`theta_1..theta_n`), converted to radians.
    AnglesRad(Vec<f64>),
}

/// How the joint stiffnesses were given.
#[derive(Debug, Clone, PartialEq)]
pub enum StiffnessSpec {
    /// A named profile normalized to `[min, max]` over the joints.
    Profile {
        /// The profile.
        profile: StiffnessProfile,
        /// `min_n_m_per_rad`.
        min_n_m_per_rad: f64,
        /// `max_n_m_per_rad`.
        max_n_m_per_rad: f64,
    },
    /// `values_n_m_per_rad`, one per flexible joint.
    Values,
}

/// The `[solver]` table.
#[derive(Debug, Clone, PartialEq)]
pub struct SolverSettings {
    /// `tolerance` on the KKT residual (`None`: the solver's default).
    pub tolerance: Option<f64>,
    /// `max_iterations` (`None`: the solver's default).
    pub max_iterations: Option<usize>,
    /// `initial` (default [`Start::Straight`]).
    pub initial: Start,
}

/// A validated scene.
#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    /// The chain: `links - 1` flexible joints, lengths, base angle, limits, stiffness, rest
    /// angles (sim-core works relative to the base attachment point).
    pub chain: Chain,
    /// How the stiffness was given (the values are in `chain`).
    pub stiffness: StiffnessSpec,
    /// `[base] position_m`: the attachment point in the ground frame, m.
    pub base_position_m: Vector2<f64>,
    /// `[tip_load] force_n`: dead load at the tip, ground frame, N (zero when absent).
    pub tip_force_n: Vector2<f64>,
    /// `[tip_pin] position_m`: the pin in the ground frame (not relative to the base), m.
    pub tip_pin_m: Option<Vector2<f64>>,
    /// `[solver]`.
    pub solver: SolverSettings,
    /// Where some keys are in the file, for errors found only when solving.
    pub locations: SceneLocations,
}

/// Where keys whose trouble shows only when solving sit in the file.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SceneLocations {
    /// `[tip_pin] position_m` (an unreachable pin).
    pub tip_pin_position_m: Option<Location>,
    /// `[solver] initial`.
    pub solver_initial: Option<Location>,
}

impl Scene {
    /// Reads and validates a scene file; errors carry `path` as given.
    ///
    /// # Errors
    /// [`SceneError`] when the file cannot be read or is not a valid scene.
    pub fn from_path(path: &Path) -> Result<Scene, SceneError> {
        let label = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| SceneError {
            path: label.clone(),
            location: None,
            kind: Box::new(SceneErrorKind::Io(e)),
        })?;
        Scene::parse(&text, &label)
    }

    /// Parses and validates scene text; `path` is only used in error messages.
    ///
    /// # Errors
    /// [`SceneError`] naming the key and, where known, its line and column.
    pub fn parse(text: &str, path: &str) -> Result<Scene, SceneError> {
        let source = Source { text, path };
        let raw: RawScene = toml::from_str(text).map_err(|e| source.toml_error(&e))?;
        raw.validate(&source)
    }

    /// Number of flexible joints `n` (`links - 1`).
    pub fn n(&self) -> usize {
        self.chain.n()
    }

    /// The pin relative to the base attachment point (what sim-core takes), m.
    pub fn tip_pin_relative_m(&self) -> Option<Vector2<f64>> {
        self.tip_pin_m.map(|p| p - self.base_position_m)
    }
}

// ---------------------------------------------------------------------------------------
// Raw serde model: exactly the keys of scene-format.md.

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    antenna: Spanned<RawAntenna>,
    base: Option<RawBase>,
    tip_load: Option<RawTipLoad>,
    tip_pin: Option<RawTipPin>,
    solver: Option<RawSolver>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawAntenna {
    links: Spanned<i64>,
    link_length_m: Option<Spanned<f64>>,
    link_lengths_m: Option<Spanned<Vec<f64>>>,
    base_angle_deg: Option<Spanned<f64>>,
    joint_limits_deg: Option<Spanned<Vec<f64>>>,
    rest_angles_deg: Option<Spanned<Vec<f64>>>,
    stiffness: Option<Spanned<RawStiffness>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawStiffness {
    profile: Option<Spanned<String>>,
    min_n_m_per_rad: Option<Spanned<f64>>,
    max_n_m_per_rad: Option<Spanned<f64>>,
    values_n_m_per_rad: Option<Spanned<Vec<f64>>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBase {
    position_m: Option<Spanned<Vec<f64>>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTipLoad {
    force_n: Spanned<Vec<f64>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTipPin {
    position_m: Spanned<Vec<f64>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSolver {
    tolerance: Option<Spanned<f64>>,
    max_iterations: Option<Spanned<i64>>,
    initial: Option<Spanned<RawInitial>>,
}

/// `initial`: a name or a list of angles in degrees.
#[derive(Debug)]
enum RawInitial {
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
// Errors with locations.

/// The scene text and its name, for turning spans into located errors.
struct Source<'a> {
    text: &'a str,
    path: &'a str,
}

impl Source<'_> {
    fn at(&self, span: Range<usize>) -> Option<Location> {
        Some(Location::of_offset(self.text, span.start))
    }

    fn error(&self, span: Option<Range<usize>>, kind: SceneErrorKind) -> SceneError {
        SceneError {
            path: self.path.to_string(),
            location: span.and_then(|s| self.at(s)),
            kind: Box::new(kind),
        }
    }

    fn invalid(
        &self,
        span: Range<usize>,
        table: &str,
        key: &str,
        reason: impl Into<String>,
    ) -> SceneError {
        self.error(
            Some(span),
            SceneErrorKind::Invalid {
                key: key.to_string(),
                table: table.to_string(),
                reason: reason.into(),
            },
        )
    }

    /// Turns a TOML/serde error into a located scene error naming the key.
    fn toml_error(&self, e: &toml::de::Error) -> SceneError {
        let span = e.span();
        let offset = span.as_ref().map_or(0, |s| s.start);
        let message = e.message().trim().to_string();
        if let Some(rest) = message.strip_prefix("unknown field `") {
            let names = backticked(rest);
            let key = rest.split('`').next().unwrap_or_default().to_string();
            let allowed: Vec<String> = names.into_iter().collect();
            let table = table_with_keys(&allowed)
                .map_or_else(|| table_at(self.text, offset), str::to_string);
            return self.error(
                span,
                SceneErrorKind::UnknownKey {
                    key,
                    table,
                    allowed,
                },
            );
        }
        if let Some(rest) = message.strip_prefix("missing field `") {
            let key = rest.split('`').next().unwrap_or_default().to_string();
            let owners: Vec<&str> = TABLES
                .iter()
                .filter(|(_, keys)| keys.contains(&key.as_str()))
                .map(|(t, _)| *t)
                .collect();
            let table = match owners.as_slice() {
                [only] => (*only).to_string(),
                _ => table_at(self.text, offset),
            };
            return self.error(span, SceneErrorKind::MissingKey { key, table });
        }
        let message = match key_at(self.text, offset) {
            Some(key) => format!("`{key}` in {}: {message}", table_at(self.text, offset)),
            None => message,
        };
        self.error(span, SceneErrorKind::Syntax { message })
    }
}

/// The names between backticks in `text` after its first backticked name.
fn backticked(text: &str) -> Vec<String> {
    // `text` starts just after the first opening backtick: "foo`, expected one of `a`, `b`".
    text.split('`')
        .skip(1)
        .enumerate()
        .filter(|(i, _)| i % 2 == 1)
        .map(|(_, s)| s.to_string())
        .collect()
}

/// The table whose allowed keys are exactly `keys`, if exactly one is.
fn table_with_keys(keys: &[String]) -> Option<&'static str> {
    let mut found = TABLES.iter().filter(|(_, allowed)| {
        allowed.len() == keys.len() && allowed.iter().all(|a| keys.iter().any(|k| k == a))
    });
    match (found.next(), found.next()) {
        (Some((table, _)), None) => Some(table),
        _ => None,
    }
}

/// The table header in force at byte `offset` (`[name]`), or `the top level`.
fn table_at(text: &str, offset: usize) -> String {
    let offset = offset.min(text.len());
    let line_start = text[..offset].rfind('\n').map_or(0, |i| i + 1);
    text[..line_start]
        .lines()
        .rev()
        .map(str::trim)
        .find(|l| l.starts_with('['))
        .and_then(|l| {
            let inner = l.trim_start_matches('[');
            inner
                .find(']')
                .map(|end| format!("[{}]", inner[..end].trim()))
        })
        .unwrap_or_else(|| "the top level".to_string())
}

/// The key of the `key = value` line holding byte `offset`, when `offset` is in the value.
fn key_at(text: &str, offset: usize) -> Option<String> {
    let offset = offset.min(text.len());
    let line_start = text[..offset].rfind('\n').map_or(0, |i| i + 1);
    let before = &text[line_start..offset];
    let (key, _) = before.split_once('=')?;
    let key = key.trim().trim_matches('"');
    let plain = !key.is_empty()
        && key
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'));
    plain.then(|| key.to_string())
}

fn quoted_list(names: &[&str]) -> String {
    names
        .iter()
        .map(|n| format!("\"{n}\""))
        .collect::<Vec<_>>()
        .join(", ")
}

// ---------------------------------------------------------------------------------------
// Validation.

const ANTENNA: &str = "[antenna]";
const STIFFNESS: &str = "[antenna.stiffness]";
const SOLVER: &str = "[solver]";

/// Checks that every value of a list is finite; returns the list.
fn finite_list(
    source: &Source<'_>,
    table: &str,
    key: &str,
    list: &Spanned<Vec<f64>>,
) -> Result<Vec<f64>, SceneError> {
    if let Some((i, v)) = list
        .get_ref()
        .iter()
        .enumerate()
        .find(|(_, v)| !v.is_finite())
    {
        return Err(source.invalid(
            list.span(),
            table,
            key,
            format!(
                "value #{} is {v}; every value must be a finite number",
                i + 1
            ),
        ));
    }
    Ok(list.get_ref().clone())
}

/// A finite list of exactly `len` values, `what` saying what each value is for.
fn list_of_len(
    source: &Source<'_>,
    table: &str,
    key: &str,
    list: &Spanned<Vec<f64>>,
    len: usize,
    what: &str,
) -> Result<Vec<f64>, SceneError> {
    let found = list.get_ref().len();
    if found != len {
        return Err(source.invalid(
            list.span(),
            table,
            key,
            format!("has {found} value(s); expected {len} ({what})"),
        ));
    }
    finite_list(source, table, key, list)
}

fn point(
    source: &Source<'_>,
    table: &str,
    key: &str,
    list: &Spanned<Vec<f64>>,
) -> Result<Vector2<f64>, SceneError> {
    let v = list_of_len(source, table, key, list, 2, "[x, y]")?;
    Ok(Vector2::new(v[0], v[1]))
}

fn finite(
    source: &Source<'_>,
    table: &str,
    key: &str,
    value: &Spanned<f64>,
) -> Result<f64, SceneError> {
    let v = *value.get_ref();
    if v.is_finite() {
        Ok(v)
    } else {
        Err(source.invalid(
            value.span(),
            table,
            key,
            format!("{v} is not a finite number"),
        ))
    }
}

fn positive(
    source: &Source<'_>,
    table: &str,
    key: &str,
    value: &Spanned<f64>,
) -> Result<f64, SceneError> {
    let v = finite(source, table, key, value)?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(source.invalid(value.span(), table, key, format!("{v} must be > 0")))
    }
}

impl RawScene {
    fn validate(self, source: &Source<'_>) -> Result<Scene, SceneError> {
        let antenna_span = self.antenna.span();
        let antenna = self.antenna.into_inner();

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
                    Some(antenna_span),
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
                Some(antenna_span),
                SceneErrorKind::MissingKey {
                    key: "stiffness".to_string(),
                    table: ANTENNA.to_string(),
                },
            ));
        };
        let (spec, k) = stiffness_values(source, stiffness, &link_lengths_m)?;

        let chain = Chain::builder(n)
            .link_lengths_m(link_lengths_m)
            .base_angle_rad(base_angle_deg.to_radians())
            .joint_limit(limit)
            .stiffnesses_nm_per_rad(k)
            .rest_angles_rad(rest_angles_rad)
            .build()
            .map_err(|e| source.invalid(antenna_span.clone(), ANTENNA, "antenna", e.to_string()))?;

        let base_position_m = match self.base.as_ref().and_then(|b| b.position_m.as_ref()) {
            Some(p) => point(source, "[base]", "position_m", p)?,
            None => Vector2::zeros(),
        };
        let tip_force_n = match &self.tip_load {
            Some(load) => point(source, "[tip_load]", "force_n", &load.force_n)?,
            None => Vector2::zeros(),
        };
        let tip_pin_m = match &self.tip_pin {
            Some(pin) => {
                let p = point(source, "[tip_pin]", "position_m", &pin.position_m)?;
                check_reach(source, &chain, base_position_m, p, pin.position_m.span())?;
                Some(p)
            }
            None => None,
        };

        let solver = match &self.solver {
            Some(raw) => raw.validate(source, &chain)?,
            None => SolverSettings {
                tolerance: None,
                max_iterations: None,
                initial: Start::Straight,
            },
        };

        let locations = SceneLocations {
            tip_pin_position_m: self
                .tip_pin
                .as_ref()
                .and_then(|p| source.at(p.position_m.span())),
            solver_initial: self
                .solver
                .as_ref()
                .and_then(|s| s.initial.as_ref())
                .and_then(|i| source.at(i.span())),
        };
        Ok(Scene {
            chain,
            stiffness: spec,
            base_position_m,
            tip_force_n,
            tip_pin_m,
            solver,
            locations,
        })
    }
}

/// A pin farther from the end of the base link than the flagellum's length cannot be reached.
fn check_reach(
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

impl RawSolver {
    fn validate(&self, source: &Source<'_>, chain: &Chain) -> Result<SolverSettings, SceneError> {
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

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = r#"
[antenna]
links = 9
link_length_m = 0.04
base_angle_deg = 30.0

[antenna.stiffness]
profile = "linear"
min_n_m_per_rad = 0.004
max_n_m_per_rad = 0.082
"#;

    fn err(text: &str) -> String {
        match Scene::parse(text, "s.toml") {
            Ok(_) => panic!("parsed: {text}"),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn good_scene_builds_the_chain() {
        let scene = Scene::parse(GOOD, "s.toml").unwrap();
        assert_eq!(scene.n(), 8);
        let k = scene.chain.stiffness_nm_per_rad();
        assert_eq!(k.len(), 9);
        assert!((k[1] - 0.082).abs() < 1e-15 && (k[8] - 0.004).abs() < 1e-15);
        assert_eq!(scene.solver.initial, Start::Straight);
        assert_eq!(scene.tip_pin_m, None);
    }

    #[test]
    fn unknown_keys_name_key_place_and_allowed_keys() {
        let e = err(&format!("{GOOD}[solver]\nfoo = 2\n"));
        assert!(e.starts_with("s.toml:12:1: unknown key `foo` in [solver]; allowed: tolerance, max_iterations, initial"), "{e}");
        let e = err(&format!("{GOOD}[walls]\n"));
        assert!(e.contains("unknown key `walls` in the top level"), "{e}");
        let e = err(&GOOD.replace("profile =", "colour = 1\nprofile ="));
        assert!(
            e.contains(":8:1: unknown key `colour` in [antenna.stiffness]"),
            "{e}"
        );
        let e = err(&format!(
            "{GOOD}[tip_pin]\nposition_m = [0.1, 0.1]\nx = 1\n"
        ));
        assert!(
            e.contains(":13:1: unknown key `x` in [tip_pin]; allowed: position_m"),
            "{e}"
        );
    }

    #[test]
    fn type_errors_name_the_key() {
        let e = err(&GOOD.replace("links = 9", "links = \"nine\""));
        assert!(e.starts_with("s.toml:3:9: `links` in [antenna]:"), "{e}");
    }

    #[test]
    fn semantic_errors_name_the_key() {
        let e = err(&GOOD.replace(
            "link_length_m = 0.04",
            "link_length_m = 0.04\nlink_lengths_m = [0.04]",
        ));
        assert!(
            e.contains(
                "s.toml:5:18: `link_lengths_m` and `link_length_m` in [antenna] exclude each other"
            ),
            "{e}"
        );
        let e = err(&GOOD.replace("link_length_m = 0.04", "link_lengths_m = [0.04, 0.04]"));
        assert!(
            e.contains("`link_lengths_m` in [antenna]: has 2 value(s); expected 9"),
            "{e}"
        );
        let e = err(&GOOD.replace("\"linear\"", "\"lin\""));
        assert!(e.contains("`profile` in [antenna.stiffness]: unknown stiffness profile name \"lin\"; known profiles: constant, linear"), "{e}");
        let e = err(&GOOD.replace("0.082", "0.001"));
        assert!(
            e.contains("s.toml:10:19: `max_n_m_per_rad` in [antenna.stiffness]: 0.001 is below"),
            "{e}"
        );
        let e = err(&GOOD.replace("30.0", "nan"));
        assert!(
            e.contains("s.toml:5:18: `base_angle_deg` in [antenna]: NaN is not a finite number"),
            "{e}"
        );
        let e = err(&GOOD.replace("links = 9", "links = 1"));
        assert!(e.contains("`links` in [antenna]: 1 is out of range"), "{e}");
        let e = err(&format!("{GOOD}[solver]\ninitial = \"Z\"\n"));
        assert!(
            e.contains("s.toml:12:11: `initial` in [solver]: invalid value: string \"Z\""),
            "{e}"
        );
        let e = err(&format!("{GOOD}[solver]\ninitial = [1.0, 2.0]\n"));
        assert!(
            e.contains("`initial` in [solver]: has 2 value(s); expected 8"),
            "{e}"
        );
        let e = err(&format!("{GOOD}[tip_pin]\nposition_m = [1.0, 0.0]\n"));
        assert!(
            e.contains("farther than the flexible links reach (0.320000 m)"),
            "{e}"
        );
    }

    #[test]
    fn missing_keys_are_named() {
        let e = err("[antenna]\nlink_length_m = 0.04\n");
        assert!(e.contains("missing key `links` in [antenna]"), "{e}");
        let e = err(&GOOD.replace("profile = \"linear\"", ""));
        assert!(
            e.contains("missing key `profile` or `values_n_m_per_rad` in [antenna.stiffness]"),
            "{e}"
        );
        let e = err("");
        assert!(e.contains("missing key `antenna` in the top level"), "{e}");
    }

    #[test]
    fn custom_profile_is_a_values_list() {
        let values = "values_n_m_per_rad = [0.05, 0.04, 0.03, 0.02, 0.01, 0.01, 0.01, 0.01]";
        let text = GOOD
            .replace(
                "profile = \"linear\"",
                &format!("profile = \"custom\"\n{values}"),
            )
            .replace("min_n_m_per_rad = 0.004\n", "")
            .replace("max_n_m_per_rad = 0.082\n", "");
        let s = Scene::parse(&text, "s.toml").unwrap();
        assert_eq!(s.stiffness, StiffnessSpec::Values);
        assert_eq!(s.chain.stiffness_nm_per_rad()[1], 0.05);
        let e = err(&GOOD.replace("\"linear\"", "\"custom\""));
        assert!(e.contains("give it as values_n_m_per_rad"), "{e}");
        let e = err(&GOOD.replace("\"linear\"", "\"custom:0.1,0.2\""));
        assert!(e.contains("give it as values_n_m_per_rad"), "{e}");
    }

    #[test]
    fn explicit_values_and_pin_and_start() {
        let text = r#"
[antenna]
links = 3
link_lengths_m = [0.02, 0.03, 0.04]
rest_angles_deg = [10.0, -5.0]
[antenna.stiffness]
values_n_m_per_rad = [0.02, 0.01]
[base]
position_m = [1.0, 2.0]
[tip_pin]
position_m = [1.05, 2.01]
[solver]
initial = [20, -20]
max_iterations = 50
"#;
        let s = Scene::parse(text, "s.toml").unwrap();
        assert_eq!(s.chain.stiffness_nm_per_rad(), &[0.0, 0.02, 0.01]);
        assert_eq!(s.stiffness, StiffnessSpec::Values);
        assert!((s.tip_pin_relative_m().unwrap() - Vector2::new(0.05, 0.01)).norm() < 1e-12);
        match &s.solver.initial {
            Start::AnglesRad(a) => assert!((a[0] - 20f64.to_radians()).abs() < 1e-15),
            other => panic!("{other:?}"),
        }
        assert_eq!(s.solver.max_iterations, Some(50));
    }
}
