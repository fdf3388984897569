//! [`EstimateHistory`]: antennad's wall estimates (live, the stream's `estimate` lines,
//! `docs/stream-protocol.md`: the newest and those of the history window; recorded, a
//! trial's `/antenna/estimate` channel: all of them), and where the estimated wall lies in
//! the chain panel's frame ([`EstimatedWall`]).
//!
//! An estimate is in the carriage frame: origin at the base pivot at the estimate's newest
//! poll, x along the stage's travel, y toward the wall; the wall is the line
//! `y = distance_m + (x - preview_m) tan(angle_rad)` (an angle of 0 when the estimator gives
//! none, as the bend estimator does). [`Estimate::wall_in_track_m`] turns it into the track
//! frame the chain is drawn in, given the base pivot, the direction of travel and the side of
//! it the wall is on ([`crate::rig::RigGeometry::wall_side`]).

use std::collections::VecDeque;

use antenna_data::stream::EstimateMessage;

use crate::frame::PointM;

/// One estimate as received (times in seconds on the daemon's clock).
#[derive(Debug, Clone, PartialEq)]
pub struct Estimate {
    /// The newest poll the estimate used (its `samples` line's `seq`).
    pub seq: u64,
    /// That poll's time, seconds.
    pub t_s: f64,
    /// When the estimate was made, seconds (`None` from a recording, which keeps only the
    /// poll's time).
    pub estimated_s: Option<f64>,
    /// The estimator: `"contact-line"`, `"bend"` or `"ideal-preview"`.
    pub estimator: String,
    /// The wall's distance along y at `preview_m` along x, metres (`None`: no estimate).
    pub distance_m: Option<f64>,
    /// The wall's angle to x, radians (`None` from the bend estimator or with no estimate).
    pub angle_rad: Option<f64>,
    /// Where along x the distance holds, metres ahead of the base pivot.
    pub preview_m: Option<f64>,
    /// Why there is no estimate.
    pub reason: Option<String>,
    /// The simulated rig only: the true wall's distance there, metres.
    pub true_distance_m: Option<f64>,
    /// The simulated rig only: the true wall's angle there, radians.
    pub true_angle_rad: Option<f64>,
}

impl From<EstimateMessage> for Estimate {
    fn from(m: EstimateMessage) -> Self {
        Self {
            seq: m.seq,
            t_s: m.t_ns as f64 * 1e-9,
            estimated_s: Some(m.estimated_ns as f64 * 1e-9),
            estimator: m.estimator,
            distance_m: m.distance_m.filter(|d| d.is_finite()),
            angle_rad: m.angle_rad.filter(|a| a.is_finite()),
            preview_m: m.preview_m.filter(|p| p.is_finite()),
            reason: m.reason,
            true_distance_m: m.true_distance_m.filter(|d| d.is_finite()),
            true_angle_rad: m.true_angle_rad.filter(|a| a.is_finite()),
        }
    }
}

impl From<antenna_data::record::EstimateMessage> for Estimate {
    /// A recorded estimate (times on the trial's clock, as its polls').
    fn from(m: antenna_data::record::EstimateMessage) -> Self {
        Self {
            seq: m.seq,
            t_s: m.t_s,
            estimated_s: None,
            estimator: m.estimator,
            distance_m: m.distance_m.filter(|d| d.is_finite()),
            angle_rad: m.wall_angle_rad.filter(|a| a.is_finite()),
            preview_m: m.preview_m.filter(|p| p.is_finite()),
            reason: m.reason,
            true_distance_m: m.true_distance_m.filter(|d| d.is_finite()),
            true_angle_rad: m.true_angle_rad.filter(|a| a.is_finite()),
        }
    }
}

/// Which side of the stage's travel the wall is on (the estimate's y axis).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WallSide {
    /// Left of the direction of travel (counter-clockwise from it).
    Left,
    /// Right of it.
    Right,
}

impl WallSide {
    /// `"left"` or `"right"`.
    pub fn as_str(self) -> &'static str {
        match self {
            WallSide::Left => "left",
            WallSide::Right => "right",
        }
    }
}

/// The estimated wall drawn over the chain: a segment of its line, track frame, metres.
#[derive(Debug, Clone, PartialEq)]
pub struct EstimatedWall {
    /// The segment's ends.
    pub ends_m: [PointM; 2],
    /// The point the distance is measured to: `preview_m` ahead of the base pivot, on the
    /// estimated wall.
    pub at_m: PointM,
    /// Whether the estimator gave the wall's angle (`false`: drawn parallel to the travel).
    pub angle_known: bool,
    /// The estimator.
    pub estimator: String,
}

