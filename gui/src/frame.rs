//! [`ChainFrame`]: one instant of the chain, whatever its source.
//!
//! The chain panel draws only this type, so live data from antennad, a recorded MCAP trial
//! and a simulated sweep all feed it the same way: joint positions in the ground (track)
//! frame, touch bits and health per segment, hair tips, walls as polylines, and the base and
//! stage position. Positions are metres in the track frame: x along the stage's track from
//! home, y towards the wall, the antenna's base attachment at `(stage_position_m, 0)`.
//!
//! The base need not ride a stage along x: a frame carries the path its base takes
//! ([`ChainFrame::path_m`]: a sweep's straight track in any direction, a follow run's path of
//! the robot so far), and a closed-loop run's frame the robot's body ([`BodyDrawing`]: its
//! footprint at its pose and heading), the estimator's points and the whole run's extent, so
//! that sweeps and follow runs draw through the same chain panel. A frame of the rig (live
//! or recorded) may carry antennad's wall estimate ([`ChainFrame::estimated_wall`], [`crate::estimate`]).
//!
//! Where a touch switch sits is the frame's to say, the same for every source:
//! [`ChainFrame::lit_switches`] places each switch that fires at sim-core's place for it,
//! [`TouchLayout::switch_fraction`] of its segment's link from the proximal joint (switch `i`
//! covers the quarter `[i/4, (i+1)/4)` of the link, [`sim_core::switch_for_fraction`]).

use sim_core::{SWITCHES_PER_SEGMENT, TouchLayout};

use crate::estimate::EstimatedWall;
use crate::history::Health;

/// A point in the track frame, metres: `[x, y]`.
pub type PointM = [f64; 2];

/// One segment's state in a frame. Segment `k` (1-based, base to tip) measures joint `k` and
/// rides on link `k`, the link it lights up when touched.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SegmentState {
    /// Touch bits (bit i: switch i closed), 0..=15; 0 for a failed read.
    pub touch_bits: u8,
    /// The reading's health: an unhealthy segment is drawn as such.
    pub health: Health,
    /// Whether the joint angle drawn is this instant's (false: the last valid one was held,
    /// or none was known and 0 was drawn).
    pub angle_current: bool,
}

impl SegmentState {
    /// A healthy, untouched segment.
    pub const QUIET: SegmentState = SegmentState {
        touch_bits: 0,
        health: Health::Ok,
        angle_current: true,
    };

    /// Whether any touch switch is closed.
    pub fn touched(&self) -> bool {
        self.touch_bits != 0
    }
}

/// One touch switch that fires, where it sits on its link ([`ChainFrame::lit_switches`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LitSwitch {
    /// The segment's index in [`ChainFrame::segments`] (0: the segment nearest the base); it
    /// rides on link `segment + 1`.
    pub segment: usize,
    /// The switch, 0 (the most proximal) to 3: bit `switch` of the segment's touch bits.
    pub switch: usize,
    /// Where it sits, track frame, metres.
    pub point_m: PointM,
}

/// A hair drawn from its root on a link to its tip.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HairDrawing {
    /// The link carrying it (1-based).
    pub link: usize,
    /// Its root, track frame, metres.
    pub root_m: PointM,
    /// Its tip, track frame, metres.
    pub tip_m: PointM,
}

/// A moving robot's body in a frame (a closed-loop run, [`crate::follow`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyDrawing {
    /// The point of rotation, ground frame, metres.
    pub por_m: PointM,
    /// The heading, ground frame, counter-clockwise, radians.
    pub heading_rad: f64,
    /// The footprint's corners (a rectangle about the point of rotation), counter-clockwise
    /// from the front corner on the body's right, ground frame, metres.
    pub corners_m: [PointM; 4],
    /// Whether the footprint overlaps a wall.
    pub collided: bool,
    /// The estimated wall point: `estimate_m` across the body axis at the estimate's preview,
    /// toward the wall's side, ground frame, metres (`None` without an estimate).
    pub estimated_wall_m: Option<PointM>,
}

