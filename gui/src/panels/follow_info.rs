//! A closed-loop run's figures: the robot and controller (from the run's `start` line), the
//! step at the cursor (pose, heading, turning rate, command, error, estimate or why there is
//! none, contacts, collision), and the summary once the run is over.

use egui::{Color32, RichText};

use crate::follow::FollowRunState;

/// The run's figures (see the module documentation).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FollowInfoPanel;

impl FollowInfoPanel {
    /// Draws `run`'s figures at the cursor `cursor_s`.
    pub fn ui(&mut self, ui: &mut egui::Ui, run: &FollowRunState, cursor_s: Option<f64>) {
        let s = &run.start;
        let mm =
            |v: Option<f64>| v.map_or_else(|| "-".to_owned(), |v| format!("{:.1} mm", v * 1e3));
        egui::Grid::new("follow_robot")
            .num_columns(2)
            .show(ui, |ui| {
                let mut row = |k: &str, v: String| {
                    ui.label(k);
                    ui.label(v);
                    ui.end_row();
                };
                row(
                    "robot",
                    format!("{} body, wall on the {}", s.body, s.wall_side),
                );
                row("speed", format!("{:.3} m/s", s.speed_m_per_s));
                row("estimator", s.estimator.clone());
                row("setpoint", format!("{:.1} mm", s.setpoint_m * 1e3));
                row(
                    "step",
                    format!("{:.4} s, delay {} step(s)", s.step_s, s.delay_steps),
                );
            });
        if !s.note.is_empty() {
            ui.label(RichText::new(format!("placement: {}", s.note)).small());
        }
        if let Some(note) = &run.walls_note {
            ui.label(
                RichText::new(format!("no walls drawn: {note}"))
                    .small()
                    .color(Color32::from_rgb(220, 120, 0)),
            );
        }
        if let Some(step) = cursor_s.and_then(|c| run.step_at(c)) {
            ui.separator();
            ui.label(RichText::new(format!("at t = {:.3} s", step.t_s)).strong());
            egui::Grid::new("follow_step")
                .num_columns(2)
                .show(ui, |ui| {
                    let mut row = |k: &str, v: String| {
                        ui.label(k);
                        ui.label(v);
                        ui.end_row();
                    };
                    row(
                        "pose",
                        format!("({:.3}, {:.3}) m", step.pose_m[0], step.pose_m[1]),
                    );
                    row(
                        "heading",
                        format!("{:.2} deg", step.heading_rad.to_degrees()),
                    );
                    row(
                        "turning",
                        format!("{:.2} deg/s", step.omega_rad_per_s.to_degrees()),
                    );
                    match (step.u_n_m, step.turn_command_rad_per_s) {
                        (Some(u), _) => row("moment u", format!("{:.2e} N m", u)),
                        (None, Some(w)) => {
                            row("turn command", format!("{:.2} deg/s", w.to_degrees()))
                        }
                        (None, None) => {}
                    }
                    row("wall distance", mm(step.wall_distance_m));
                    row("error", mm(step.error_m));
                    match (step.estimate_m, &step.no_estimate) {
                        (Some(d), _) => row(
                            "estimate",
                            format!("{} at {} ahead", mm(Some(d)), mm(step.estimate_preview_m)),
                        ),
                        (None, Some(why)) => row("estimate", format!("none: {why}")),
                        (None, None) => row("estimate", "none".to_owned()),
                    }
                    row("contacts", step.contacts.to_string());
                    row(
                        "in a wall",
                        if step.collided { "yes" } else { "no" }.to_owned(),
                    );
                });
        }
        ui.separator();
        match &run.summary {
            Some(summary) => {
                let colour = if summary.status == "ok" {
                    Color32::from_rgb(0, 150, 0)
                } else {
                    Color32::RED
                };
                ui.label(
                    RichText::new(format!("status: {}", summary.status))
                        .color(colour)
                        .strong(),
                );
                if let Some(detail) = &summary.detail {
                    ui.label(RichText::new(detail).small());
                }
                egui::Grid::new("follow_summary")
                    .num_columns(2)
                    .show(ui, |ui| {
                        let mut row = |k: &str, v: String| {
                            ui.label(k);
                            ui.label(v);
                            ui.end_row();
                        };
                        row(
                            "steps",
                            format!(
                                "{} ({:.2} s, {:.3} m)",
                                summary.steps, summary.duration_s, summary.travel_m
                            ),
                        );
                        row("rms error", mm(summary.rms_error_m));
                        row("max error", mm(summary.max_error_m));
                        row(
                            "settling distance",
                            summary
                                .settling_distance_m
                                .map_or_else(|| "-".to_owned(), |v| format!("{v:.3} m")),
                        );
                        row(
                            "collisions",
                            match summary.first_collision_s {
                                Some(t) => format!("{} (first at {t:.3} s)", summary.collisions),
                                None => summary.collisions.to_string(),
                            },
                        );
                        row(
                            "contact share",
                            format!("{:.1} %", 100.0 * summary.contact_share),
                        );
                        row(
                            "estimate share",
                            format!("{:.1} %", 100.0 * summary.estimate_share),
                        );
                        row("estimate rms error", mm(summary.estimate_rms_error_m));
                    });
            }
            None if run.is_finished() => {
                ui.label("no summary (the file ends without one: cut short?)");
            }
            None => {
                ui.label("running...");
            }
        }
    }
}
