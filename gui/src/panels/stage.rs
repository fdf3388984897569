//! Stage and servo state: the stage's position within its soft limits, the servo angle, the
//! trial being recorded and the daemon's latest note (a device unavailable, a move refused).

use egui::{Color32, RichText};

/// What the stage panel shows.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StageInfo {
    /// Stage position, metres (`None`: unavailable).
    pub stage_position_m: Option<f64>,
    /// The stage's soft limits, metres.
    pub stage_range_m: Option<(f64, f64)>,
    /// Servo angle, degrees (`None`: unavailable).
    pub servo_angle_deg: Option<f64>,
    /// The base link's mounting angle, degrees.
    pub mount_angle_deg: f64,
    /// The trial being recorded (live), or the recording's name.
    pub trial: Option<String>,
    /// The daemon's note.
    pub note: Option<String>,
}

/// The stage and servo panel (see the module documentation).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StagePanel;

impl StagePanel {
    /// Draws `info`.
    pub fn ui(&mut self, ui: &mut egui::Ui, info: &StageInfo) {
        egui::Grid::new("stage_grid").num_columns(2).show(ui, |ui| {
            ui.label("stage");
            match info.stage_position_m {
                Some(x) => {
                    ui.label(format!("{:.1} mm", x * 1e3));
                }
                None => {
                    ui.label(RichText::new("unavailable").color(Color32::RED));
                }
            }
            ui.end_row();
            if let (Some(x), Some((lo, hi))) = (info.stage_position_m, info.stage_range_m)
                && hi > lo
            {
                ui.label("travel");
                ui.add(
                    egui::ProgressBar::new(((x - lo) / (hi - lo)).clamp(0.0, 1.0) as f32)
                        .text(format!("{:.0}..{:.0} mm", lo * 1e3, hi * 1e3)),
                );
                ui.end_row();
            }
            ui.label("servo");
            match info.servo_angle_deg {
                Some(a) => {
                    ui.label(format!(
                        "{a:.1} deg (base link at {:.1} deg)",
                        info.mount_angle_deg + a
                    ));
                }
                None => {
                    ui.label(RichText::new("unavailable").color(Color32::RED));
                }
            }
            ui.end_row();
            ui.label("trial");
            ui.label(info.trial.as_deref().unwrap_or("none"));
            ui.end_row();
        });
        if let Some(note) = &info.note {
            ui.label(RichText::new(note).small());
        }
    }
}