impl BodyDrawing {
    /// The body at `por_m` heading `heading_rad`, with a `footprint_m` = `[length, width]`
    /// rectangle centred on the point of rotation.
    pub fn new(por_m: PointM, heading_rad: f64, footprint_m: [f64; 2], collided: bool) -> Self {
        let (sin, cos) = heading_rad.sin_cos();
        let (half_length, half_width) = (footprint_m[0] / 2.0, footprint_m[1] / 2.0);
        let corner = |ahead: f64, left: f64| {
            [
                por_m[0] + cos * ahead - sin * left,
                por_m[1] + sin * ahead + cos * left,
            ]
        };
        Self {
            por_m,
            heading_rad,
            corners_m: [
                corner(half_length, -half_width),
                corner(half_length, half_width),
                corner(-half_length, half_width),
                corner(-half_length, -half_width),
            ],
            collided,
            estimated_wall_m: None,
        }
    }
}

/// One instant of the chain (see the module documentation).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ChainFrame {
    /// The instant, seconds on the source's clock.
    pub t_s: f64,
    /// The base attachment, then the distal end of every link, base link first: `n + 2`
    /// points for `n` segments (sim-core's frames `C_G`, `C_0`, ..., `C_n`).
    pub joints_m: Vec<PointM>,
    /// One per segment, base to tip.
    pub segments: Vec<SegmentState>,
    /// Hairs, if the antenna has any.
    pub hairs: Vec<HairDrawing>,
    /// Walls, each a polyline.
    pub walls_m: Vec<Vec<PointM>>,
    /// Where the chain touches a wall, when the source knows (a simulated sweep's contact
    /// points; a measured chain has only its touch bits).
    pub contacts_m: Vec<PointM>,
    /// The base attachment (the same as `joints_m[0]`).
    pub base_m: PointM,
    /// The stage's position, metres, if known.
    pub stage_position_m: Option<f64>,
    /// The base link's angle from the track (mounting angle plus servo), radians.
    pub base_angle_rad: f64,
    /// The stage's soft limits, metres, if known (drawn as the track when `path_m` is
    /// empty).
    pub stage_range_m: Option<(f64, f64)>,
    /// The path of a moving base, ground frame, metres: a sweep's track from its start to its
    /// end (in any direction), a follow run's point of rotation up to this instant. Empty for
    /// the rig (its track is `stage_range_m`).
    pub path_m: Vec<PointM>,
    /// A closed-loop run's robot body (`None` for the rig and a sweep).
    pub body: Option<BodyDrawing>,
    /// A closed-loop run's estimator points (the contact line's window), ground frame,
    /// metres.
    pub estimated_points_m: Vec<PointM>,
    /// The whole run's extent `(min, max)` (every pose's footprint and antenna reach), for a
    /// view that fits the run; `None`: fit the frame ([`ChainFrame::bounds_m`]).
    pub run_extent_m: Option<(PointM, PointM)>,
    /// antennad's wall estimate at this instant, drawn over the chain (live or recorded).
    pub estimated_wall: Option<EstimatedWall>,
    /// Why no estimated wall is drawn, when the source estimates (the daemon's reason, that
    /// the newest estimate is too old, or that it sends none).
    pub estimate_note: Option<String>,
}

/// How far a second frame's joints are from a first's.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameDifference {
    /// Distance between corresponding points of `joints_m`, metres.
    pub per_point_m: Vec<f64>,
    /// The largest of them, metres.
    pub max_m: f64,
    /// The tips' distance, metres.
    pub tip_m: f64,
}

impl ChainFrame {
    /// Segments in the frame.
    pub fn segment_count(&self) -> usize {
        self.segments.len()
    }

    /// The tip (the last joint point).
    pub fn tip_m(&self) -> Option<PointM> {
        self.joints_m.last().copied()
    }

