//! The chain: segments, joints, touch switches lit where they fire, contact points (a
//! simulated sweep's), hairs, walls, the base and the stage, the measured chain overlaid
//! with sim-core's prediction for the same base pose and wall, and the difference between
//! them.
//!
//! Touches are drawn from the frame alone, so live, recorded and simulated chains show them
//! the same way: a link whose segment has any touch bit set is drawn red, and each switch
//! that fires is a dot at its place along the link ([`ChainFrame::lit_switches`]); the
//! prediction's switches are rings.

use egui::{Align2, Color32, FontId, Pos2, Rect, Sense, Shape, Stroke, Vec2};

use crate::frame::{ChainFrame, PointM};

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

/// The chain panel (see the module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct ChainPanel {
    /// Draw the prediction.
    pub show_prediction: bool,
    /// Draw the measured-to-predicted difference.
    pub show_difference: bool,
}

impl Default for ChainPanel {
    fn default() -> Self {
        Self {
            show_prediction: true,
            show_difference: true,
        }
    }
}

/// Maps track-frame metres to screen points, y up, equal scales.
struct ToScreen {
    centre_m: PointM,
    centre_px: Pos2,
    px_per_m: f32,
}

impl ToScreen {
    fn fit(rect: Rect, frames: &[&ChainFrame]) -> Self {
        let (mut min, mut max) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for f in frames {
            let (a, b) = f.bounds_m();
            min = [min[0].min(a[0]), min[1].min(a[1])];
            max = [max[0].max(b[0]), max[1].max(b[1])];
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
    ) {
        ui.horizontal(|ui| {
            ui.checkbox(&mut self.show_prediction, "prediction");
            ui.checkbox(&mut self.show_difference, "difference");
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
        let to = ToScreen::fit(rect.shrink(8.0), &frames);
        let painter = painter.with_clip_rect(rect);

        // The track (the stage's soft limits), the wall, the base and the stage carriage.
        if let Some((lo, hi)) = measured.stage_range_m {
            painter.line_segment(
                [to.pos([lo, 0.0]), to.pos([hi, 0.0])],
                Stroke::new(2.0, TRACK_COLOUR),
            );
        }
        for wall in &measured.walls_m {
            let points: Vec<Pos2> = wall.iter().map(|p| to.pos(*p)).collect();
            painter.add(Shape::line(points, Stroke::new(5.0, WALL_COLOUR)));
        }
        let base = to.pos(measured.base_m);
        painter.rect_filled(
            Rect::from_center_size(base, Vec2::new(22.0, 10.0)),
            2.0,
            TRACK_COLOUR,
        );

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
        for p in measured.joints_m[1..].iter().filter(|_| spacing_px >= 8.0) {
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
        legend.push_str(
            "\nblue: measured   red: touched, dots: the switches that fire   grey dashed: unhealthy",
        );
        if !measured.contacts_m.is_empty() {
            legend.push_str("   red rings: contact points");
        }
        if predicted.is_some() {
            legend.push_str(&format!("\norange dashed: predicted ({model})"));
        }
        painter.text(
            rect.left_top() + Vec2::new(8.0, 6.0),
            Align2::LEFT_TOP,
            legend,
            FontId::proportional(12.0),
            ui.visuals().text_color(),
        );
    }
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
