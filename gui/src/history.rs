//! [`History`]: a bounded ring buffer of polls, columnar, with per-block summaries so that a
//! minute at 1 kHz of a 150-segment chain decimates to screen resolution in well under a
//! millisecond.
//!
//! Every poll is one [`Sample`]: a time, the stage and the servo, and per segment a
//! [`SegmentReading`] (angle, touch bits, health). The buffer keeps the newest
//! [`History::capacity`] samples; older ones are dropped as new ones arrive. Times must not
//! decrease (a sample older than the newest is refused).
//!
//! Queries work on time windows: [`History::index_range`] finds the samples of a window,
//! [`History::envelope`] reduces one segment's angle to a min/max pair per screen column and
//! [`History::touch_spans`] its touch bits to contact intervals at column resolution. Both read
//! whole blocks of [`BLOCK_SAMPLES`] samples from a summary kept up to date on every push,
//! and raw samples only at the ends of a column, so the answer is exact and its cost is
//! `O(columns x (BLOCK_SAMPLES + samples per column / BLOCK_SAMPLES))`.

use std::collections::VecDeque;
use std::ops::Range;

use crate::error::MonitorError;

/// Samples per summary block.
pub const BLOCK_SAMPLES: usize = 64;

/// Why a segment's reading is missing or doubtful.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Health {
    /// A valid, PEC-checked reading.
    Ok,
    /// A valid reading, but the segment's sample counter stopped: old news.
    Stale,
    /// The segment did not acknowledge its address.
    Nack,
    /// The reading's PEC byte was wrong; it was dropped.
    Pec,
    /// Another bus error.
    Bus,
}

impl Health {
    /// Whether the segment is to be drawn as unhealthy.
    pub fn is_unhealthy(self) -> bool {
        self != Health::Ok
    }

    /// Whether the reading failed (no angle, no touch bits).
    pub fn is_failed(self) -> bool {
        matches!(self, Health::Nack | Health::Pec | Health::Bus)
    }

    /// A short word for tables and CSV: `ok`, `stale`, `nack`, `pec`, `bus`.
    pub fn as_str(self) -> &'static str {
        match self {
            Health::Ok => "ok",
            Health::Stale => "stale",
            Health::Nack => "nack",
            Health::Pec => "pec",
            Health::Bus => "bus",
        }
    }

    fn code(self) -> u8 {
        match self {
            Health::Ok => 0,
            Health::Stale => 1,
            Health::Nack => 2,
            Health::Pec => 3,
            Health::Bus => 4,
        }
    }

    fn from_code(code: u8) -> Self {
        match code {
            0 => Health::Ok,
            1 => Health::Stale,
            2 => Health::Nack,
            3 => Health::Pec,
            _ => Health::Bus,
        }
    }
}

/// One segment in one poll.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SegmentReading {
    /// Joint angle, radians (calibrated); `None` when the read failed.
    pub angle_rad: Option<f64>,
    /// Touch bits (bit i: switch i closed), 0..=15; `None` when the read failed.
    pub touch_bits: Option<u8>,
    /// The reading's health.
    pub health: Health,
}

/// One poll of every segment, with the stage and the servo at that instant.
#[derive(Debug, Clone, PartialEq)]
pub struct Sample {
    /// The poll's number (`seq`), if the source has one.
    pub seq: Option<u64>,
    /// Time, seconds: since the daemon started (live) or since the trial started (recording).
    pub t_s: f64,
    /// One entry per segment, base to tip.
    pub segments: Vec<SegmentReading>,
    /// Stage carriage position, metres, if known.
    pub stage_position_m: Option<f64>,
    /// Base servo angle, radians (not counting the base link's mounting angle), if known.
    pub servo_angle_rad: Option<f64>,
}

/// One screen column of [`History::envelope`]: the column's middle time and the angle's
/// range over the samples in it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EnvelopeColumn {
    /// The column's centre, seconds.
    pub t_s: f64,
    /// The smallest valid angle in the column, radians.
    pub min_rad: f64,
    /// The largest valid angle in the column, radians.
    pub max_rad: f64,
}