    /// Link `k`'s end points (0: the base link), if it exists.
    pub fn link_m(&self, k: usize) -> Option<(PointM, PointM)> {
        Some((*self.joints_m.get(k)?, *self.joints_m.get(k + 1)?))
    }

    /// Where switch `switch` (0 the most proximal .. 3) of the segment at `segment` (an index
    /// into [`ChainFrame::segments`]) sits: [`TouchLayout::switch_fraction`] of the way along
    /// its link from the proximal joint. `None` past the last switch or segment.
    pub fn switch_m(&self, segment: usize, switch: usize) -> Option<PointM> {
        if switch >= SWITCHES_PER_SEGMENT || segment >= self.segments.len() {
            return None;
        }
        let (a, b) = self.link_m(segment + 1)?;
        let f = TouchLayout::switch_fraction(switch);
        Some([a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])])
    }

    /// Every touch switch that fires, segment by segment from the base, each segment's from
    /// its proximal end: one per set bit of each segment's touch bits, at [`Self::switch_m`].
    /// A failed read (touch bits 0) lights none.
    pub fn lit_switches(&self) -> Vec<LitSwitch> {
        self.segments
            .iter()
            .enumerate()
            .flat_map(|(segment, state)| {
                (0..SWITCHES_PER_SEGMENT)
                    .filter(move |&switch| state.touch_bits & (1 << switch) != 0)
                    .map(move |switch| (segment, switch))
            })
            .filter_map(|(segment, switch)| {
                self.switch_m(segment, switch).map(|point_m| LitSwitch {
                    segment,
                    switch,
                    point_m,
                })
            })
            .collect()
    }

    /// The smallest box holding the chain, the base, the stage's track, the base's path and
    /// the body, as `(min, max)`; walls are not included (they are drawn clipped to it).
    pub fn bounds_m(&self) -> (PointM, PointM) {
        let (mut min, mut max) = self.local_bounds_m();
        for p in &self.path_m {
            min = [min[0].min(p[0]), min[1].min(p[1])];
            max = [max[0].max(p[0]), max[1].max(p[1])];
        }
        (min, max)
    }

    /// [`Self::bounds_m`] without the base's path: the chain, the base, the stage's track
    /// and the body (a view that follows the robot).
    pub fn local_bounds_m(&self) -> (PointM, PointM) {
        let mut min = self.base_m;
        let mut max = self.base_m;
        let mut grow = |p: &PointM| {
            min = [min[0].min(p[0]), min[1].min(p[1])];
            max = [max[0].max(p[0]), max[1].max(p[1])];
        };
        self.joints_m.iter().for_each(&mut grow);
        self.hairs.iter().for_each(|h| grow(&h.tip_m));
        if let Some((lo, hi)) = self.stage_range_m {
            grow(&[lo, 0.0]);
            grow(&[hi, 0.0]);
        }
        if let Some(body) = &self.body {
            body.corners_m.iter().for_each(&mut grow);
        }
        (min, max)
    }

    /// How far `other`'s joints are from this frame's, point by point; `None` if the two
    /// have different numbers of points.
    pub fn difference(&self, other: &ChainFrame) -> Option<FrameDifference> {
        if self.joints_m.len() != other.joints_m.len() || self.joints_m.is_empty() {
            return None;
        }
        let per_point_m: Vec<f64> = self
            .joints_m
            .iter()
            .zip(&other.joints_m)
            .map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1]))
            .collect();
        let max_m = per_point_m.iter().copied().fold(0.0, f64::max);
        let tip_m = per_point_m.last().copied().unwrap_or(0.0);
        Some(FrameDifference {
            per_point_m,
            max_m,
            tip_m,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(points: Vec<PointM>) -> ChainFrame {
        ChainFrame {
            t_s: 0.0,
            segments: vec![SegmentState::QUIET; points.len().saturating_sub(2)],
            base_m: points[0],
            joints_m: points,
            hairs: Vec::new(),
            walls_m: Vec::new(),
            contacts_m: Vec::new(),
            stage_position_m: None,
            base_angle_rad: 0.0,
            stage_range_m: Some((0.0, 0.3)),
            ..ChainFrame::default()
        }
    }

    #[test]
    fn difference_and_bounds() {
        let a = frame(vec![[0.0, 0.0], [0.04, 0.0], [0.08, 0.0]]);
        let b = frame(vec![[0.0, 0.0], [0.04, 0.0], [0.08, 0.03]]);
        let d = a.difference(&b).unwrap();
        assert_eq!(d.per_point_m, vec![0.0, 0.0, 0.03]);
        assert_eq!((d.max_m, d.tip_m), (0.03, 0.03));
        assert!(a.difference(&frame(vec![[0.0, 0.0], [1.0, 0.0]])).is_none());
        assert_eq!(b.bounds_m(), ([0.0, 0.0], [0.3, 0.03]));
        assert_eq!(a.link_m(1), Some(([0.04, 0.0], [0.08, 0.0])));
        assert_eq!(a.link_m(2), None);
        // A moving base's path widens the bounds; the local bounds leave it out.
        let mut c = a.clone();
        c.path_m = vec![[-0.5, 0.0], [0.0, 0.0]];
        assert_eq!(c.bounds_m(), ([-0.5, 0.0], [0.3, 0.0]));
        assert_eq!(c.local_bounds_m(), a.bounds_m());
    }

    #[test]
    fn a_body_turned_a_quarter_has_its_length_along_y() {
        let body = BodyDrawing::new([1.0, 2.0], std::f64::consts::FRAC_PI_2, [0.2, 0.1], false);
        let near =
            |p: PointM, q: PointM| (p[0] - q[0]).abs() < 1e-12 && (p[1] - q[1]).abs() < 1e-12;
        // Ahead is +y, the body's right is +x.
        assert!(near(body.corners_m[0], [1.05, 2.1]), "{:?}", body.corners_m);
        assert!(near(body.corners_m[1], [0.95, 2.1]));
        assert!(near(body.corners_m[2], [0.95, 1.9]));
        assert!(near(body.corners_m[3], [1.05, 1.9]));
    }

    /// Bit `i` lights switch `i` alone, `(i + 1/2) / 4` of the way along its segment's link;
    /// the base link carries no switch.
    #[test]
    fn each_touch_bit_lights_its_own_switch_along_the_link() {
        // Two segments: the base link along x, link 1 up y, link 2 along x again.
        let mut f = frame(vec![[0.0, 0.0], [0.04, 0.0], [0.04, 0.04], [0.08, 0.04]]);
        let near = |p: Option<PointM>, q: PointM| {
            p.is_some_and(|p| (p[0] - q[0]).abs() < 1e-12 && (p[1] - q[1]).abs() < 1e-12)
        };
        assert!(f.lit_switches().is_empty());
        f.segments[0].touch_bits = 0b0100;
        let lit = f.lit_switches();
        assert_eq!(lit.len(), 1, "{lit:?}");
        assert_eq!((lit[0].segment, lit[0].switch), (0, 2));
        assert!(near(Some(lit[0].point_m), [0.04, 0.025]), "{lit:?}");
        f.segments[1].touch_bits = 0b1001;
        let lit: Vec<(usize, usize)> = f
            .lit_switches()
            .iter()
            .map(|l| (l.segment, l.switch))
            .collect();
        assert_eq!(lit, [(0, 2), (1, 0), (1, 3)]);
        assert!(near(f.switch_m(1, 0), [0.045, 0.04]));
        assert!(near(f.switch_m(1, 3), [0.075, 0.04]));
        assert_eq!(f.switch_m(1, 4), None);
        assert_eq!(f.switch_m(2, 0), None);
    }
}
