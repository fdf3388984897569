//! The chain: segments, joints, touch switches lit where they fire, contact points (a
//! simulated sweep's), hairs, walls, the base and the stage, the measured chain overlaid
//! with sim-core's prediction for the same base pose and wall, and the difference between
//! them.
//!
//! The base need not ride a stage along x: a frame's path ([`ChainFrame::path_m`]: a sweep's
//! straight track in any direction, a follow run's path so far) is drawn as the track, and a
//! closed-loop run's robot ([`crate::frame::BodyDrawing`]) as its footprint at its pose and
//! heading (red while it overlaps a wall), with the estimator's points and the estimated wall
//! point. Such a view either follows the robot or fits the whole run ([`TopView`]).
//!
//! antennad's wall estimate, live or recorded ([`ChainFrame::estimated_wall`]), is drawn over the chain
//! when **estimate** is ticked: the estimated wall as a bluish green line (dashed when the
//! estimator gives no angle: drawn parallel to the stage's travel), a cross where its distance
//! is measured (the preview point), and the reason in the legend when there is no estimate.
//!
//! Touches are drawn from the frame alone, so live, recorded and simulated chains show them
//! the same way: a link whose segment has any touch bit set is drawn red, and each switch
//! that fires is a dot at its place along the link ([`ChainFrame::lit_switches`]); the
//! prediction's switches are rings.
//!
//! A simulated sweep's wall map ([`WallMap`], [`crate::mapping`]) is drawn over the walls when
//! **wall map** is ticked: the wall section passed up to the step shown, sampled along its
//! length and shaded by each sample's distance to the nearest estimated contact point
//! ([`coverage_colour`]: captured, bluish green, to missed, vermillion, at the completeness
//! threshold), on a dark band so that it reads on either theme; the estimated points as small
//! dots (as in the thesis's Figures 4.15 and 4.16); a colour bar in the panel's lower right
//! corner; and the numbers (mean and 90th percentile coverage error, completeness, points) in
//! the row above the panel.

use std::collections::HashSet;

use egui::{Align2, Color32, FontId, Pos2, Rect, RichText, Sense, Shape, Stroke, Vec2};
use nalgebra::Vector2;
use sim_core::{Coverage, CoverageSettings, Wall};

use crate::frame::{ChainFrame, PointM};
use crate::mapping::{COLOUR_BANDS, coverage_band, coverage_colour, coverage_summary};

/// The measured chain's colour (the screenshot check looks for it).
pub const CHAIN_COLOUR: Color32 = Color32::from_rgb(30, 110, 255);
/// A link whose segment's touch switches fire.
pub const TOUCH_COLOUR: Color32 = Color32::from_rgb(255, 40, 90);
/// The predicted chain.
pub const PREDICTED_COLOUR: Color32 = Color32::from_rgb(255, 160, 0);
/// A segment that is not healthy.
pub const UNHEALTHY_COLOUR: Color32 = Color32::from_rgb(150, 150, 150);
const WALL_COLOUR: Color32 = Color32::from_rgb(170, 140, 110);
const DIFFERENCE_COLOUR: Color32 = Color32::from_rgb(255, 0, 255);
const TRACK_COLOUR: Color32 = Color32::from_rgb(110, 110, 110);
/// A closed-loop run's body outline.
const BODY_COLOUR: Color32 = Color32::from_rgb(90, 90, 90);
/// The body while its footprint overlaps a wall.
const COLLIDED_COLOUR: Color32 = Color32::from_rgb(230, 0, 0);
/// The estimator's points and the estimated wall point (bluish green).
const ESTIMATE_COLOUR: Color32 = Color32::from_rgb(0, 158, 115);
/// How far around the robot a view that follows it shows at least, metres.
const FOLLOW_MARGIN_M: f64 = 0.15;
/// The band under the wall map's colours.
const MAP_UNDERLAY_COLOUR: Color32 = Color32::from_rgb(35, 35, 35);

/// The chain panel (see the module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct ChainPanel {
    /// Draw the prediction.
    pub show_prediction: bool,
    /// Draw the measured-to-predicted difference.
    pub show_difference: bool,
    /// Draw a sweep's wall map.
    pub show_map: bool,
    /// Draw antennad's wall estimate (live or recorded).
    pub show_estimate: bool,
    /// A moving robot's view: following it, or the whole run.
    pub top_view: TopView,
}