// Per-segment state byte: touch bits in 0..=3, health code in 4..=6.
const TOUCH_MASK: u8 = 0x0F;
const HEALTH_SHIFT: u8 = 4;

/// Summary of [`BLOCK_SAMPLES`] consecutive samples (by absolute sample number).
#[derive(Debug, Clone)]
struct Block {
    min_rad: Vec<f32>,
    max_rad: Vec<f32>,
    /// OR of the touch bits.
    touch_or: Vec<u8>,
}

impl Block {
    fn new(segments: usize) -> Self {
        Self {
            min_rad: vec![f32::INFINITY; segments],
            max_rad: vec![f32::NEG_INFINITY; segments],
            touch_or: vec![0; segments],
        }
    }
}

/// The bounded, columnar history (see the module documentation).
#[derive(Debug, Clone)]
pub struct History {
    segments: usize,
    capacity: usize,
    /// Physical index of the oldest sample.
    head: usize,
    len: usize,
    /// Samples ever pushed (the absolute number of the next one).
    pushed: u64,
    t_s: Vec<f64>,
    seq: Vec<u64>,
    stage_m: Vec<f64>,
    servo_rad: Vec<f64>,
    angle_rad: Vec<f32>,
    state: Vec<u8>,
    /// Summaries of blocks `first_block..`, by absolute sample number / BLOCK_SAMPLES.
    blocks: VecDeque<Block>,
    first_block: u64,
}

const NO_SEQ: u64 = u64::MAX;

impl History {
    /// An empty history of `segments` segments keeping at most `capacity` samples (at least
    /// one).
    pub fn new(segments: usize, capacity: usize) -> Self {
        let capacity = capacity.max(1);
        Self {
            segments,
            capacity,
            head: 0,
            len: 0,
            pushed: 0,
            t_s: Vec::new(),
            seq: Vec::new(),
            stage_m: Vec::new(),
            servo_rad: Vec::new(),
            angle_rad: Vec::new(),
            state: Vec::new(),
            blocks: VecDeque::new(),
            first_block: 0,
        }
    }

    /// Segments per sample.
    pub fn segment_count(&self) -> usize {
        self.segments
    }

    /// The most samples kept.
    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// Samples held now.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether no sample is held.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Samples pushed since the history was made (those dropped for age included).
    pub fn total_pushed(&self) -> u64 {
        self.pushed
    }

    /// Changes the capacity, keeping the newest samples that fit.
    pub fn set_capacity(&mut self, capacity: usize) {
        let capacity = capacity.max(1);
        if capacity == self.capacity {
            return;
        }
        let keep = self.len.min(capacity);
        let mut fresh = History::new(self.segments, capacity);
        fresh.pushed = self.pushed - keep as u64;
        fresh.first_block = fresh.pushed / BLOCK_SAMPLES as u64;
        for sample in (self.len - keep..self.len).filter_map(|i| self.sample(i)) {
            fresh.push_unchecked(&sample);
        }
        *self = fresh;
    }

    /// Appends a poll, dropping the oldest when full. Refused if the sample has the wrong
    /// number of segments or is older than the newest one.
    pub fn push(&mut self, sample: &Sample) -> Result<(), MonitorError> {
        if sample.segments.len() != self.segments {
            return Err(MonitorError::SegmentCount {
                expected: self.segments,
                found: sample.segments.len(),
            });
        }
        if !sample.t_s.is_finite() {
            return Err(MonitorError::TimeOrder {
                t_s: sample.t_s,
                latest_t_s: self.latest_t_s().unwrap_or(f64::NAN),
            });
        }
        if let Some(latest) = self.latest_t_s()
            && sample.t_s < latest
        {
            return Err(MonitorError::TimeOrder {
                t_s: sample.t_s,
                latest_t_s: latest,
            });
        }
        self.push_unchecked(sample);
        Ok(())
    }

