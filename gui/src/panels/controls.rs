//! Controls: start and stop a trial, move the stage, set the base angle, stop everything.
//! **Stop everything** is always enabled (the daemon takes `stop_all` from anyone, without a
//! token); the other buttons are disabled until a token is entered and the daemon is
//! connected: control needs the daemon's token, watching does not. The daemon's replies are
//! listed below.

use egui::{Color32, RichText};

use crate::client::{Command, ReplyRecord};

/// The controls panel (see the module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct ControlsPanel {
    /// The control token (empty: no control).
    pub token: String,
    /// The trial `start_trial` asks for.
    pub trial_name: String,
    /// Where `move_stage` sends the stage, mm.
    pub stage_target_mm: f64,
    /// The servo angle `set_base_angle` asks for, degrees.
    pub servo_angle_deg: f64,
}

impl ControlsPanel {
    /// A panel with `token` (maybe empty) and the simulated rig's trial name.
    pub fn new(token: impl Into<String>) -> Self {
        Self {
            token: token.into(),
            trial_name: "wall-sweep".to_owned(),
            stage_target_mm: 100.0,
            servo_angle_deg: 0.0,
        }
    }

    /// Draws the controls; returns the commands clicked this frame. `connected` enables them
    /// (with a token); `replies` are the daemon's answers, newest last; `refusal` is the last
    /// command refused before it was sent.
    pub fn ui(
        &mut self,
        ui: &mut egui::Ui,
        connected: bool,
        replies: &[ReplyRecord],
        refusal: Option<&str>,
    ) -> Vec<Command> {
        let mut commands = Vec::new();
        ui.horizontal(|ui| {
            let label = ui.label("token");
            ui.add(
                egui::TextEdit::singleline(&mut self.token)
                    .password(true)
                    .desired_width(150.0),
            )
            .labelled_by(label.id);
        });
        let enabled = connected && !self.token.is_empty();
        if !connected {
            ui.label(RichText::new("not connected: controls disabled").weak());
        } else if self.token.is_empty() {
            ui.label(
                RichText::new(
                    "enter the daemon's token to enable control (Stop everything needs none)",
                )
                .weak(),
            );
        }
        ui.add_enabled_ui(enabled, |ui| {
            ui.horizontal(|ui| {
                let label = ui.label("trial");
                ui.add(egui::TextEdit::singleline(&mut self.trial_name).desired_width(110.0))
                    .labelled_by(label.id);
            });
            ui.horizontal(|ui| {
                if ui.button("Start trial").clicked() {
                    commands.push(Command::StartTrial {
                        name: self.trial_name.clone(),
                    });
                }
                if ui.button("Stop trial").clicked() {
                    commands.push(Command::StopTrial);
                }
            });
            ui.horizontal(|ui| {
                if ui.button("Move stage").clicked() {
                    commands.push(Command::MoveStage {
                        position_m: self.stage_target_mm * 1e-3,
                    });
                }
                let label = ui.label("to, mm");
                ui.add(egui::DragValue::new(&mut self.stage_target_mm).speed(1.0))
                    .labelled_by(label.id);
            });
            ui.horizontal(|ui| {
                if ui.button("Set base angle").clicked() {
                    commands.push(Command::SetBaseAngle {
                        angle_deg: self.servo_angle_deg,
                    });
                }
                let label = ui.label("servo, deg");
                ui.add(
                    egui::DragValue::new(&mut self.servo_angle_deg)
                        .speed(0.5)
                        .range(-45.0..=45.0),
                )
                .labelled_by(label.id);
            });
        });
        // Stopping is always allowed: enabled whatever the token and the connection (a click
        // without a connection says so below).
        let stop = egui::Button::new(RichText::new("Stop everything").color(Color32::WHITE))
            .fill(Color32::from_rgb(180, 30, 30));
        if ui.add(stop).clicked() {
            commands.push(Command::StopAll);
        }
        if let Some(refusal) = refusal {
            ui.label(RichText::new(refusal).color(Color32::RED));
        }
        for reply in replies.iter().rev().take(4) {
            let text = format!(
                "{} {}: {}{}",
                if reply.ok { "ok" } else { "refused" },
                reply.command.as_deref().unwrap_or("?"),
                reply
                    .error
                    .as_deref()
                    .map_or_else(String::new, |e| format!("[{e}] ")),
                reply.message
            );
            let colour = if reply.ok {
                Color32::from_rgb(0, 150, 0)
            } else {
                Color32::RED
            };
            ui.label(RichText::new(text).color(colour).small());
        }
        commands
    }
}