/// What a closed-loop run's top view shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TopView {
    /// The robot, its antenna and what is around it, moving with it.
    FollowRobot,
    /// The whole run (its extent: every pose's footprint and antenna).
    FitRun,
}

impl Default for ChainPanel {
    fn default() -> Self {
        Self {
            show_prediction: true,
            show_difference: true,
            show_map: true,
            show_estimate: true,
            top_view: TopView::FollowRobot,
        }
    }
}

/// A simulated sweep's wall map up to the step shown (see the module documentation).
#[derive(Debug, Clone, Copy)]
pub struct WallMap<'a> {
    /// The coverage of the wall passed by the points estimated up to the step mapped, or why
    /// it could not be computed; `None` while it is not (yet) computed.
    pub coverage: Option<Result<&'a Coverage, &'a str>>,
    /// The points estimated up to the step mapped, ground frame, metres.
    pub points_m: &'a [Vector2<f64>],
    /// The wall sampling and the completeness threshold the coverage was computed with.
    pub settings: CoverageSettings,
    /// The walls the samples are on (their solid side is where the map's band is drawn).
    pub walls: &'a [Wall],
}

/// Maps track-frame metres to screen points, y up, equal scales.
struct ToScreen {
    centre_m: PointM,
    centre_px: Pos2,
    px_per_m: f32,
}

impl ToScreen {
    /// The scale and centre that show the points `points_m` in `rect`.
    fn fit(rect: Rect, points_m: impl Iterator<Item = PointM>) -> Self {
        let (mut min, mut max) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in points_m.filter(|p| p[0].is_finite() && p[1].is_finite()) {
            min = [min[0].min(p[0]), min[1].min(p[1])];
            max = [max[0].max(p[0]), max[1].max(p[1])];
        }
        if !(min[0] <= max[0] && min[1] <= max[1]) {
            (min, max) = ([0.0; 2], [0.0; 2]);
        }
        let span = [(max[0] - min[0]).max(0.02), (max[1] - min[1]).max(0.02)];
        let scale =
            (f64::from(rect.width()) / span[0]).min(f64::from(rect.height()) / span[1]) * 0.9;
        Self {
            centre_m: [(min[0] + max[0]) / 2.0, (min[1] + max[1]) / 2.0],
            centre_px: rect.center(),
            px_per_m: scale as f32,
        }
    }

    fn pos(&self, p: PointM) -> Pos2 {
        Pos2::new(
            self.centre_px.x + ((p[0] - self.centre_m[0]) as f32) * self.px_per_m,
            self.centre_px.y - ((p[1] - self.centre_m[1]) as f32) * self.px_per_m,
        )
    }
}