    fn push_unchecked(&mut self, sample: &Sample) {
        let n = self.segments;
        let slot = if self.t_s.len() < self.capacity {
            // Still growing: the buffer is in order from index 0.
            self.t_s.push(0.0);
            self.seq.push(0);
            self.stage_m.push(0.0);
            self.servo_rad.push(0.0);
            self.angle_rad.resize(self.angle_rad.len() + n, 0.0);
            self.state.resize(self.state.len() + n, 0);
            self.len += 1;
            self.t_s.len() - 1
        } else if self.len < self.capacity {
            let slot = (self.head + self.len) % self.capacity;
            self.len += 1;
            slot
        } else {
            let slot = self.head;
            self.head = (self.head + 1) % self.capacity;
            slot
        };
        self.t_s[slot] = sample.t_s;
        self.seq[slot] = sample.seq.unwrap_or(NO_SEQ);
        self.stage_m[slot] = sample.stage_position_m.unwrap_or(f64::NAN);
        self.servo_rad[slot] = sample.servo_angle_rad.unwrap_or(f64::NAN);
        let abs = self.pushed;
        self.pushed += 1;
        let block_number = abs / BLOCK_SAMPLES as u64;
        while self.first_block + self.blocks.len() as u64 <= block_number {
            self.blocks.push_back(Block::new(n));
        }
        // Drop summaries of blocks whose samples are all gone.
        let oldest_abs = self.pushed - self.len as u64;
        while self.blocks.len() > 1 && (self.first_block + 1) * (BLOCK_SAMPLES as u64) <= oldest_abs
        {
            self.blocks.pop_front();
            self.first_block += 1;
        }
        let block_index = (block_number - self.first_block) as usize;
        let block = &mut self.blocks[block_index];
        for (k, reading) in sample.segments.iter().enumerate() {
            let angle = reading.angle_rad.map_or(f32::NAN, |v| v as f32);
            let touch = reading.touch_bits.unwrap_or(0) & TOUCH_MASK;
            self.angle_rad[slot * n + k] = angle;
            self.state[slot * n + k] = touch | (reading.health.code() << HEALTH_SHIFT);
            if angle.is_finite() {
                block.min_rad[k] = block.min_rad[k].min(angle);
                block.max_rad[k] = block.max_rad[k].max(angle);
            }
            block.touch_or[k] |= touch;
        }
    }

    /// Physical slot of logical index `i` (0 = oldest held).
    fn slot(&self, i: usize) -> usize {
        (self.head + i) % self.capacity
    }

    /// Time of the sample at logical index `i` (0 = oldest held), seconds.
    pub fn t_s(&self, i: usize) -> Option<f64> {
        (i < self.len).then(|| self.t_s[self.slot(i)])
    }

    /// The oldest sample's time, seconds.
    pub fn first_t_s(&self) -> Option<f64> {
        self.t_s(0)
    }

    /// The newest sample's time, seconds.
    pub fn latest_t_s(&self) -> Option<f64> {
        self.len.checked_sub(1).and_then(|i| self.t_s(i))
    }

    /// Joint angle of `segment` at index `i`, radians (`None`: failed read or out of range).
    pub fn angle_rad(&self, i: usize, segment: usize) -> Option<f64> {
        if i >= self.len || segment >= self.segments {
            return None;
        }
        let v = self.angle_rad[self.slot(i) * self.segments + segment];
        v.is_finite().then_some(f64::from(v))
    }

    /// Touch bits and health of `segment` at index `i`.
    pub fn touch_and_health(&self, i: usize, segment: usize) -> Option<(u8, Health)> {
        if i >= self.len || segment >= self.segments {
            return None;
        }
        let s = self.state[self.slot(i) * self.segments + segment];
        Some((s & TOUCH_MASK, Health::from_code(s >> HEALTH_SHIFT)))
    }

    /// The newest valid angle of `segment` at or before index `i`, looking back at most
    /// `max_back` samples: what to draw for a segment whose read just failed.
    pub fn last_valid_angle_rad(&self, i: usize, segment: usize, max_back: usize) -> Option<f64> {
        let i = i.min(self.len.checked_sub(1)?);
        (i.saturating_sub(max_back)..=i)
            .rev()
            .find_map(|j| self.angle_rad(j, segment))
    }

