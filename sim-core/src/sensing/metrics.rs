//! Wall-following metrics of a posture (docs/model.md 8, thesis 4.2.1 and 3.3.1): point of bend,
//! point of contact, preview distance, flip detection, and the correlations the thesis's
//! Table 4.1 reports.
//!
//! # Numbering (docs/model.md 8)
//! Joint `j` (`1..=n`) sits at `p_(j-1)`, the distal end of link `j - 1`; the base pivot is
//! point 0 and the tip is point `n + 1`. A point on link `i` at fraction `s` of its length
//! (`0` its proximal end, `1` its distal end) has the **chain coordinate** `i + s` in these
//! units: joint `j` is `j`, the tip is `n + 1`.
//!
//! Everything here takes plain inputs (angles, contact points in the ground frame, the base
//! position, the direction of motion), so any solver can feed it.

use nalgebra::Vector2;

use crate::walls::{SegmentContact, Wall};

/// One point of the chain touching a wall: plain input to the metrics.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChainContact {
    /// The link touching (`0` is the base link, `1..=n` the flagellum).
    pub link: usize,
    /// Where along the link, `0` (proximal end) to `1` (distal end). For a hair tip: the
    /// fraction of the hair's pivot on its link.
    pub s: f64,
    /// The contact point in the ground frame, metres (for a hair: the hair tip).
    pub point_m: Vector2<f64>,
}

impl ChainContact {
    /// `link + s`: joint `j` is `j`, the tip is `n + 1` (see the module docs).
    pub fn chain_coordinate(&self) -> f64 {
        self.link as f64 + self.s
    }
}

/// The point of bend (thesis 4.2.1): the joint `j >= 1` with the greatest `|theta_j|`, ties to
/// the more proximal joint. `theta_rad` has `n + 1` entries (`theta_0` is the base angle and is
/// not a candidate); non-finite entries are skipped. `None` if no joint qualifies.
pub fn point_of_bend(theta_rad: &[f64]) -> Option<usize> {
    let mut best: Option<(usize, f64)> = None;
    for (j, theta) in theta_rad.iter().enumerate().skip(1) {
        let magnitude = theta.abs();
        if !magnitude.is_finite() {
            continue;
        }
        if best.is_none_or(|(_, top)| magnitude > top) {
            best = Some((j, magnitude));
        }
    }
    best.map(|(j, _)| j)
}

/// The most proximal contact (thesis 4.2.1: "the joint of most proximal contact").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointOfContact {
    /// The link of that contact.
    pub link: usize,
    /// Its fraction along the link.
    pub s: f64,
    /// `link + s` (see the module docs).
    pub chain_coordinate: f64,
    /// The nearest point number: `round(chain_coordinate)` (joint `j` = `j`, tip = `n + 1`).
    pub joint: usize,
}

/// The point of contact: the contact with the smallest chain coordinate (ties: the first
/// listed). Contacts with a non-finite `s` are skipped. `None` without contacts.
pub fn point_of_contact(contacts: &[ChainContact]) -> Option<PointOfContact> {
    let mut best: Option<&ChainContact> = None;
    for contact in contacts.iter().filter(|c| c.s.is_finite()) {
        if best.is_none_or(|b| contact.chain_coordinate() < b.chain_coordinate()) {
            best = Some(contact);
        }
    }
    best.map(|c| {
        let chain_coordinate = c.chain_coordinate();
        PointOfContact {
            link: c.link,
            s: c.s,
            chain_coordinate,
            joint: chain_coordinate.round().max(0.0) as usize,
        }
    })
}

/// The preview distance (docs/model.md 8): how far ahead of the base pivot, along the direction
/// of motion (`motion_angle_rad` from the ground x-axis), the antenna touches the wall:
/// `max over contacts of (point_m - base_m) . (cos a, sin a)`, metres. Negative when every
/// contact is behind the base. `None` without contacts (non-finite points are skipped).
pub fn preview_distance_m(
    contacts: &[ChainContact],
    base_m: &Vector2<f64>,
    motion_angle_rad: f64,
) -> Option<f64> {
    let (sin, cos) = motion_angle_rad.sin_cos();
    let ahead = Vector2::new(cos, sin);
    contacts
        .iter()
        .map(|c| (c.point_m - base_m).dot(&ahead))
        .filter(|d| d.is_finite())
        .fold(None, |best: Option<f64>, d| {
            Some(best.map_or(d, |b| b.max(d)))
        })
}