impl ChainPanel {
    /// Draws `measured` (and `predicted`, for the same base pose) in the space available.
    /// `model` names the prediction's model; `note` says why there is none, if there is none.
    pub fn ui(
        &mut self,
        ui: &mut egui::Ui,
        measured: Option<&ChainFrame>,
        predicted: Option<&ChainFrame>,
        model: &str,
        note: Option<&str>,
        map: Option<&WallMap<'_>>,
    ) {
        ui.horizontal(|ui| {
            if measured.is_some_and(|m| m.run_extent_m.is_some()) {
                ui.selectable_value(&mut self.top_view, TopView::FollowRobot, "follow robot");
                ui.selectable_value(&mut self.top_view, TopView::FitRun, "fit run");
                ui.separator();
            }
            ui.checkbox(&mut self.show_prediction, "prediction");
            ui.checkbox(&mut self.show_difference, "difference");
            if measured.is_some_and(|m| m.estimated_wall.is_some() || m.estimate_note.is_some()) {
                ui.checkbox(&mut self.show_estimate, "estimate");
            }
            if let Some(map) = map {
                if ui.checkbox(&mut self.show_map, "wall map").changed() {
                    ui.ctx().request_repaint();
                }
                match map.coverage.filter(|_| self.show_map) {
                    Some(Ok(c)) => {
                        ui.label(coverage_summary(
                            c,
                            map.points_m.len(),
                            map.settings.complete_within_m * 1e3,
                        ));
                    }
                    Some(Err(e)) => {
                        ui.label(RichText::new(format!("wall map: {e}")).color(Color32::RED));
                    }
                    None => {}
                }
            }
            if let (Some(m), Some(p)) = (measured, predicted)
                && let Some(d) = m.difference(p)
            {
                ui.label(format!(
                    "measured vs predicted: max {:.1} mm, tip {:.1} mm",
                    d.max_m * 1e3,
                    d.tip_m * 1e3
                ));
            } else if let Some(note) = note {
                ui.label(format!("no prediction: {note}"));
            }
        });
        let (response, painter) = ui.allocate_painter(ui.available_size(), Sense::hover());
        let rect = response.rect;
        // A border, not a fill: one less full layer for a software renderer to blend.
        painter.rect_stroke(
            rect,
            4.0,
            ui.visuals().widgets.noninteractive.bg_stroke,
            egui::StrokeKind::Inside,
        );
        let Some(measured) = measured else {
            painter.text(
                rect.center(),
                Align2::CENTER_CENTER,
                "no chain yet",
                FontId::proportional(18.0),
                ui.visuals().weak_text_color(),
            );
            return;
        };
        let predicted = predicted.filter(|_| self.show_prediction);
        let mut frames = vec![measured];
        frames.extend(predicted);
        let map = map.filter(|_| self.show_map);
        let mapped = map.and_then(|m| m.coverage.and_then(Result::ok).map(|c| (m, c)));
        // With a map: the wall passed in view too, below the legend's three lines.
        let mut fit_rect = rect.shrink(8.0);
        if mapped.is_some() {
            fit_rect.min.y = (fit_rect.min.y + 44.0).min(fit_rect.max.y);
        }
        let map_points_m = mapped
            .into_iter()
            .flat_map(|(_, c)| c.samples.iter().map(|s| [s.point_m.x, s.point_m.y]));
        let corners = |(a, b): (PointM, PointM)| [a, b];
        let to = match (measured.run_extent_m, &measured.body, self.top_view) {
            (Some(extent), _, TopView::FitRun) => ToScreen::fit(
                fit_rect,
                frames
                    .iter()
                    .flat_map(|f| corners(f.local_bounds_m()))
                    .chain(corners(extent)),
            ),
            (Some(_), Some(body), TopView::FollowRobot) => {
                let m = FOLLOW_MARGIN_M;
                let around = [
                    [body.por_m[0] - m, body.por_m[1] - m],
                    [body.por_m[0] + m, body.por_m[1] + m],
                ];
                ToScreen::fit(
                    fit_rect,
                    frames
                        .iter()
                        .flat_map(|f| corners(f.local_bounds_m()))
                        .chain(around)
                        .chain(body.estimated_wall_m),
                )
            }
            _ => ToScreen::fit(
                fit_rect,
                frames
                    .iter()
                    .flat_map(|f| corners(f.bounds_m()))
                    .chain(map_points_m),
            ),
        };
        let painter = painter.with_clip_rect(rect);

        // The track (a moving base's path, or the stage's soft limits), the wall, the base
        // and the stage carriage (or the robot's body).
        if measured.path_m.len() >= 2 {
            let points: Vec<Pos2> = measured.path_m.iter().map(|p| to.pos(*p)).collect();
            painter.add(Shape::line(points, Stroke::new(2.0, TRACK_COLOUR)));
        } else if let Some((lo, hi)) = measured.stage_range_m {
            painter.line_segment(
                [to.pos([lo, 0.0]), to.pos([hi, 0.0])],
                Stroke::new(2.0, TRACK_COLOUR),
            );
        }
        for wall in &measured.walls_m {
            let points: Vec<Pos2> = wall.iter().map(|p| to.pos(*p)).collect();
            painter.add(Shape::line(points, Stroke::new(5.0, WALL_COLOUR)));
        }
        if let Some((map, coverage)) = mapped {
            paint_wall_map(
                &painter,
                &to,
                map,
                coverage,
                to.pos(measured.base_m),
                ui.visuals().strong_text_color(),
            );
        }
        let estimated_wall = measured
            .estimated_wall
            .as_ref()
            .filter(|_| self.show_estimate);
        if let Some(wall) = estimated_wall {
            let ends = wall.ends_m.map(|p| to.pos(p));
            let stroke = Stroke::new(3.0, ESTIMATE_COLOUR);
            if wall.angle_known {
                painter.line_segment(ends, stroke);
            } else {
                painter.add(Shape::dashed_line(&ends, stroke, 10.0, 6.0));
            }
            let at = to.pos(wall.at_m);
            let r = 6.0;
            let cross = Stroke::new(2.0, ESTIMATE_COLOUR);
            painter.line_segment([at + Vec2::new(-r, -r), at + Vec2::new(r, r)], cross);
            painter.line_segment([at + Vec2::new(-r, r), at + Vec2::new(r, -r)], cross);
        }
        let base = to.pos(measured.base_m);
        if let Some(body) = &measured.body {
            let colour = if body.collided {
                COLLIDED_COLOUR
            } else {
                BODY_COLOUR
            };
            let outline: Vec<Pos2> = body.corners_m.iter().map(|p| to.pos(*p)).collect();
            painter.add(Shape::closed_line(outline, Stroke::new(2.0, colour)));
            // The heading: from the point of rotation to the front edge's middle.
            let [front_right, front_left, ..] = body.corners_m;
            let front = [
                (front_right[0] + front_left[0]) / 2.0,
                (front_right[1] + front_left[1]) / 2.0,
            ];
            painter.arrow(
                to.pos(body.por_m),
                to.pos(front) - to.pos(body.por_m),
                Stroke::new(1.5, colour),
            );
            painter.circle_filled(to.pos(body.por_m), 3.5, colour);
            for p in &measured.estimated_points_m {
                painter.circle_filled(to.pos(*p), 2.5, ESTIMATE_COLOUR);
            }
            if let Some(p) = body.estimated_wall_m {
                let at = to.pos(p);
                let r = 6.0;
                let stroke = Stroke::new(2.0, ESTIMATE_COLOUR);
                painter.line_segment([at + Vec2::new(-r, -r), at + Vec2::new(r, r)], stroke);
                painter.line_segment([at + Vec2::new(-r, r), at + Vec2::new(r, -r)], stroke);
            }
        } else {
            painter.rect_filled(
                Rect::from_center_size(base, Vec2::new(22.0, 10.0)),
                2.0,
                TRACK_COLOUR,
            );
        }

        if let Some(p) = predicted {
            let points: Vec<Pos2> = p.joints_m.iter().map(|q| to.pos(*q)).collect();
            painter.add(Shape::dashed_line(
                &points,
                Stroke::new(2.5, PREDICTED_COLOUR),
                8.0,
                4.0,
            ));
            paint_lit_switches(&painter, &to, p, SwitchMark::Ring(PREDICTED_COLOUR));
            if self.show_difference {
                for (a, b) in measured.joints_m.iter().zip(&p.joints_m) {
                    painter.line_segment(
                        [to.pos(*a), to.pos(*b)],
                        Stroke::new(1.0, DIFFERENCE_COLOUR),
                    );
                }
            }
        }

        // The measured chain: the base link, then one link per segment.
        let width = (to.px_per_m * 0.004).clamp(2.0, 6.0);
        if let Some((a, b)) = measured.link_m(0) {
            painter.line_segment([to.pos(a), to.pos(b)], Stroke::new(width, TRACK_COLOUR));
        }
        for (k, segment) in measured.segments.iter().enumerate() {
            let Some((a, b)) = measured.link_m(k + 1) else {
                continue;
            };
            let (pa, pb) = (to.pos(a), to.pos(b));
            if segment.health.is_unhealthy() {
                painter.add(Shape::dashed_line(
                    &[pa, pb],
                    Stroke::new(width, UNHEALTHY_COLOUR),
                    5.0,
                    4.0,
                ));
                let c = pa.lerp(pb, 0.5);
                let r = 5.0;
                let cross = Stroke::new(2.0, Color32::RED);
                painter.line_segment([c + Vec2::new(-r, -r), c + Vec2::new(r, r)], cross);
                painter.line_segment([c + Vec2::new(-r, r), c + Vec2::new(r, -r)], cross);
                painter.text(
                    c + Vec2::new(8.0, -8.0),
                    Align2::LEFT_BOTTOM,
                    segment.health.as_str(),
                    FontId::proportional(11.0),
                    Color32::RED,
                );
            } else {
                let colour = if segment.touched() {
                    TOUCH_COLOUR
                } else {
                    CHAIN_COLOUR
                };
                painter.line_segment([pa, pb], Stroke::new(width, colour));
            }
        }
        // The touch switches along the links, lit where they fire.
        paint_lit_switches(&painter, &to, measured, SwitchMark::Dot(width * 0.9 + 1.0));
        // Joint circles only where they do not crowd each other.
        let spacing_px = measured
            .link_m(1)
            .map_or(0.0, |(a, b)| to.pos(a).distance(to.pos(b)));
        let distal = measured.joints_m.get(1..).unwrap_or_default();
        for p in distal.iter().filter(|_| spacing_px >= 8.0) {
            painter.circle(
                to.pos(*p),
                width * 0.8,
                ui.visuals().panel_fill,
                Stroke::new(1.5, CHAIN_COLOUR),
            );
        }
        for hair in &measured.hairs {
            painter.line_segment(
                [to.pos(hair.root_m), to.pos(hair.tip_m)],
                Stroke::new(1.5, CHAIN_COLOUR),
            );
        }
        // Where the chain touches a wall (a simulation knows the points).
        for p in &measured.contacts_m {
            painter.circle_stroke(to.pos(*p), 5.0, Stroke::new(2.0, TOUCH_COLOUR));
        }
        painter.circle_filled(base, 4.0, Color32::BLACK);

        let mut legend = format!(
            "t = {:.3} s   base {:.1} deg",
            measured.t_s,
            measured.base_angle_rad.to_degrees()
        );
        if let Some(x) = measured.stage_position_m {
            legend.push_str(&format!("   stage {:.1} mm", x * 1e3));
        }
        if let Some(body) = &measured.body {
            legend.push_str(&format!(
                "   heading {:.1} deg{}",
                body.heading_rad.to_degrees(),
                if body.collided { "   IN A WALL" } else { "" }
            ));
        }
        legend.push_str(
            "\nblue: measured   red: touched, dots: the switches that fire   grey dashed: unhealthy",
        );
        if !measured.contacts_m.is_empty() {
            legend.push_str("   red rings: contact points");
        }
        if predicted.is_some() {
            legend.push_str(&format!("\norange dashed: predicted ({model})"));
        }
        if let Some(wall) = estimated_wall {
            legend.push_str(&format!(
                "\ngreen{}: the estimated wall ({}{}), cross: its distance at the preview",
                if wall.angle_known { "" } else { " dashed" },
                wall.estimator,
                if wall.angle_known {
                    ""
                } else {
                    ": no angle, drawn along the travel"
                }
            ));
        } else if let Some(note) = measured
            .estimate_note
            .as_ref()
            .filter(|_| self.show_estimate)
        {
            legend.push_str(&format!("\nno wall estimate: {note}"));
        }
        if measured.body.is_some() {
            legend.push_str(
                "\ngrey: the body (red: in a wall), its path   green dots: the estimator's \
                 points   green cross: the estimated wall",
            );
        }
        if mapped.is_some() {
            legend.push_str(
                "\nwall map: the wall passed, shaded by the distance to the nearest estimated \
                 contact point (dots)",
            );
        }
        let at = rect.left_top() + Vec2::new(8.0, 6.0);
        let galley = painter.layout_no_wrap(
            legend,
            FontId::proportional(12.0),
            ui.visuals().text_color(),
        );
        if mapped.is_some() {
            // The map's band may run under the legend: keep the legend readable.
            painter.rect_filled(
                Rect::from_min_size(at, galley.size()).expand(2.0),
                3.0,
                ui.visuals().panel_fill.gamma_multiply(0.6),
            );
        }
        painter.galley(at, galley, ui.visuals().text_color());
        if let Some((map, _)) = mapped {
            paint_colour_bar(
                &painter,
                rect,
                map.settings.complete_within_m * 1e3,
                ui.visuals(),
            );
        }
    }
}