    /// The whole sample at index `i` (0 = oldest held).
    pub fn sample(&self, i: usize) -> Option<Sample> {
        if i >= self.len {
            return None;
        }
        let slot = self.slot(i);
        let n = self.segments;
        let opt = |v: f64| v.is_finite().then_some(v);
        Some(Sample {
            seq: (self.seq[slot] != NO_SEQ).then_some(self.seq[slot]),
            t_s: self.t_s[slot],
            segments: (0..n)
                .map(|k| {
                    let s = self.state[slot * n + k];
                    let health = Health::from_code(s >> HEALTH_SHIFT);
                    SegmentReading {
                        angle_rad: opt(f64::from(self.angle_rad[slot * n + k])),
                        touch_bits: (!health.is_failed()).then_some(s & TOUCH_MASK),
                        health,
                    }
                })
                .collect(),
            stage_position_m: opt(self.stage_m[slot]),
            servo_angle_rad: opt(self.servo_rad[slot]),
        })
    }

    /// The index of the newest sample at or before `t_s` (the oldest if all are later).
    pub fn index_at(&self, t_s: f64) -> Option<usize> {
        if self.len == 0 {
            return None;
        }
        Some(self.lower_bound_after(t_s).saturating_sub(1))
    }

    /// Number of samples with time `<= t_s` (a partition point over the ring).
    fn lower_bound_after(&self, t_s: f64) -> usize {
        let (mut lo, mut hi) = (0, self.len);
        while lo < hi {
            let mid = (lo + hi) / 2;
            if self.t_s[self.slot(mid)] <= t_s {
                lo = mid + 1;
            } else {
                hi = mid;
            }
        }
        lo
    }

    /// Number of samples with time `< t_s`.
    fn lower_bound(&self, t_s: f64) -> usize {
        let (mut lo, mut hi) = (0, self.len);
        while lo < hi {
            let mid = (lo + hi) / 2;
            if self.t_s[self.slot(mid)] < t_s {
                lo = mid + 1;
            } else {
                hi = mid;
            }
        }
        lo
    }

    /// The indices of the samples with `t0_s <= t <= t1_s`.
    pub fn index_range(&self, t0_s: f64, t1_s: f64) -> Range<usize> {
        let start = self.lower_bound(t0_s);
        let end = self.lower_bound_after(t1_s).max(start);
        start..end
    }

    /// Splits `t0_s..=t1_s` into `columns` equal columns and returns each one's sample range.
    fn column_ranges(&self, t0_s: f64, t1_s: f64, columns: usize) -> Vec<(f64, Range<usize>)> {
        let columns = columns.max(1);
        let width = (t1_s - t0_s) / columns as f64;
        let mut out = Vec::with_capacity(columns);
        let mut start = self.lower_bound(t0_s);
        for c in 0..columns {
            let right = if c + 1 == columns {
                self.lower_bound_after(t1_s)
            } else {
                self.lower_bound(t0_s + width * (c + 1) as f64)
            };
            let right = right.max(start);
            out.push((t0_s + width * (c as f64 + 0.5), start..right));
            start = right;
        }
        out
    }

    /// Folds over the samples of `range`: whole summary blocks through `block`, the samples
    /// at the ends through `sample`.
    fn fold_range<A>(
        &self,
        range: Range<usize>,
        init: A,
        sample: impl Fn(A, usize) -> A,
        block: impl Fn(A, &Block) -> A,
    ) -> A {
        let base_abs = self.pushed - self.len as u64;
        let b = BLOCK_SAMPLES as u64;
        let (abs0, abs1) = (base_abs + range.start as u64, base_abs + range.end as u64);
        // Whole blocks strictly inside [abs0, abs1) whose summaries cover only held samples.
        let first_whole = abs0.div_ceil(b).max(base_abs.div_ceil(b));
        let last_whole = abs1 / b; // exclusive
        if first_whole >= last_whole {
            return range.fold(init, sample);
        }
        let mut acc = (range.start..(first_whole * b - base_abs) as usize).fold(init, &sample);
        for number in first_whole..last_whole {
            if let Some(summary) = number
                .checked_sub(self.first_block)
                .and_then(|k| self.blocks.get(k as usize))
            {
                acc = block(acc, summary);
            }
        }
        ((last_whole * b - base_abs) as usize..range.end).fold(acc, sample)
    }

