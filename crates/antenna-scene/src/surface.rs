//! The surface keys a `[[walls]]` table and each of its `[[walls.zones]]` share: `surface`
//! (`"smooth"` or `"rough"`), `mu`, and for a rough surface `hold_shear_n` and
//! `hold_tension_n` (docs/model.md 6-7).

use std::ops::Range;

use sim_core::{SMOOTH_MU_DEFAULT, Surface};
use toml::Spanned;

use super::source::{Source, non_negative, not_for, one_of};
use crate::error::SceneError;

/// The names `surface` accepts.
pub const SURFACE_NAMES: &[&str] = &["smooth", "rough"];

/// The surface keys of one table, as written.
pub struct RawSurfaceKeys<'a> {
    /// `surface`: `"smooth"` (the default) or `"rough"`.
    pub surface: Option<&'a Spanned<String>>,
    /// `mu`, the smooth surface's friction coefficient.
    pub mu: Option<&'a Spanned<f64>>,
    /// `hold_shear_n`, a rough surface's holding strength along it.
    pub hold_shear_n: Option<&'a Spanned<f64>>,
    /// `hold_tension_n`, a rough surface's holding strength away from it.
    pub hold_tension_n: Option<&'a Spanned<f64>>,
}

impl RawSurfaceKeys<'_> {
    /// The surface: smooth with `mu` (default 0.3) unless `surface = "rough"`, which needs
    /// both holding strengths.
    pub fn validate(
        &self,
        source: &Source<'_>,
        table: &str,
        table_span: Range<usize>,
    ) -> Result<Surface, SceneError> {
        let rough = match self.surface {
            Some(s) => one_of(source, table, "surface", s, SURFACE_NAMES)? == 1,
            None => false,
        };
        let mu = match self.mu {
            Some(m) => non_negative(source, table, "mu", m)?,
            None => SMOOTH_MU_DEFAULT,
        };
        if !rough {
            for (key, value) in [
                ("hold_shear_n", self.hold_shear_n),
                ("hold_tension_n", self.hold_tension_n),
            ] {
                if let Some(v) = value {
                    return Err(not_for(
                        source,
                        v.span(),
                        table,
                        key,
                        "a smooth surface",
                        &["surface", "mu"],
                    ));
                }
            }
            return Ok(Surface::Smooth { mu });
        }
        let hold = |key: &str, value: Option<&Spanned<f64>>| match value {
            Some(v) => non_negative(source, table, key, v),
            None => Err(source.missing(table_span.clone(), table, key)),
        };
        Ok(Surface::Rough {
            mu,
            hold_shear_n: hold("hold_shear_n", self.hold_shear_n)?,
            hold_tension_n: hold("hold_tension_n", self.hold_tension_n)?,
        })
    }
}
