//! From what the robot senses to the wall's distance (and angle where it can) in the body
//! frame: the contact-line estimator (mapped contact points and odometry), the bend
//! estimator (the point of bend and a calibration table) and the ideal preview (the true
//! geometry, the check against theory). Each says when it has no estimate and why.

use nalgebra::Vector2;

use crate::Wall;
use crate::walls::first_ray_hit;

/// An estimate of the wall in the body frame (x ahead, y toward the wall).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    /// `d`: the distance from the body axis to the wall along the perpendicular at
    /// `preview_m` ahead of the point of rotation, m.
    pub distance_m: f64,
    /// The wall's angle to the body axis, positive when the body is turned away from the
    /// wall (`theta`), radians; `None` where the estimator gives no angle.
    pub angle_rad: Option<f64>,
    /// Where along the body axis `distance_m` holds, m ahead of the point of rotation.
    pub preview_m: f64,
}

/// Why there is no estimate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NoEstimate {
    /// No touch switch has closed within the window.
    NoContact,
    /// Fewer than two contact points in the window.
    TooFewPoints,
    /// The points in the window span less than [`MIN_SPAN_M`].
    TooShortSpan,
    /// No switch is closed, so the antenna's bend says nothing of a wall.
    NoTouch,
    /// The point of bend lies outside the calibration table.
    OutsideCalibration,
    /// The preview ray meets no wall within [`PREVIEW_RANGE_M`].
    NoWallOnRay,
}

impl NoEstimate {
    /// In words.
    pub fn reason(self) -> &'static str {
        match self {
            NoEstimate::NoContact => "no contact in the window",
            NoEstimate::TooFewPoints => "fewer than 2 contact points in the window",
            NoEstimate::TooShortSpan => "the contact points span less than 1 cm",
            NoEstimate::NoTouch => "no touch switch closed",
            NoEstimate::OutsideCalibration => "the point of bend is outside the calibration table",
            NoEstimate::NoWallOnRay => "the preview ray meets no wall",
        }
    }
}

/// The contact-line estimator needs points spanning at least this, m.
pub const MIN_SPAN_M: f64 = 0.01;

/// How far the ideal preview's ray looks, m.
pub const PREVIEW_RANGE_M: f64 = 100.0;

/// The ideal preview (the template's `d`): a ray from `preview_m` ahead of the point of
/// rotation along the body's normal toward the wall (its left: the loop runs every wall on
/// the left), to the first wall it meets.
pub fn ideal_preview(
    walls: &[Wall],
    por_m: &Vector2<f64>,
    heading_rad: f64,
    preview_m: f64,
) -> Result<Estimate, NoEstimate> {
    let (sin, cos) = heading_rad.sin_cos();
    let ahead = Vector2::new(cos, sin);
    let left = Vector2::new(-sin, cos);
    let origin = por_m + ahead * preview_m;
    first_ray_hit(walls, &origin, &left, PREVIEW_RANGE_M)
        .map(|(_, t_m)| Estimate {
            distance_m: t_m,
            angle_rad: None,
            preview_m,
        })
        .ok_or(NoEstimate::NoWallOnRay)
}

/// The robot's dead reckoning: the commanded forward speed and an ideal gyro (the true
/// turning rate), integrated by the midpoint rule. Points are kept in its frame and carried
/// into the current body frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Odometry {
    /// The point of rotation in the odometry frame, m.
    pub por_m: Vector2<f64>,
    /// The heading in the odometry frame, radians.
    pub heading_rad: f64,
}

impl Odometry {
    /// Moves on by `speed_m_per_s` over `dt_s` while the heading changes by
    /// `d_heading_rad`.
    pub fn advance(&mut self, speed_m_per_s: f64, d_heading_rad: f64, dt_s: f64) {
        let mid = self.heading_rad + 0.5 * d_heading_rad;
        self.por_m += Vector2::new(mid.cos(), mid.sin()) * (speed_m_per_s * dt_s);
        self.heading_rad += d_heading_rad;
    }

    /// A body-frame point in the odometry frame.
    pub fn to_odometry(&self, body_m: &Vector2<f64>) -> Vector2<f64> {
        let (sin, cos) = self.heading_rad.sin_cos();
        self.por_m
            + Vector2::new(
                cos * body_m.x - sin * body_m.y,
                sin * body_m.x + cos * body_m.y,
            )
    }

    /// An odometry-frame point in the body frame.
    pub fn to_body(&self, odometry_m: &Vector2<f64>) -> Vector2<f64> {
        let (sin, cos) = self.heading_rad.sin_cos();
        let d = odometry_m - self.por_m;
        Vector2::new(cos * d.x + sin * d.y, -sin * d.x + cos * d.y)
    }
}