impl Estimate {
    /// Whether this line carries an estimate (a distance).
    pub fn has_estimate(&self) -> bool {
        self.distance_m.is_some()
    }

    /// The estimate minus the truth, metres (both known only on the simulated rig).
    pub fn error_m(&self) -> Option<f64> {
        Some(self.distance_m? - self.true_distance_m?)
    }

    /// The estimated wall in the track frame: the base pivot at `base_m`, the stage's travel
    /// along the unit vector `direction`, the wall on `side` of it; the segment spans `x`
    /// (carriage frame, metres ahead of the base pivot; widened to hold the preview point).
    /// `None` without an estimate.
    pub fn wall_in_track_m(
        &self,
        base_m: PointM,
        direction: [f64; 2],
        side: WallSide,
        x_m: (f64, f64),
    ) -> Option<EstimatedWall> {
        let distance_m = self.distance_m?;
        let preview_m = self.preview_m.unwrap_or(0.0);
        let slope = self.angle_rad.unwrap_or(0.0).tan();
        if !slope.is_finite() {
            return None;
        }
        let sign = match side {
            WallSide::Left => 1.0,
            WallSide::Right => -1.0,
        };
        // y toward the wall: the travel turned a quarter toward `side`.
        let normal = [-direction[1] * sign, direction[0] * sign];
        let to_track = |x: f64| {
            let y = distance_m + (x - preview_m) * slope;
            [
                base_m[0] + x * direction[0] + y * normal[0],
                base_m[1] + x * direction[1] + y * normal[1],
            ]
        };
        let (x0, x1) = (x_m.0.min(preview_m), x_m.1.max(preview_m));
        Some(EstimatedWall {
            ends_m: [to_track(x0), to_track(x1)],
            at_m: to_track(preview_m),
            angle_known: self.angle_rad.is_some(),
            estimator: self.estimator.clone(),
        })
    }
}

/// How long an estimate stays current after its poll at least, seconds
/// ([`EstimateHistory::current_at`]).
pub const STALE_AFTER_S: f64 = 1.0;

/// A plotted series: runs of `[t_s, value]` points, one line each (a gap breaks a line).
pub type Lines = Vec<Vec<[f64; 2]>>;

/// The estimates received, oldest first, bounded by the history window (see the module
/// documentation).
#[derive(Debug, Clone, Default)]
pub struct EstimateHistory {
    estimates: VecDeque<Estimate>,
    window_s: f64,
    capacity: usize,
    received: u64,
}

impl EstimateHistory {
    /// Every one of `estimates` (a recording's), in time order (a stable sort: equal times
    /// keep their order).
    pub fn whole(estimates: impl IntoIterator<Item = Estimate>) -> Self {
        let mut estimates: Vec<Estimate> = estimates.into_iter().collect();
        estimates.sort_by(|a, b| a.t_s.total_cmp(&b.t_s));
        Self {
            received: estimates.len() as u64,
            capacity: estimates.len().max(1),
            window_s: f64::INFINITY,
            estimates: estimates.into(),
        }
    }

    /// Empty; keeps the estimates of the last `window_s` seconds, at most `capacity`.
    pub fn new(window_s: f64, capacity: usize) -> Self {
        Self {
            estimates: VecDeque::new(),
            window_s,
            capacity: capacity.max(1),
            received: 0,
        }
    }

    /// Changes the window and the bound (keeps the newest estimates that fit).
    pub fn set_window(&mut self, window_s: f64, capacity: usize) {
        self.window_s = window_s;
        self.capacity = capacity.max(1);
        self.trim();
    }

    /// Estimates held.
    pub fn len(&self) -> usize {
        self.estimates.len()
    }

    /// Whether none is held.
    pub fn is_empty(&self) -> bool {
        self.estimates.is_empty()
    }

    /// Estimates received since the monitor connected (held or not).
    pub fn received(&self) -> u64 {
        self.received
    }

    /// The newest estimate.
    pub fn latest(&self) -> Option<&Estimate> {
        self.estimates.back()
    }

    /// The estimates held, oldest first.
    pub fn iter(&self) -> impl Iterator<Item = &Estimate> {
        self.estimates.iter()
    }