    /// `segment`'s angle over `t0_s..=t1_s` reduced to at most `columns` columns, each its
    /// centre time and the min and max valid angle in it (columns without a valid angle are
    /// left out). A line through `(t, min), (t, max)` of every column draws every sample's
    /// extent at screen resolution.
    pub fn envelope(
        &self,
        segment: usize,
        t0_s: f64,
        t1_s: f64,
        columns: usize,
    ) -> Vec<EnvelopeColumn> {
        if segment >= self.segments || t1_s.partial_cmp(&t0_s) != Some(std::cmp::Ordering::Greater)
        {
            return Vec::new();
        }
        let n = self.segments;
        self.column_ranges(t0_s, t1_s, columns)
            .into_iter()
            .filter_map(|(t_s, range)| {
                let (lo, hi) = self.fold_range(
                    range,
                    (f32::INFINITY, f32::NEG_INFINITY),
                    |(lo, hi), i| {
                        // f32::min and max skip a NaN (a failed read).
                        let v = self.angle_rad[self.slot(i) * n + segment];
                        (lo.min(v), hi.max(v))
                    },
                    |(lo, hi), block| {
                        (
                            lo.min(block.min_rad[segment]),
                            hi.max(block.max_rad[segment]),
                        )
                    },
                );
                (lo <= hi).then(|| EnvelopeColumn {
                    t_s,
                    min_rad: f64::from(lo),
                    max_rad: f64::from(hi),
                })
            })
            .collect()
    }

    /// The intervals of `t0_s..=t1_s` (at the resolution of `columns` columns) in which any
    /// touch bit of `segment` was set, merged, as `(start_s, end_s)`.
    pub fn touch_spans(
        &self,
        segment: usize,
        t0_s: f64,
        t1_s: f64,
        columns: usize,
    ) -> Vec<(f64, f64)> {
        self.touch_spans_all(t0_s, t1_s, columns)
            .into_iter()
            .nth(segment)
            .unwrap_or_default()
    }

