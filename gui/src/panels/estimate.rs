//! antennad's live wall estimate against time: the estimated distance to the wall (along y,
//! toward the wall, at the estimate's preview ahead of the base pivot) and, from the
//! simulated rig, the true distance there, in mm, over the view's window, with the cursor; a
//! click scrubs. Above the plot, the estimate at the cursor (its estimator, distance, angle,
//! preview and error against the truth), or why there is none.

use egui::{Color32, RichText};
use egui_plot::{Legend, Line, Plot, PlotPoints, VLine};

use crate::estimate::{Estimate, EstimateHistory};
use crate::view::ViewState;

/// The estimated distance (the chain panel's estimate colour, bluish green).
pub const ESTIMATE_COLOUR: Color32 = Color32::from_rgb(0, 158, 115);
/// The true distance (simulated rig).
const TRUE_COLOUR: Color32 = Color32::from_rgb(0, 114, 178);
/// The line above the plot when there is no current estimate.
const WARNING_COLOUR: Color32 = Color32::from_rgb(220, 120, 0);

/// The estimate panel (see the module documentation).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct EstimatePanel;

/// One line about `estimate`: its estimator, distance, angle, preview and error, or why
/// there is none.
pub fn describe(estimate: &Estimate) -> String {
    let Some(distance_m) = estimate.distance_m else {
        return format!(
            "no wall estimate ({}): {}",
            estimate.estimator,
            estimate.reason.as_deref().unwrap_or("no reason given")
        );
    };
    let mut text = format!(
        "wall estimate ({}): {:.1} mm",
        estimate.estimator,
        distance_m * 1e3
    );
    match estimate.angle_rad {
        Some(a) => text.push_str(&format!(", {:.1} deg", a.to_degrees())),
        None => text.push_str(", no angle"),
    }
    if let Some(p) = estimate.preview_m {
        text.push_str(&format!(" at {:.0} mm ahead", p * 1e3));
    }
    if let (Some(truth), Some(error)) = (estimate.true_distance_m, estimate.error_m()) {
        text.push_str(&format!(
            "; true {:.1} mm, error {:+.1} mm",
            truth * 1e3,
            error * 1e3
        ));
    }
    text
}

impl EstimatePanel {
    /// Draws `estimates` over the view's window (`latest_s`: the newest sample's time, which
    /// the view's window follows); a click scrubs `view`.
    pub fn ui(
        &mut self,
        ui: &mut egui::Ui,
        estimates: &EstimateHistory,
        view: &mut ViewState,
        latest_s: Option<f64>,
    ) {
        let cursor = view.cursor_s(latest_s);
        ui.horizontal(|ui| {
            ui.label("wall distance, mm");
            let here = cursor.map_or(Ok(None), |c| estimates.current_at(c));
            match here {
                Ok(Some(e)) if e.has_estimate() => {
                    ui.label(describe(e));
                }
                Ok(Some(e)) => {
                    ui.label(RichText::new(describe(e)).color(WARNING_COLOUR));
                }
                Err(age_s) => {
                    ui.label(
                        RichText::new(format!(
                            "no current wall estimate: the newest was made {age_s:.1} s \
                             before the cursor"
                        ))
                        .color(WARNING_COLOUR),
                    );
                }
                Ok(None) if estimates.received() == 0 => {
                    ui.label(
                        RichText::new(
                            "no wall estimate: the daemon sends none ([estimate] estimator = \
                             \"none\", or a daemon from before the estimate)",
                        )
                        .weak(),
                    );
                }
                Ok(None) => {
                    ui.label(RichText::new("no wall estimate at the cursor yet").weak());
                }
            }
        });
        let Some((t0, t1)) = view.window(latest_s) else {
            return;
        };
        let columns = (ui.available_width() as usize).clamp(16, 4096);
        let (estimated, truth) = estimates.distance_series_mm(t0, t1, columns);
        let response = Plot::new("wall_estimate")
            .legend(Legend::default())
            .show_background(false)
            .allow_zoom(false)
            .allow_drag(false)
            .allow_scroll(false)
            .allow_double_click_reset(false)
            .auto_bounds([false, true])
            .x_axis_label("t, s")
            .show(ui, |plot_ui| {
                plot_ui.set_plot_bounds_x(t0..=t1);
                for points in truth {
                    plot_ui.line(
                        Line::new("true distance", PlotPoints::from(points))
                            .color(TRUE_COLOUR)
                            .width(1.5),
                    );
                }
                for points in estimated {
                    plot_ui.line(
                        Line::new("estimated distance", PlotPoints::from(points))
                            .color(ESTIMATE_COLOUR)
                            .width(1.5),
                    );
                }
                if let Some(c) = cursor {
                    plot_ui.vline(VLine::new("cursor", c).color(Color32::GRAY));
                }
                let clicked = plot_ui.response().clicked();
                clicked.then(|| plot_ui.pointer_coordinate()).flatten()
            });
        if let Some(point) = response.inner {
            view.scrub(point.x, latest_s);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_line_says_the_estimate_or_why_there_is_none() {
        let mut e = Estimate {
            seq: 1,
            t_s: 0.001,
            estimated_s: Some(0.001),
            estimator: "contact-line".to_owned(),
            distance_m: Some(0.3),
            angle_rad: Some(0.1),
            preview_m: Some(0.05),
            reason: None,
            true_distance_m: Some(0.298),
            true_angle_rad: Some(0.1),
        };
        assert_eq!(
            describe(&e),
            "wall estimate (contact-line): 300.0 mm, 5.7 deg at 50 mm ahead; true 298.0 mm, \
             error +2.0 mm"
        );
        e.angle_rad = None;
        e.true_distance_m = None;
        e.estimator = "bend".to_owned();
        assert_eq!(
            describe(&e),
            "wall estimate (bend): 300.0 mm, no angle at 50 mm ahead"
        );
        e.distance_m = None;
        e.reason = Some("no contact in the window".to_owned());
        assert_eq!(
            describe(&e),
            "no wall estimate (bend): no contact in the window"
        );
    }
}