    /// Adds `estimate`. One older than the newest held means a new daemon (its clock
    /// restarted): the history starts afresh with it.
    pub fn push(&mut self, estimate: Estimate) {
        if self.latest().is_some_and(|l| estimate.t_s < l.t_s) {
            self.estimates.clear();
        }
        self.received += 1;
        self.estimates.push_back(estimate);
        self.trim();
    }

    /// Forgets every estimate held (a new daemon's samples started afresh).
    pub fn clear(&mut self) {
        self.estimates.clear();
    }

    fn trim(&mut self) {
        let newest = self.latest().map_or(f64::NEG_INFINITY, |l| l.t_s);
        while self.estimates.len() > self.capacity
            || self
                .estimates
                .front()
                .is_some_and(|e| e.t_s < newest - self.window_s)
        {
            self.estimates.pop_front();
        }
    }

    /// The newest estimate made from a poll at or before `t_s`.
    pub fn at(&self, t_s: f64) -> Option<&Estimate> {
        let n = self.estimates.partition_point(|e| e.t_s <= t_s);
        n.checked_sub(1).and_then(|i| self.estimates.get(i))
    }

    /// [`Self::at`] if it is current at `t_s`: made no longer before it than
    /// [`STALE_AFTER_S`] or three times the interval since the estimate before it, whichever
    /// is longer (the daemon's rate is its `[estimate] rate_hz`, not sent). Otherwise how
    /// long before `t_s` the newest estimate was made (`Err`), or `Ok(None)` for none at all.
    pub fn current_at(&self, t_s: f64) -> Result<Option<&Estimate>, f64> {
        let n = self.estimates.partition_point(|e| e.t_s <= t_s);
        let Some(i) = n.checked_sub(1) else {
            return Ok(None);
        };
        let Some(estimate) = self.estimates.get(i) else {
            return Ok(None);
        };
        let interval_s = i
            .checked_sub(1)
            .and_then(|j| self.estimates.get(j))
            .map_or(0.0, |before| estimate.t_s - before.t_s);
        let age_s = t_s - estimate.t_s;
        if age_s > STALE_AFTER_S.max(3.0 * interval_s) {
            Err(age_s)
        } else {
            Ok(Some(estimate))
        }
    }

    /// The estimated and the true distance between `t0_s` and `t1_s`, millimetres, each as
    /// runs of consecutive estimates that have one (one without breaks its line), at most
    /// about `columns` points each (every `k`th estimate).
    pub fn distance_series_mm(&self, t0_s: f64, t1_s: f64, columns: usize) -> (Lines, Lines) {
        let first = self
            .estimates
            .partition_point(|e| e.t_s < t0_s)
            .saturating_sub(1);
        let last = self.estimates.partition_point(|e| e.t_s <= t1_s);
        let stride = (last.saturating_sub(first) / columns.max(1)).max(1);
        let (mut estimated, mut truth): (Lines, Lines) = Default::default();
        let (mut estimated_broke, mut truth_broke) = (true, true);
        for e in self.estimates.range(first.min(last)..last).step_by(stride) {
            push_point(
                &mut estimated,
                e.distance_m.map(|d| [e.t_s, d * 1e3]),
                &mut estimated_broke,
            );
            push_point(
                &mut truth,
                e.true_distance_m.map(|d| [e.t_s, d * 1e3]),
                &mut truth_broke,
            );
        }
        (estimated, truth)
    }
}

