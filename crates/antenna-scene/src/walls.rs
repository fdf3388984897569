//! `[[walls]]` (any number, wall 0 first) with their `[[walls.zones]]`: a line, a polyline
//! (the thesis's trapezoid; its vertices in `vertices_m` or, digitized, in a `points_file`) or a
//! sinusoid, solid on one side, with a surface or surface zones (docs/model.md 6).

use std::ops::Range;
use std::path::Path;

use nalgebra::Vector2;
use serde::Deserialize;
use sim_core::{Line, Polyline, Sinusoid, SolidSide, SurfaceMap, Wall, WallError, ZoneAxis};
use toml::Spanned;

use super::points_file::read_polyline;
use super::source::{
    Source, finite, non_negative, not_for, one_of, point, positive, wall_table, zone_table,
};
use super::surface::RawSurfaceKeys;
use crate::error::{SceneError, SceneErrorKind};

/// The names `shape` accepts.
pub const WALL_SHAPE_NAMES: &[&str] = &["line", "polyline", "sinusoid"];
/// The names `solid` accepts.
pub const SOLID_SIDE_NAMES: &[&str] = &["left", "right"];
/// The names `zones_along` accepts.
pub const ZONE_AXIS_NAMES: &[&str] = &["arclength", "x"];

/// The keys each shape takes, in [`WALL_SHAPE_NAMES`] order.
const SHAPE_KEYS: [&[&str]; 3] = [
    &["point_m", "angle_deg"],
    &["vertices_m", "points_file"],
    &[
        "point_m",
        "angle_deg",
        "amplitude_m",
        "frequency_per_m",
        "phase_deg",
    ],
];

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawWall {
    shape: Option<Spanned<String>>,
    solid: Option<Spanned<String>>,
    point_m: Option<Spanned<Vec<f64>>>,
    angle_deg: Option<Spanned<f64>>,
    vertices_m: Option<Spanned<Vec<Vec<f64>>>>,
    points_file: Option<Spanned<String>>,
    amplitude_m: Option<Spanned<f64>>,
    frequency_per_m: Option<Spanned<f64>>,
    phase_deg: Option<Spanned<f64>>,
    surface: Option<Spanned<String>>,
    mu: Option<Spanned<f64>>,
    hold_shear_n: Option<Spanned<f64>>,
    hold_tension_n: Option<Spanned<f64>>,
    zones_along: Option<Spanned<String>>,
    zones: Option<Vec<Spanned<RawZone>>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawZone {
    from_m: Option<Spanned<f64>>,
    surface: Option<Spanned<String>>,
    mu: Option<Spanned<f64>>,
    hold_shear_n: Option<Spanned<f64>>,
    hold_tension_n: Option<Spanned<f64>>,
}

impl RawWall {
    /// The wall numbered `index` (0-based, file order); a `points_file` is resolved against
    /// `folder` (the scene file's).
    pub(crate) fn validate(
        &self,
        source: &Source<'_>,
        index: usize,
        span: Range<usize>,
        folder: &Path,
    ) -> Result<Wall, SceneError> {
        let table = wall_table(index);
        let table = table.as_str();
        let Some(shape) = &self.shape else {
            return Err(source.missing(span, table, "shape"));
        };
        let shape_index = one_of(source, table, "shape", shape, WALL_SHAPE_NAMES)?;
        let shape_name = WALL_SHAPE_NAMES[shape_index];
        let takes = SHAPE_KEYS[shape_index];
        let shape_keys: [(&str, Option<Range<usize>>); 7] = [
            ("point_m", self.point_m.as_ref().map(Spanned::span)),
            ("angle_deg", self.angle_deg.as_ref().map(Spanned::span)),
            ("vertices_m", self.vertices_m.as_ref().map(Spanned::span)),
            ("points_file", self.points_file.as_ref().map(Spanned::span)),
            ("amplitude_m", self.amplitude_m.as_ref().map(Spanned::span)),
            (
                "frequency_per_m",
                self.frequency_per_m.as_ref().map(Spanned::span),
            ),
            ("phase_deg", self.phase_deg.as_ref().map(Spanned::span)),
        ];
        for (key, at) in shape_keys {
            if let Some(at) = at
                && !takes.contains(&key)
            {
                return Err(not_for(
                    source,
                    at,
                    table,
                    key,
                    &format!("a {shape_name} wall"),
                    takes,
                ));
            }
        }
        let Some(solid) = &self.solid else {
            return Err(source.missing(span, table, "solid"));
        };
        let solid = match one_of(source, table, "solid", solid, SOLID_SIDE_NAMES)? {
            0 => SolidSide::Left,
            _ => SolidSide::Right,
        };
        let required_point = || match &self.point_m {
            Some(p) => point(source, table, "point_m", p),
            None => Err(source.missing(span.clone(), table, "point_m")),
        };
        let angle_rad = match &self.angle_deg {
            Some(a) => finite(source, table, "angle_deg", a)?.to_radians(),
            None => 0.0,
        };
        let geometry_error = |key: &str, at: Range<usize>, e: WallError| {
            source.invalid(at, table, key, e.to_string())
        };
        let shape: sim_core::WallShape = match shape_index {
            0 => Line::new(required_point()?, angle_rad, solid)
                .map_err(|e| geometry_error("point_m", span.clone(), e))?
                .into(),
            1 => match (&self.vertices_m, &self.points_file) {
                (Some(list), None) => {
                    let mut vertices = Vec::with_capacity(list.get_ref().len());
                    for (i, v) in list.get_ref().iter().enumerate() {
                        let ok = v.len() == 2 && v.iter().all(|x| x.is_finite());
                        if !ok {
                            return Err(source.invalid(
                                list.span(),
                                table,
                                "vertices_m",
                                format!(
                                    "vertex #{} is {v:?}; every vertex is [x, y] in finite metres",
                                    i + 1
                                ),
                            ));
                        }
                        vertices.push(Vector2::new(v[0], v[1]));
                    }
                    Polyline::new(vertices, solid)
                        .map_err(|e| geometry_error("vertices_m", list.span(), e))?
                        .into()
                }
                (None, Some(file)) => read_polyline(&folder.join(file.get_ref()), solid)
                    .map_err(|error| {
                        source.error(
                            Some(file.span()),
                            SceneErrorKind::PointsFile {
                                key: "points_file".to_string(),
                                table: table.to_string(),
                                error,
                            },
                        )
                    })?
                    .into(),
                (Some(list), Some(file)) => {
                    // Report the later of the two in the file.
                    let (key, other, at) = if file.span().start > list.span().start {
                        ("points_file", "vertices_m", file.span())
                    } else {
                        ("vertices_m", "points_file", list.span())
                    };
                    return Err(source.error(
                        Some(at),
                        SceneErrorKind::Conflict {
                            key: key.to_string(),
                            other: other.to_string(),
                            table: table.to_string(),
                        },
                    ));
                }
                (None, None) => {
                    return Err(source.error(
                        Some(span),
                        SceneErrorKind::MissingKey {
                            key: "vertices_m` or `points_file".to_string(),
                            table: table.to_string(),
                        },
                    ));
                }
            },
            _ => {
                let baseline = required_point()?;
                let amplitude_m = match &self.amplitude_m {
                    Some(a) => non_negative(source, table, "amplitude_m", a)?,
                    None => return Err(source.missing(span, table, "amplitude_m")),
                };
                let frequency_per_m = match &self.frequency_per_m {
                    Some(f) => positive(source, table, "frequency_per_m", f)?,
                    None => return Err(source.missing(span, table, "frequency_per_m")),
                };
                let phase_rad = match &self.phase_deg {
                    Some(p) => finite(source, table, "phase_deg", p)?.to_radians(),
                    None => 0.0,
                };
                Sinusoid::new(
                    baseline,
                    angle_rad,
                    amplitude_m,
                    frequency_per_m,
                    phase_rad,
                    solid,
                )
                .map_err(|e| geometry_error("amplitude_m", span.clone(), e))?
                .into()
            }
        };
        let first = RawSurfaceKeys {
            surface: self.surface.as_ref(),
            mu: self.mu.as_ref(),
            hold_shear_n: self.hold_shear_n.as_ref(),
            hold_tension_n: self.hold_tension_n.as_ref(),
        }
        .validate(source, table, span.clone())?;
        let axis = match &self.zones_along {
            Some(a) => match one_of(source, table, "zones_along", a, ZONE_AXIS_NAMES)? {
                0 => ZoneAxis::Arclength,
                _ => ZoneAxis::WorldX,
            },
            None => ZoneAxis::Arclength,
        };
        let mut boundaries: Vec<(f64, sim_core::Surface)> = Vec::new();
        for (z, zone) in self.zones.iter().flatten().enumerate() {
            let zone_label = zone_table(index, z);
            let zt = zone_label.as_str();
            let raw = zone.get_ref();
            let Some(from) = &raw.from_m else {
                return Err(source.missing(zone.span(), zt, "from_m"));
            };
            let from_m = finite(source, zt, "from_m", from)?;
            if let Some(&(previous_m, _)) = boundaries.last()
                && from_m <= previous_m
            {
                return Err(source.invalid(
                    from.span(),
                    zt,
                    "from_m",
                    format!(
                        "{from_m} does not exceed the previous zone's from_m ({previous_m}); \
                         zones go in increasing order"
                    ),
                ));
            }
            let surface = RawSurfaceKeys {
                surface: raw.surface.as_ref(),
                mu: raw.mu.as_ref(),
                hold_shear_n: raw.hold_shear_n.as_ref(),
                hold_tension_n: raw.hold_tension_n.as_ref(),
            }
            .validate(source, zt, zone.span())?;
            boundaries.push((from_m, surface));
        }
        let surfaces = SurfaceMap::zoned(axis, first, boundaries)
            .map_err(|e| source.invalid(span.clone(), table, "zones", e.to_string()))?;
        Ok(Wall { shape, surfaces })
    }
}