    /// [`History::touch_spans`] of every segment at once, in one pass over the samples
    /// (they are stored sample by sample, so this reads memory in order).
    pub fn touch_spans_all(&self, t0_s: f64, t1_s: f64, columns: usize) -> Vec<Vec<(f64, f64)>> {
        let n = self.segments;
        let mut spans: Vec<Vec<(f64, f64)>> = vec![Vec::new(); n];
        if t1_s.partial_cmp(&t0_s) != Some(std::cmp::Ordering::Greater) {
            return spans;
        }
        let columns = columns.max(1);
        let half = (t1_s - t0_s) / columns as f64 / 2.0;
        let mut touched = vec![0u8; n];
        for (t_s, range) in self.column_ranges(t0_s, t1_s, columns) {
            touched.fill(0);
            touched = self.fold_range(
                range,
                touched,
                |mut acc, i| {
                    let row = &self.state[self.slot(i) * n..][..n];
                    for (a, &s) in acc.iter_mut().zip(row) {
                        *a |= s & TOUCH_MASK;
                    }
                    acc
                },
                |mut acc, block| {
                    for (a, &b) in acc.iter_mut().zip(&block.touch_or) {
                        *a |= b;
                    }
                    acc
                },
            );
            let (start, end) = (t_s - half, t_s + half);
            for (segment, _) in touched.iter().enumerate().filter(|(_, t)| **t != 0) {
                let list = &mut spans[segment];
                match list.last_mut() {
                    Some(last) if (last.1 - start).abs() <= half * 1e-6 => last.1 = end,
                    _ => list.push((start, end)),
                }
            }
        }
        spans
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(i: u64, segments: usize) -> Sample {
        Sample {
            seq: Some(i),
            t_s: i as f64 * 1e-3,
            segments: (0..segments)
                .map(|k| SegmentReading {
                    angle_rad: Some((i as f64 * 0.01 + k as f64).sin()),
                    touch_bits: Some(if i % 100 < 10 && k == 0 { 0b1000 } else { 0 }),
                    health: Health::Ok,
                })
                .collect(),
            stage_position_m: Some(i as f64 * 1e-4),
            servo_angle_rad: None,
        }
    }

    #[test]
    fn keeps_the_newest_capacity_samples_in_order() {
        let mut h = History::new(2, 100);
        for i in 0..250 {
            h.push(&sample(i, 2)).unwrap();
        }
        assert_eq!(h.len(), 100);
        assert_eq!(h.total_pushed(), 250);
        assert_eq!(h.first_t_s(), Some(0.150));
        assert_eq!(h.latest_t_s(), Some(0.249));
        assert_eq!(h.sample(0), Some(sample(150, 2).rounded()));
        h.set_capacity(10);
        assert_eq!(h.len(), 10);
        assert_eq!(h.first_t_s(), Some(0.240));
        h.set_capacity(1000);
        assert_eq!(h.len(), 10);
        h.push(&sample(250, 2)).unwrap();
        assert_eq!(h.len(), 11);
    }

    #[test]
    fn refuses_wrong_segment_counts_and_older_samples() {
        let mut h = History::new(2, 10);
        h.push(&sample(5, 2)).unwrap();
        assert!(matches!(
            h.push(&sample(6, 3)),
            Err(MonitorError::SegmentCount {
                expected: 2,
                found: 3
            })
        ));
        assert!(matches!(
            h.push(&sample(4, 2)),
            Err(MonitorError::TimeOrder { .. })
        ));
    }

    /// The block-accelerated envelope equals a brute-force one over every column, for
    /// windows that start and end inside blocks and a ring that has wrapped.
    #[test]
    fn envelope_and_touch_spans_match_brute_force() {
        let mut h = History::new(3, 5000);
        for i in 0..7777 {
            let mut s = sample(i, 3);
            if i % 333 == 0 {
                s.segments[1] = SegmentReading {
                    angle_rad: None,
                    touch_bits: None,
                    health: Health::Nack,
                };
            }
            h.push(&s).unwrap();
        }
        for &(t0, t1, columns) in &[
            (2.8, 7.7, 37),
            (3.0001, 3.9, 500),
            (5.0, 5.05, 400),
            (0.0, 10.0, 3),
        ] {
            for segment in 0..3 {
                let fast = h.envelope(segment, t0, t1, columns);
                let slow: Vec<EnvelopeColumn> = h
                    .column_ranges(t0, t1, columns)
                    .into_iter()
                    .filter_map(|(t_s, r)| {
                        let values: Vec<f64> = r.filter_map(|i| h.angle_rad(i, segment)).collect();
                        let lo = values.iter().copied().fold(f64::INFINITY, f64::min);
                        let hi = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                        (!values.is_empty()).then_some(EnvelopeColumn {
                            t_s,
                            min_rad: lo,
                            max_rad: hi,
                        })
                    })
                    .collect();
                assert_eq!(fast, slow, "segment {segment} window {t0}..{t1}");
                let spans = h.touch_spans(segment, t0, t1, columns);
                let touched_columns = h
                    .column_ranges(t0, t1, columns)
                    .into_iter()
                    .filter(|(_, r)| {
                        r.clone()
                            .any(|i| h.touch_and_health(i, segment).is_some_and(|(t, _)| t != 0))
                    })
                    .count();
                let width = (t1 - t0) / columns as f64;
                let covered: f64 = spans.iter().map(|(a, b)| b - a).sum();
                assert!(
                    (covered / width - touched_columns as f64).abs() < 1e-6,
                    "segment {segment}: {covered} s vs {touched_columns} columns"
                );
            }
        }
    }

    #[test]
    fn index_queries() {
        let mut h = History::new(1, 100);
        for i in 0..50 {
            h.push(&sample(i, 1)).unwrap();
        }
        assert_eq!(h.index_range(0.0105, 0.020), 11..21);
        assert_eq!(h.index_at(0.0105), Some(10));
        assert_eq!(h.index_at(-1.0), Some(0));
        assert_eq!(h.index_at(9.0), Some(49));
        assert_eq!(h.last_valid_angle_rad(49, 0, 10), h.angle_rad(49, 0));
    }

    impl Sample {
        /// The sample as stored (angles as f32).
        fn rounded(mut self) -> Self {
            let r = |v: Option<f64>| v.map(|x| f64::from(x as f32));
            for s in &mut self.segments {
                s.angle_rad = r(s.angle_rad);
            }
            self
        }
    }
}