/// The contact-line estimator's window of mapped contact points.
#[derive(Clone, Debug, Default)]
pub struct ContactWindow {
    window_s: f64,
    /// `(time, point in the odometry frame)`, oldest first.
    points: std::collections::VecDeque<(f64, Vector2<f64>)>,
    /// The points in the current body frame (scratch, and what the last estimate used).
    body_points: Vec<Vector2<f64>>,
}

impl ContactWindow {
    /// A window of `window_s` seconds.
    pub fn new(window_s: f64) -> ContactWindow {
        ContactWindow {
            window_s,
            ..ContactWindow::default()
        }
    }

    /// Adds points mapped at `t_s` (body frame) and drops those older than the window.
    pub fn add(&mut self, t_s: f64, odometry: &Odometry, body_points_m: &[Vector2<f64>]) {
        self.points
            .extend(body_points_m.iter().map(|p| (t_s, odometry.to_odometry(p))));
        while self
            .points
            .front()
            .is_some_and(|(t, _)| *t < t_s - self.window_s - 1e-12)
        {
            self.points.pop_front();
        }
    }

    /// The points of the last estimate, in the body frame at its time.
    pub fn body_points_m(&self) -> &[Vector2<f64>] {
        &self.body_points
    }

    /// The line fitted to the window's points (total least squares), carried into the
    /// current body frame: `d` at the points' mean forward coordinate, the angle, and that
    /// coordinate as the preview.
    pub fn estimate(&mut self, odometry: &Odometry) -> Result<Estimate, NoEstimate> {
        self.body_points.clear();
        self.body_points
            .extend(self.points.iter().map(|(_, p)| odometry.to_body(p)));
        let points = &self.body_points;
        match points.len() {
            0 => return Err(NoEstimate::NoContact),
            1 => return Err(NoEstimate::TooFewPoints),
            _ => {}
        }
        let n = points.len() as f64;
        let mean = points.iter().sum::<Vector2<f64>>() / n;
        let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
        for p in points {
            let d = p - mean;
            sxx += d.x * d.x;
            sxy += d.x * d.y;
            syy += d.y * d.y;
        }
        // The principal direction of the scatter: the fitted line's direction.
        let angle = 0.5 * (2.0 * sxy).atan2(sxx - syy);
        let direction = Vector2::new(angle.cos(), angle.sin());
        let (lo, hi) = points
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                let s = (p - mean).dot(&direction);
                (lo.min(s), hi.max(s))
            });
        if hi - lo < MIN_SPAN_M {
            return Err(NoEstimate::TooShortSpan);
        }
        // The line through the mean: d at the mean's forward coordinate is the mean's y.
        // Its angle folded to (-90, 90] degrees from the body axis.
        let mut wall_angle = angle;
        if wall_angle > std::f64::consts::FRAC_PI_2 {
            wall_angle -= std::f64::consts::PI;
        } else if wall_angle <= -std::f64::consts::FRAC_PI_2 {
            wall_angle += std::f64::consts::PI;
        }
        Ok(Estimate {
            distance_m: mean.y,
            angle_rad: Some(wall_angle),
            preview_m: mean.x,
        })
    }
}

/// The bend estimator's calibration: the continuous point of bend ([`bend_coordinate`])
/// against the wall's distance from the point of rotation, measured with the body parallel
/// to a straight wall (static placements at `theta = 0`), sorted by the point of bend.
#[derive(Clone, Debug, PartialEq)]
pub struct BendTable {
    /// `(point of bend, distance_m)`, by point of bend.
    pub rows: Vec<(f64, f64)>,
}

impl BendTable {
    /// The table from measured `(point of bend, distance)` pairs: rows that are not finite
    /// dropped, sorted by the point of bend, one row per point of bend (the first measured).
    pub fn from_measurements(mut rows: Vec<(f64, f64)>) -> BendTable {
        rows.retain(|(b, d)| b.is_finite() && d.is_finite());
        rows.sort_by(|a, b| a.0.total_cmp(&b.0));
        rows.dedup_by(|a, b| a.0 == b.0);
        BendTable { rows }
    }

    /// The distance for a point of bend, by linear interpolation; outside the table's range
    /// there is none.
    pub fn distance_m(&self, bend: f64) -> Result<f64, NoEstimate> {
        let rows = &self.rows;
        let (first, last) = match (rows.first(), rows.last()) {
            (Some(f), Some(l)) => (f, l),
            _ => return Err(NoEstimate::OutsideCalibration),
        };
        if !(bend >= first.0 && bend <= last.0) {
            return Err(NoEstimate::OutsideCalibration);
        }
        let i = rows.partition_point(|r| r.0 < bend);
        if i == 0 {
            return Ok(first.1);
        }
        let (a, b) = (rows[i - 1], rows[i]);
        Ok(a.1 + (b.1 - a.1) * (bend - a.0) / (b.0 - a.0))
    }
}

