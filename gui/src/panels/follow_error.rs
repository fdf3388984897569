//! A closed-loop run's distance error against time: the true distance from the point of
//! rotation to the wall minus the setpoint, and the estimate's error (the estimate minus the
//! true `d` at its preview, where there is an estimate), in mm, over the view's window, with
//! the cursor; a click scrubs (the top view follows).

use egui::Color32;
use egui_plot::{HLine, Legend, Line, Plot, PlotPoints, VLine};

use crate::follow::FollowRunState;
use crate::view::ViewState;

/// The true distance's error.
const TRUE_COLOUR: Color32 = Color32::from_rgb(0, 114, 178);
/// The estimate's error.
const ESTIMATE_COLOUR: Color32 = Color32::from_rgb(0, 158, 115);

/// A plotted series: runs of `[t_s, value]` points, one line each.
pub type Lines = Vec<Vec<[f64; 2]>>;

/// The error panel (see the module documentation).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FollowErrorPanel;

/// The two error series of `run` between `t0_s` and `t1_s` in mm, each as runs of
/// consecutive steps that have a value (a step without one breaks its line), at most about
/// `columns` points each (every `k`th step).
pub fn error_series_mm(
    run: &FollowRunState,
    t0_s: f64,
    t1_s: f64,
    columns: usize,
) -> (Lines, Lines) {
    let first = run
        .steps
        .partition_point(|s| s.t_s < t0_s)
        .saturating_sub(1);
    let last = run
        .steps
        .partition_point(|s| s.t_s <= t1_s)
        .min(run.steps.len());
    let stride = (last.saturating_sub(first) / columns.max(1)).max(1);
    let (mut truth, mut estimate): (Lines, Lines) = Default::default();
    let push =
        |lines: &mut Vec<Vec<[f64; 2]>>, point: Option<[f64; 2]>, broke: &mut bool| match point {
            Some(p) if p[1].is_finite() => {
                if *broke || lines.is_empty() {
                    lines.push(Vec::new());
                }
                *broke = false;
                if let Some(line) = lines.last_mut() {
                    line.push(p);
                }
            }
            _ => *broke = true,
        };
    let (mut truth_broke, mut estimate_broke) = (true, true);
    for s in run.steps[first.min(last)..last].iter().step_by(stride) {
        push(
            &mut truth,
            s.error_m.map(|e| [s.t_s, e * 1e3]),
            &mut truth_broke,
        );
        push(
            &mut estimate,
            s.estimate_m
                .zip(s.true_distance_at_preview_m)
                .map(|(e, d)| [s.t_s, (e - d) * 1e3]),
            &mut estimate_broke,
        );
    }
    (truth, estimate)
}

impl FollowErrorPanel {
    /// Draws `run`'s errors over the view's window; a click scrubs `view`.
    pub fn ui(&mut self, ui: &mut egui::Ui, run: &FollowRunState, view: &mut ViewState) {
        let latest = run.history.latest_t_s();
        let cursor = view.cursor_s(latest);
        let here = cursor.and_then(|c| run.step_at(c));
        ui.horizontal(|ui| {
            ui.label(format!(
                "distance error, mm (setpoint {:.0} mm)",
                run.start.setpoint_m * 1e3
            ));
            if let Some(s) = here {
                let mm = |v: Option<f64>| {
                    v.map_or_else(|| "-".to_owned(), |v| format!("{:.1}", v * 1e3))
                };
                ui.label(format!(
                    "at {:.3} s: true {} mm, estimate {} mm",
                    s.t_s,
                    mm(s.error_m),
                    mm(s.estimate_m
                        .zip(s.true_distance_at_preview_m)
                        .map(|(e, d)| e - d))
                ));
            }
        });
        let Some((t0, t1)) = view.window(latest) else {
            ui.label("no steps yet");
            return;
        };
        let columns = (ui.available_width() as usize).clamp(16, 4096);
        let (truth, estimate) = error_series_mm(run, t0, t1, columns);
        let response = Plot::new("follow_error")
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
                plot_ui.hline(HLine::new("setpoint", 0.0).color(Color32::GRAY));
                for points in truth {
                    plot_ui.line(
                        Line::new("true distance - setpoint", PlotPoints::from(points))
                            .color(TRUE_COLOUR)
                            .width(1.5),
                    );
                }
                for points in estimate {
                    plot_ui.line(
                        Line::new("estimate - true d at its preview", PlotPoints::from(points))
                            .color(ESTIMATE_COLOUR)
                            .width(1.2),
                    );
                }
                if let Some(c) = cursor {
                    plot_ui.vline(VLine::new("cursor", c).color(Color32::GRAY));
                }
                let clicked = plot_ui.response().clicked();
                clicked.then(|| plot_ui.pointer_coordinate()).flatten()
            });
        if let Some(point) = response.inner {
            view.scrub(point.x, latest);
        }
    }
}
