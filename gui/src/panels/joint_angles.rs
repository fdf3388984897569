//! Joint-angle time series of the visible window, reduced to one min/max pair per screen
//! column ([`crate::history::History::envelope`]) so that a minute at 1 kHz costs no more to
//! draw than a second. Wheel-zoom and drag act on the time axis; a click scrubs.

use egui_plot::{Legend, Line, Plot, PlotPoints, VLine};

use crate::history::History;
use crate::view::ViewState;

/// Joints shown by default at most (evenly spread, the tip always among them).
const DEFAULT_JOINTS: usize = 8;

/// The joint-angle panel (see the module documentation).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct JointAnglesPanel {
    /// Which joints are plotted (0-based); empty until the segment count is known.
    selected: Vec<bool>,
}

impl JointAnglesPanel {
    /// The joints plotted (0-based), for `segments` segments.
    pub fn joints(&mut self, segments: usize) -> Vec<usize> {
        if self.selected.len() != segments {
            self.selected = vec![false; segments];
            let shown = segments.min(DEFAULT_JOINTS);
            for j in 0..shown {
                // 0, ..., segments - 1 spread evenly.
                let k = if shown == 1 {
                    segments - 1
                } else {
                    j * (segments - 1) / (shown - 1)
                };
                self.selected[k] = true;
            }
        }
        (0..segments).filter(|&k| self.selected[k]).collect()
    }

    /// Draws the plot of `history` over the view's window; applies the user's zoom, pan and
    /// clicks to `view`.
    pub fn ui(
        &mut self,
        ui: &mut egui::Ui,
        history: &History,
        view: &mut ViewState,
        max_window_s: f64,
    ) {
        let segments = history.segment_count();
        let joints = self.joints(segments);
        let latest = history.latest_t_s();
        ui.horizontal(|ui| {
            ui.label("joint angles, deg");
            ui.menu_button(format!("joints ({} of {segments})", joints.len()), |ui| {
                egui::ScrollArea::vertical()
                    .max_height(300.0)
                    .show(ui, |ui| {
                        for (k, on) in self.selected.iter_mut().enumerate() {
                            ui.checkbox(on, format!("joint {}", k + 1));
                        }
                    });
            });
        });
        let Some((t0, t1)) = view.window(latest) else {
            ui.label("no samples yet");
            return;
        };
        // One column per two points of width: a min/max pair each.
        let columns = (ui.available_width() as usize / 2).clamp(16, 4096);
        let cursor = view.cursor_s(latest);
        let response = Plot::new("joint_angles")
            .legend(Legend::default())
            .show_background(false)
            .allow_zoom([true, false])
            .allow_drag([true, false])
            .allow_scroll([true, false])
            .allow_double_click_reset(false)
            .auto_bounds([false, true])
            .x_axis_label("t, s")
            .show(ui, |plot_ui| {
                plot_ui.set_plot_bounds_x(t0..=t1);
                for &k in &joints {
                    let points: Vec<[f64; 2]> = history
                        .envelope(k, t0, t1, columns)
                        .iter()
                        .flat_map(|c| {
                            [
                                [c.t_s, c.min_rad.to_degrees()],
                                [c.t_s, c.max_rad.to_degrees()],
                            ]
                        })
                        .collect();
                    plot_ui.line(
                        Line::new(format!("joint {}", k + 1), PlotPoints::from(points)).width(1.5),
                    );
                }
                if let Some(c) = cursor {
                    plot_ui.vline(VLine::new("cursor", c).color(egui::Color32::GRAY));
                }
                let clicked = plot_ui.response().clicked();
                clicked.then(|| plot_ui.pointer_coordinate()).flatten()
            });
        if let Some(point) = response.inner {
            view.scrub(point.x, latest);
            return;
        }
        // Adopt the plot's window only when the user moved it (a drag or a wheel zoom over
        // the plot); otherwise the view decides.
        let plot = &response.response;
        let wheeled = plot.hovered()
            && ui.input(|i| i.smooth_scroll_delta != egui::Vec2::ZERO || i.zoom_delta() != 1.0);
        if plot.dragged() || wheeled {
            let bounds = response.transform.bounds();
            let (b0, b1) = (bounds.min()[0], bounds.max()[0]);
            let tolerance = 1e-6 * (t1 - t0).max(1e-9);
            if (b0 - t0).abs() > tolerance || (b1 - t1).abs() > tolerance {
                view.set_window(b0, b1, latest, max_window_s);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_joints_are_spread_to_the_tip() {
        let mut p = JointAnglesPanel::default();
        assert_eq!(p.joints(3), vec![0, 1, 2]);
        assert_eq!(p.joints(150), vec![0, 21, 42, 63, 85, 106, 127, 149]);
        assert_eq!(p.joints(1), vec![0]);
    }
}