/// Adds `point` to the last line of `lines`, or starts a new one after a break; `None` breaks.
fn push_point(lines: &mut Lines, point: Option<[f64; 2]>, broke: &mut bool) {
    match point {
        Some(p) => {
            if *broke || lines.is_empty() {
                lines.push(Vec::new());
            }
            *broke = false;
            if let Some(line) = lines.last_mut() {
                line.push(p);
            }
        }
        None => *broke = true,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn estimate(seq: u64, distance_m: Option<f64>) -> Estimate {
        Estimate {
            seq,
            // 128 a second: times exact in binary.
            t_s: seq as f64 / 128.0,
            estimated_s: Some(seq as f64 / 128.0 + 1e-5),
            estimator: "contact-line".to_owned(),
            distance_m,
            angle_rad: distance_m.map(|_| 0.1),
            preview_m: distance_m.map(|_| 0.05),
            reason: distance_m
                .is_none()
                .then(|| "no contact in the window".to_owned()),
            true_distance_m: Some(0.3),
            true_angle_rad: Some(0.1),
        }
    }

    #[test]
    fn the_history_keeps_its_window_and_finds_the_estimate_at_a_time() {
        let mut h = EstimateHistory::new(0.5, 1000);
        for seq in 0..100 {
            h.push(estimate(
                seq,
                (seq % 10 != 3).then_some(0.3 + seq as f64 * 1e-4),
            ));
        }
        assert_eq!(h.received(), 100);
        // 0.5 s at 128/s: the estimates of the last 64 intervals, 35 to 99.
        assert_eq!(h.len(), 65);
        assert_eq!(h.iter().next().unwrap().seq, 35);
        assert_eq!(h.latest().unwrap().seq, 99);
        assert_eq!(h.at(75.5 / 128.0).unwrap().seq, 75);
        assert!(h.at(0.1).is_none());
        assert_eq!(h.at(5.0).unwrap().seq, 99);
        // Current for a second after the newest poll (at 128/s); then how long ago it was.
        assert_eq!(h.current_at(1.5).unwrap().unwrap().seq, 99);
        assert_eq!(h.current_at(3.0 + 99.0 / 128.0), Err(3.0));
        assert_eq!(h.current_at(0.1), Ok(None));
        // From the one before 0.6 s (76) to the last: the lines break at 83 and 93, which have
        // no estimate; the truth runs on.
        let (estimated, truth) = h.distance_series_mm(0.6, 0.9, 1000);
        assert_eq!(truth.len(), 1);
        assert_eq!(truth[0].len(), 24);
        assert_eq!(estimated.len(), 3, "{estimated:?}");
        assert_eq!(estimated[0].first().unwrap()[0], 76.0 / 128.0);
        assert!(estimated.iter().flatten().all(|p| p[1] > 300.0));
        assert!(truth.iter().flatten().all(|p| (p[1] - 300.0).abs() < 1e-9));
        // A bound tighter than the window.
        h.set_window(0.5, 10);
        assert_eq!(h.len(), 10);
        // A new daemon: its clock restarted.
        h.push(estimate(1, Some(0.2)));
        assert_eq!(h.len(), 1);
        assert_eq!(h.received(), 101);
    }

    #[test]
    fn the_wall_lies_toward_its_side_of_the_travel() {
        let e = Estimate {
            angle_rad: Some(0.0),
            ..estimate(1, Some(0.3))
        };
        let left = e
            .wall_in_track_m([0.1, 0.0], [1.0, 0.0], WallSide::Left, (-0.1, 0.4))
            .unwrap();
        let near = |p: PointM, q: PointM| (p[0] - q[0]).hypot(p[1] - q[1]) < 1e-12;
        assert!(near(left.ends_m[0], [0.0, 0.3]) && near(left.ends_m[1], [0.5, 0.3]));
        assert!(near(left.at_m, [0.15, 0.3]));
        assert!(left.angle_known);
        let right = e
            .wall_in_track_m([0.1, 0.0], [1.0, 0.0], WallSide::Right, (-0.1, 0.4))
            .unwrap();
        assert!(near(right.at_m, [0.15, -0.3]));
        // Travel along +y: left of it is -x.
        let up = e
            .wall_in_track_m([0.0, 0.0], [0.0, 1.0], WallSide::Left, (0.0, 0.1))
            .unwrap();
        assert!(near(up.at_m, [-0.3, 0.05]));
        // An angle: y = d + (x - preview) tan(angle).
        let sloped = Estimate {
            angle_rad: Some(0.2),
            ..estimate(1, Some(0.3))
        };
        let w = sloped
            .wall_in_track_m([0.0, 0.0], [1.0, 0.0], WallSide::Left, (0.0, 0.3))
            .unwrap();
        let [a, b] = w.ends_m;
        assert!(((b[1] - a[1]) / (b[0] - a[0]) - 0.2f64.tan()).abs() < 1e-12);
        assert!((a[1] - (0.3 - 0.05 * 0.2f64.tan())).abs() < 1e-12);
        // No angle (the bend estimator): parallel to the travel, said so.
        let bend = Estimate {
            angle_rad: None,
            ..estimate(1, Some(0.3))
        };
        let w = bend
            .wall_in_track_m([0.0, 0.0], [1.0, 0.0], WallSide::Left, (0.0, 0.3))
            .unwrap();
        assert!(!w.angle_known && w.ends_m[0][1] == w.ends_m[1][1]);
        // No estimate, no wall.
        assert!(
            estimate(1, None)
                .wall_in_track_m([0.0, 0.0], [1.0, 0.0], WallSide::Left, (0.0, 0.3))
                .is_none()
        );
    }
}