/// The continuous point of bend: the joint with the greatest `|theta_j|`
/// ([`crate::sensing::metrics::point_of_bend`]) moved by the vertex of the parabola through it and its two
/// neighbours (half a joint at most); `None` where no joint qualifies.
pub fn bend_coordinate(theta_rad: &[f64]) -> Option<f64> {
    let j = crate::sensing::metrics::point_of_bend(theta_rad)?;
    let magnitude = |k: usize| theta_rad.get(k).map(|t| t.abs());
    let (Some(a), Some(b), Some(c)) = (
        (j >= 2).then(|| magnitude(j - 1)).flatten(),
        magnitude(j),
        magnitude(j + 1),
    ) else {
        return Some(j as f64);
    };
    let curvature = a - 2.0 * b + c;
    if curvature >= 0.0 {
        return Some(j as f64);
    }
    Some(j as f64 + (0.5 * (a - c) / curvature).clamp(-0.5, 0.5))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn odometry_carries_points_into_the_body_frame() {
        let mut odometry = Odometry::default();
        let point = odometry.to_odometry(&Vector2::new(0.1, 0.05));
        // Straight on by 0.1 m: the point is now beside the body.
        odometry.advance(1.0, 0.0, 0.1);
        let body = odometry.to_body(&point);
        assert!((body - Vector2::new(0.0, 0.05)).norm() < 1e-15);
        // A quarter turn clockwise on the spot: the point ahead is now on the left.
        let mut turned = Odometry::default();
        let ahead = turned.to_odometry(&Vector2::new(0.1, 0.0));
        turned.advance(0.0, -std::f64::consts::FRAC_PI_2, 1.0);
        assert!((turned.to_body(&ahead) - Vector2::new(0.0, 0.1)).norm() < 1e-15);
    }

    #[test]
    fn the_contact_line_recovers_a_wall_line_in_the_body_frame() {
        // A wall at 0.1 m, the body turned away from it by 0.1 rad: in the body frame the
        // wall rises at 0.1 rad.
        let theta = 0.1_f64;
        let mut window = ContactWindow::new(1.0);
        let odometry = Odometry::default();
        let points: Vec<Vector2<f64>> = (0..5)
            .map(|k| {
                let x = 0.05 + 0.01 * k as f64;
                Vector2::new(x, 0.1 / theta.cos() + x * theta.tan())
            })
            .collect();
        window.add(0.0, &odometry, &points);
        let e = window.estimate(&odometry).unwrap();
        assert!((e.angle_rad.unwrap() - theta).abs() < 1e-12);
        assert!((e.preview_m - 0.07).abs() < 1e-12);
        let d = 0.1 / theta.cos() + e.preview_m * theta.tan();
        assert!((e.distance_m - d).abs() < 1e-12);
    }

    #[test]
    fn the_contact_line_says_why_it_has_no_estimate() {
        let odometry = Odometry::default();
        let mut window = ContactWindow::new(0.5);
        assert_eq!(window.estimate(&odometry), Err(NoEstimate::NoContact));
        window.add(0.0, &odometry, &[Vector2::new(0.1, 0.1)]);
        assert_eq!(window.estimate(&odometry), Err(NoEstimate::TooFewPoints));
        window.add(0.1, &odometry, &[Vector2::new(0.105, 0.1)]);
        assert_eq!(window.estimate(&odometry), Err(NoEstimate::TooShortSpan));
        // Old points leave the window.
        window.add(0.7, &odometry, &[]);
        assert_eq!(window.estimate(&odometry), Err(NoEstimate::NoContact));
    }

    #[test]
    fn the_bend_table_interpolates_and_refuses_outside() {
        let table = BendTable::from_measurements(vec![(5.0, 0.2), (3.0, 0.1), (4.0, 0.16)]);
        assert_eq!(table.distance_m(3.0), Ok(0.1));
        assert!((table.distance_m(3.5).unwrap() - 0.13).abs() < 1e-15);
        assert_eq!(table.distance_m(5.5), Err(NoEstimate::OutsideCalibration));
        assert_eq!(
            table.distance_m(f64::NAN),
            Err(NoEstimate::OutsideCalibration)
        );
    }

    #[test]
    fn the_continuous_point_of_bend_moves_toward_the_larger_neighbour() {
        assert_eq!(bend_coordinate(&[0.5, 0.1, 0.3, 0.1]), Some(2.0));
        let b = bend_coordinate(&[0.5, 0.1, 0.3, 0.2]).unwrap();
        assert!(b > 2.0 && b < 2.5, "{b}");
        assert_eq!(bend_coordinate(&[0.5]), None);
    }
}
