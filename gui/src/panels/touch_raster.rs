//! The touch raster: one row per segment (the base at the bottom), time across the same
//! window as the joint angles, a bar where any touch switch of that segment fired. Built from
//! [`crate::history::History::touch_spans_all`] at one column per screen point and drawn as one
//! mesh, so 150 segments over a minute stay cheap.

use egui::{Align2, Color32, FontId, Mesh, Rect, Sense, Stroke, Vec2};

use crate::history::History;
use crate::panels::chain::TOUCH_COLOUR;

/// The touch raster panel (see the module documentation).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TouchRasterPanel;

impl TouchRasterPanel {
    /// Draws the raster of `history` over `t0_s..=t1_s` with the cursor at `cursor_s`.
    pub fn ui(
        &mut self,
        ui: &mut egui::Ui,
        history: &History,
        window: Option<(f64, f64)>,
        cursor_s: Option<f64>,
    ) {
        ui.label("touch raster (rows: segments, base at the bottom)");
        let (response, painter) = ui.allocate_painter(ui.available_size(), Sense::hover());
        let rect = response.rect;
        painter.rect_stroke(
            rect,
            2.0,
            ui.visuals().widgets.noninteractive.bg_stroke,
            egui::StrokeKind::Inside,
        );
        let Some((t0, t1)) = window.filter(|(a, b)| b > a) else {
            return;
        };
        let n = history.segment_count();
        if n == 0 {
            return;
        }
        let label_width = 28.0;
        let plot = Rect::from_min_max(rect.min + Vec2::new(label_width, 0.0), rect.max);
        let row_height = plot.height() / n as f32;
        let x = |t: f64| plot.left() + ((t - t0) / (t1 - t0)) as f32 * plot.width();
        let columns = (plot.width() as usize).max(1);
        let mut mesh = Mesh::default();
        for (k, spans) in history.touch_spans_all(t0, t1, columns).iter().enumerate() {
            let top = plot.bottom() - (k + 1) as f32 * row_height;
            let bottom = top + row_height.max(1.0) * 0.85;
            for &(a, b) in spans {
                let r = Rect::from_min_max(
                    egui::pos2(x(a).max(plot.left()), top),
                    egui::pos2(
                        x(b).min(plot.right()).max(x(a) + 1.0),
                        bottom.max(top + 1.0),
                    ),
                );
                mesh.add_colored_rect(r, TOUCH_COLOUR);
            }
        }
        painter.add(mesh);
        let step = (n / 8).max(1);
        for k in (0..n).step_by(step) {
            let y = plot.bottom() - (k as f32 + 0.5) * row_height;
            painter.text(
                egui::pos2(rect.left() + 2.0, y),
                Align2::LEFT_CENTER,
                format!("{}", k + 1),
                FontId::monospace(10.0),
                ui.visuals().weak_text_color(),
            );
        }
        if let Some(c) = cursor_s
            && (t0..=t1).contains(&c)
        {
            painter.line_segment(
                [
                    egui::pos2(x(c), plot.top()),
                    egui::pos2(x(c), plot.bottom()),
                ],
                Stroke::new(1.0, Color32::GRAY),
            );
        }
    }
}
