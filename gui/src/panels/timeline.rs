//! The view bar: pause and follow-latest, zoom, the history window the user sets, the scrub
//! slider over the whole history, and the exports of the visible range.

use crate::view::ViewState;

/// What the user asked for in the view bar this frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TimelineAction {
    /// Freeze the view (acquisition goes on).
    Pause,
    /// Follow the newest sample.
    Follow,
    /// Multiply the window's width by this.
    Zoom(f64),
    /// Keep this many seconds of history.
    SetHistory(f64),
    /// Show the chain at this instant.
    Scrub(f64),
    /// Export the visible range as CSV.
    ExportCsv,
    /// Export the view as PNG.
    ExportPng,
    /// Export the view as SVG.
    ExportSvg,
    /// Play a recording from the cursor at the set speed.
    Play,
    /// Stop playing.
    StopPlaying,
}

/// The view bar (see the module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct TimelinePanel {
    history_s: f64,
    /// Playback speed of a recording (1: real time).
    pub speed: f64,
}

impl TimelinePanel {
    /// A bar showing a history window of `history_s` seconds.
    pub fn new(history_s: f64) -> Self {
        Self {
            history_s,
            speed: 1.0,
        }
    }

    /// Draws the bar for `view` over a history spanning `first_s..=latest_s`; `live` shows
    /// the history setting (a recording keeps all of itself, and plays instead: `playing`
    /// says whether it is). Returns the user's actions.
    pub fn ui(
        &mut self,
        ui: &mut egui::Ui,
        view: &ViewState,
        span: Option<(f64, f64)>,
        live: bool,
        playing: bool,
    ) -> Vec<TimelineAction> {
        let mut actions = Vec::new();
        ui.horizontal(|ui| {
            if !live {
                if playing {
                    if ui.button("Stop playing").clicked() {
                        actions.push(TimelineAction::StopPlaying);
                    }
                } else if ui.button("Play").clicked() {
                    actions.push(TimelineAction::Play);
                }
                let label = ui.label("speed, x");
                ui.add(
                    egui::DragValue::new(&mut self.speed)
                        .range(0.05..=20.0)
                        .speed(0.05),
                )
                .labelled_by(label.id);
                ui.separator();
            }
            if view.is_following() {
                if ui.button("Pause").clicked() {
                    actions.push(TimelineAction::Pause);
                }
            } else if ui.button("Follow latest").clicked() {
                actions.push(TimelineAction::Follow);
            }
            if ui.button("Zoom in").clicked() {
                actions.push(TimelineAction::Zoom(0.5));
            }
            if ui.button("Zoom out").clicked() {
                actions.push(TimelineAction::Zoom(2.0));
            }
            ui.label(format!("window {:.3} s", view.window_s()));
            if live {
                let label = ui.label("history, s");
                let response = ui
                    .add(
                        egui::DragValue::new(&mut self.history_s)
                            .range(1.0..=600.0)
                            .speed(1.0),
                    )
                    .labelled_by(label.id);
                if response.changed() {
                    actions.push(TimelineAction::SetHistory(self.history_s));
                }
            }
            ui.separator();
            if ui.button("Export CSV").clicked() {
                actions.push(TimelineAction::ExportCsv);
            }
            if ui.button("Export PNG").clicked() {
                actions.push(TimelineAction::ExportPng);
            }
            if ui.button("Export SVG").clicked() {
                actions.push(TimelineAction::ExportSvg);
            }
        });
        if let Some((first, latest)) = span.filter(|(a, b)| b > a) {
            // Never clamped: clamping rounds the value and would count as a scrub.
            let mut t = view.cursor_s(Some(latest)).unwrap_or(latest);
            let label = ui.label("scrub, s");
            let slider = egui::Slider::new(&mut t, first..=latest)
                .fixed_decimals(3)
                .clamping(egui::SliderClamping::Never);
            let response = ui
                .add_sized([ui.available_width(), 18.0], slider)
                .labelled_by(label.id);
            if response.changed() {
                actions.push(TimelineAction::Scrub(t));
            }
        }
        actions
    }
}