/// The angle of a segment to a wall, in `[0, pi]` radians: between the segment's direction
/// (proximal to distal) and the wall tangent oriented **forward**, i.e. with the sign that
/// makes `tangent . (cos a, sin a) >= 0` for the direction of motion `a` (a tangent exactly
/// perpendicular to the motion is kept as given). An antenna projecting forward along the
/// wall has its distal segment below `pi / 2`; flipped back (its tip trailing) above `pi / 2`
/// (docs/model.md 7: "a flip is when the distal-most segment's angle to the wall exceeds 90 deg").
/// `None` if either vector has zero or non-finite length.
pub fn angle_to_wall_rad(
    segment_direction: &Vector2<f64>,
    wall_tangent: &Vector2<f64>,
    motion_angle_rad: f64,
) -> Option<f64> {
    let (e_norm, t_norm) = (segment_direction.norm(), wall_tangent.norm());
    if !(e_norm > 0.0 && e_norm.is_finite() && t_norm > 0.0 && t_norm.is_finite()) {
        return None;
    }
    let (sin, cos) = motion_angle_rad.sin_cos();
    let mut t = wall_tangent / t_norm;
    if t.dot(&Vector2::new(cos, sin)) < 0.0 {
        t = -t;
    }
    let e = segment_direction / e_norm;
    let cross = t.x * e.y - t.y * e.x;
    Some(cross.abs().atan2(t.dot(&e)))
}

/// Whether the distal-most segment has flipped, and the geometry that decided it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlipState {
    /// [`angle_to_wall_rad`] of the distal segment, radians in `[0, pi]`.
    pub angle_to_wall_rad: f64,
    /// `angle_to_wall_rad > pi / 2` (strictly).
    pub flipped: bool,
    /// The wall point whose tangent was used: the distal segment's deepest (or closest)
    /// point against the wall ([`Wall::segment_contact`]).
    pub contact: SegmentContact,
}

/// Flip detection (docs/model.md 7-8): the distal-most segment runs from `distal_start_m` (its
/// proximal joint) to `tip_m`; its angle to `wall` is measured against the wall tangent at
/// the segment's contact (or nearest) point, oriented along the motion. `None` for a
/// zero-length segment.
pub fn flip_state(
    wall: &Wall,
    distal_start_m: &Vector2<f64>,
    tip_m: &Vector2<f64>,
    motion_angle_rad: f64,
) -> Option<FlipState> {
    let contact = wall.segment_contact(distal_start_m, tip_m);
    let angle = angle_to_wall_rad(
        &(tip_m - distal_start_m),
        &contact.wall.tangent,
        motion_angle_rad,
    )?;
    Some(FlipState {
        angle_to_wall_rad: angle,
        flipped: angle > core::f64::consts::FRAC_PI_2,
        contact,
    })
}

/// Pearson's correlation coefficient of paired samples. `None` (undefined, docs/model.md 8) when
/// the lengths differ, there are fewer than two pairs, a value is not finite, or either
/// series is constant (a point of bend that never moves has no correlation).
pub fn pearson_correlation(x: &[f64], y: &[f64]) -> Option<f64> {
    if x.len() != y.len() || x.len() < 2 || x.iter().chain(y).any(|v| !v.is_finite()) {
        return None;
    }
    let count = x.len() as f64;
    let mean_x = x.iter().sum::<f64>() / count;
    let mean_y = y.iter().sum::<f64>() / count;
    let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
    for (a, b) in x.iter().zip(y) {
        let (dx, dy) = (a - mean_x, b - mean_y);
        sxx += dx * dx;
        syy += dy * dy;
        sxy += dx * dy;
    }
    if sxx == 0.0 || syy == 0.0 {
        return None;
    }
    Some((sxy / (sxx.sqrt() * syy.sqrt())).clamp(-1.0, 1.0))
}

/// Spearman's rank correlation (the thesis's Table 4.1, in parentheses): Pearson's on the
/// ranks, tied values sharing their mean rank. `None` as for [`pearson_correlation`].
pub fn spearman_correlation(x: &[f64], y: &[f64]) -> Option<f64> {
    if x.len() != y.len() || x.iter().chain(y).any(|v| !v.is_finite()) {
        return None;
    }
    pearson_correlation(&ranks(x), &ranks(y))
}

/// Ranks `1..=len` of finite values, ties sharing the mean of their ranks.
fn ranks(values: &[f64]) -> Vec<f64> {
    let mut order: Vec<usize> = (0..values.len()).collect();
    order.sort_by(|&a, &b| values[a].total_cmp(&values[b]));
    let mut out = vec![0.0; values.len()];
    let mut start = 0;
    while start < order.len() {
        let mut end = start + 1;
        while end < order.len() && values[order[end]] == values[order[start]] {
            end += 1;
        }
        // Positions start..end (0-based) hold ranks start+1..=end: their mean.
        let mean_rank = (start + 1 + end) as f64 / 2.0;
        for &index in &order[start..end] {
            out[index] = mean_rank;
        }
        start = end;
    }
    out
}