/// How far the map's band is drawn from the wall line, points: beside it on the solid side,
/// so that the estimated points on the wall do not hide its colours.
const MAP_OFFSET_PX: f32 = 7.5;

/// The wall samples of `coverage` as a band beside the wall on its solid side (asked of
/// `map.walls`, or away from `base`, which is in free space), shaded by their error (consecutive samples of one wall in
/// one colour band drawn as one line, on a dark underlay), then `map`'s estimated points as
/// dots in `marker` (at most one per 2 x 2 pixels: thousands of points crowd a few).
fn paint_wall_map(
    painter: &egui::Painter,
    to: &ToScreen,
    map: &WallMap<'_>,
    coverage: &Coverage,
    base: Pos2,
    marker: Color32,
) {
    let within_mm = map.settings.complete_within_m * 1e3;
    // Samples farther apart than this are on pieces of the wall not passed in one go.
    let gap_m = 3.0 * map.settings.spacing_m;
    let clip = painter.clip_rect();
    let mut lines: Vec<(Vec<Pos2>, Color32)> = Vec::new();
    let mut lone: Vec<(Pos2, Color32)> = Vec::new();
    let mut current: Option<(usize, Vec<Pos2>, Color32)> = None;
    let samples = &coverage.samples;
    let joined = |a: usize, b: usize| {
        let (a, b) = (&samples[a], &samples[b]);
        a.wall == b.wall && (b.point_m - a.point_m).norm() <= gap_m
    };
    // The neighbours of sample `k` along its run (itself at a run's ends).
    let neighbours = |k: usize| {
        let before = k.checked_sub(1).filter(|&j| joined(j, k)).unwrap_or(k);
        let after = Some(k + 1)
            .filter(|&j| j < samples.len() && joined(k, j))
            .unwrap_or(k);
        (before, after)
    };
    // The unit normal at sample `k`, the tangent turned left, metres.
    let left_normal_m = |k: usize| {
        let (before, after) = neighbours(k);
        let t = samples[after].point_m - samples[before].point_m;
        Vector2::new(-t.y, t.x).try_normalize(0.0)
    };
    // Per run of joined samples, which way the solid side is: +1 on the left of the run's
    // direction, -1 on its right (asked of the wall once, at the run's middle; without the
    // wall, away from the base, which is in free space).
    let mut side = vec![1.0_f32; samples.len()];
    let mut start = 0;
    while start < samples.len() {
        let mut end = start;
        while end + 1 < samples.len() && joined(end, end + 1) {
            end += 1;
        }
        let middle = (start + end) / 2;
        let here_m = samples[middle].point_m;
        let sign = match (left_normal_m(middle), map.walls.get(samples[middle].wall)) {
            (Some(n), Some(wall)) => {
                let probe_m = here_m + n * map.settings.spacing_m;
                if wall.signed_distance(&probe_m).gap_m < 0.0 {
                    1.0
                } else {
                    -1.0
                }
            }
            (Some(n), None) => {
                let to_base = base - to.pos([here_m.x, here_m.y]);
                // Screen y points down: the normal on screen is (n.x, -n.y).
                if f64::from(to_base.x) * n.x - f64::from(to_base.y) * n.y > 0.0 {
                    -1.0
                } else {
                    1.0
                }
            }
            (None, _) => 1.0,
        };
        side[start..=end].fill(sign);
        start = end + 1;
    }
    // Each sample on screen, moved off the wall to its solid side.
    let shifted: Vec<Pos2> = (0..samples.len())
        .map(|k| {
            let at = to.pos([samples[k].point_m.x, samples[k].point_m.y]);
            match left_normal_m(k) {
                Some(n) => {
                    let normal_px = Vec2::new(n.x as f32, -(n.y as f32)) * side[k];
                    at + normal_px * MAP_OFFSET_PX
                }
                None => at,
            }
        })
        .collect();
    for (k, sample) in samples.iter().enumerate() {
        let here = shifted[k];
        let (band, colour) = coverage_band(sample.error_mm, within_mm);
        let next = Some(k + 1).filter(|&j| j < samples.len() && joined(k, j));
        match next {
            Some(next) => {
                let there = shifted[next];
                match &mut current {
                    Some((b, points, _)) if *b == band => points.push(there),
                    _ => {
                        lines.extend(current.take().map(|(_, p, c)| (p, c)));
                        current = Some((band, vec![here, there], colour));
                    }
                }
            }
            None => match current.take() {
                Some((_, p, c)) => lines.push((p, c)),
                None => lone.push((here, colour)),
            },
        }
    }
    lines.extend(current.take().map(|(_, p, c)| (p, c)));
    let near = clip.expand(8.0);
    let visible = |points: &[Pos2]| points.iter().any(|p| near.contains(*p));
    lines.retain(|(points, _)| visible(points));
    for (points, _) in &lines {
        painter.add(Shape::line(
            points.clone(),
            Stroke::new(9.0, MAP_UNDERLAY_COLOUR),
        ));
    }
    for (points, colour) in lines {
        painter.add(Shape::line(points, Stroke::new(6.0, colour)));
    }
    for (at, colour) in lone.into_iter().filter(|(at, _)| near.contains(*at)) {
        painter.circle(at, 2.5, colour, Stroke::new(1.5, MAP_UNDERLAY_COLOUR));
    }
    let mut drawn = HashSet::new();
    for p in map.points_m {
        let at = to.pos([p.x, p.y]);
        if clip.contains(at) && drawn.insert(((at.x / 2.0) as i32, (at.y / 2.0) as i32)) {
            painter.circle_filled(at, 1.6, marker);
        }
    }
}

