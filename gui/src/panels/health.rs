//! Segment health: per segment its address, the latest reading's state and, live, the
//! daemon's counters since it started (good reads, no acknowledge, PEC errors, stale polls).

use antenna_data::stream::SegmentStatus;
use egui::{Color32, RichText};

use crate::history::Health;

/// The segment health panel (see the module documentation).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct HealthPanel;

impl HealthPanel {
    /// Draws one row per segment: `addresses` and `now` (the latest reading's health) base
    /// to tip, with the daemon's `counters` if it sent them.
    pub fn ui(
        &mut self,
        ui: &mut egui::Ui,
        addresses: &[u8],
        now: &[Health],
        counters: Option<&[SegmentStatus]>,
    ) {
        let unhealthy = now.iter().filter(|h| h.is_unhealthy()).count();
        ui.label(if unhealthy == 0 {
            RichText::new(format!("all {} segments healthy", now.len()))
        } else {
            RichText::new(format!("{unhealthy} of {} segments unhealthy", now.len()))
                .color(Color32::RED)
        });
        // Only the rows in view are laid out: a 150-segment chain costs no more than a short one.
        let row_height = ui.text_style_height(&egui::TextStyle::Body) + ui.spacing().item_spacing.y;
        let widths = [28.0, 40.0, 40.0, 56.0, 64.0, 40.0];
        let row = |ui: &mut egui::Ui, cells: [RichText; 6]| {
            ui.horizontal(|ui| {
                for (cell, width) in cells.into_iter().zip(widths) {
                    ui.add_sized([width, row_height], egui::Label::new(cell));
                }
            });
        };
        row(
            ui,
            ["seg", "addr", "now", "ok", "nack/pec", "stale"].map(|t| RichText::new(t).strong()),
        );
        egui::ScrollArea::vertical()
            .id_salt("health_scroll")
            .max_height(220.0)
            .show_rows(ui, row_height, now.len(), |ui, rows| {
                for k in rows {
                    let health = now[k];
                    let colour = if health.is_unhealthy() {
                        Color32::RED
                    } else {
                        ui.visuals().text_color()
                    };
                    let counters = counters.and_then(|c| c.get(k));
                    row(
                        ui,
                        [
                            RichText::new(format!("{}", k + 1)),
                            RichText::new(
                                addresses
                                    .get(k)
                                    .map_or_else(|| "-".to_owned(), |a| format!("{a:#04x}")),
                            ),
                            RichText::new(health.as_str()).color(colour),
                            RichText::new(counters.map_or("-".to_owned(), |c| c.ok.to_string())),
                            RichText::new(
                                counters.map_or("-".to_owned(), |c| {
                                    format!("{}/{}", c.nack, c.pec_error)
                                }),
                            ),
                            RichText::new(counters.map_or("-".to_owned(), |c| c.stale.to_string())),
                        ],
                    );
                }
            });
    }
}
