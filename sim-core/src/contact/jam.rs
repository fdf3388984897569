//! A jammed antenna: where the sweep physically cannot go on.

use nalgebra::Vector2;

use super::feature::Feature;

/// The antenna jammed against the walls: no posture within the joints' limits keeps every
/// link out of the walls with the base where it was to go; the contacts pin the chain and
/// the joints that could give are on their stops.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("the antenna jammed moving the base to ({base_x_m}, {base_y_m}) m: {description}")]
pub struct Jam {
    /// The base position aimed for, x.
    pub base_x_m: f64,
    /// The base position aimed for, y.
    pub base_y_m: f64,
    /// The contacts that pin it (at the last step solved).
    pub contacts: Vec<JammedContact>,
    /// The joints on a stop (`1..=n`).
    pub joints_on_stops: Vec<usize>,
    /// What pins it, in words.
    pub description: String,
}

/// A contact that pins a jammed antenna.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JammedContact {
    /// What touches.
    pub feature: Feature,
    /// Which wall.
    pub wall: usize,
    /// Where, ground frame, metres.
    pub point_m: Vector2<f64>,
    /// Its normal force at the last step solved, newtons.
    pub normal_force_n: f64,
}