/// The map's colour bar in the lower right corner of `rect`: the scale from 0 (captured) to
/// `within_mm` and beyond (missed), with the estimated points' dot.
fn paint_colour_bar(painter: &egui::Painter, rect: Rect, within_mm: f64, visuals: &egui::Visuals) {
    let (width, height) = (180.0, 12.0);
    let origin = rect.right_bottom() + Vec2::new(-width - 16.0, -height - 42.0);
    let frame = Rect::from_min_size(
        origin + Vec2::new(-8.0, -22.0),
        Vec2::new(width + 16.0, height + 58.0),
    );
    painter.rect_filled(frame, 4.0, visuals.panel_fill.gamma_multiply(0.9));
    let text = visuals.text_color();
    painter.text(
        origin + Vec2::new(0.0, -4.0),
        Align2::LEFT_BOTTOM,
        "wall map: coverage error, mm",
        FontId::proportional(11.0),
        text,
    );
    let slices = COLOUR_BANDS + 1;
    let slice = width / slices as f32;
    for k in 0..slices {
        let error_mm = within_mm * k as f64 / COLOUR_BANDS as f64;
        let r = Rect::from_min_size(
            origin + Vec2::new(slice * k as f32, 0.0),
            Vec2::new(slice + 0.5, height),
        );
        painter.rect_filled(r, 0.0, coverage_colour(Some(error_mm), within_mm));
    }
    painter.rect_stroke(
        Rect::from_min_size(origin, Vec2::new(width, height)),
        0.0,
        Stroke::new(1.0, MAP_UNDERLAY_COLOUR),
        egui::StrokeKind::Outside,
    );
    let below = origin + Vec2::new(0.0, height + 3.0);
    painter.text(
        below,
        Align2::LEFT_TOP,
        "0 captured",
        FontId::proportional(11.0),
        text,
    );
    painter.text(
        below + Vec2::new(width, 0.0),
        Align2::RIGHT_TOP,
        format!(">= {within_mm} missed"),
        FontId::proportional(11.0),
        text,
    );
    painter.text(
        below + Vec2::new(0.0, 16.0),
        Align2::LEFT_TOP,
        "\u{2022} estimated contact points",
        FontId::proportional(11.0),
        text,
    );
}

/// How [`paint_lit_switches`] marks a switch that fires.
#[derive(Debug, Clone, Copy)]
enum SwitchMark {
    /// A filled dot of this radius, points, in [`TOUCH_COLOUR`] (the measured chain).
    Dot(f32),
    /// A ring in this colour (the prediction).
    Ring(Color32),
}

/// Marks every touch switch of `frame` that fires at its place along its link
/// ([`ChainFrame::lit_switches`]), whatever the frame's source.
fn paint_lit_switches(
    painter: &egui::Painter,
    to: &ToScreen,
    frame: &ChainFrame,
    mark: SwitchMark,
) {
    for lit in frame.lit_switches() {
        let at = to.pos(lit.point_m);
        match mark {
            SwitchMark::Dot(radius) => painter.circle_filled(at, radius, TOUCH_COLOUR),
            SwitchMark::Ring(colour) => painter.circle_stroke(at, 5.0, Stroke::new(2.0, colour)),
        };
    }
}
