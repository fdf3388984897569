//! A [`ControlHandler`] that records what it was told, for tests and dry runs.

use std::sync::Mutex;

use antenna_data::stream::ControlCommand;

use super::control::ControlHandler;

/// Records every command; refuses those for which `refuse` returns a reason.
#[derive(Debug, Default)]
pub struct RecordingHandler {
    calls: Mutex<Vec<ControlCommand>>,
    refuse_all: Option<String>,
}

impl RecordingHandler {
    /// Accepts every command.
    pub fn new() -> Self {
        Self::default()
    }

    /// Records but refuses every command with `reason`.
    pub fn refusing(reason: impl Into<String>) -> Self {
        Self {
            calls: Mutex::new(Vec::new()),
            refuse_all: Some(reason.into()),
        }
    }

    /// The commands received so far, in order.
    pub fn calls(&self) -> Vec<ControlCommand> {
        self.calls.lock().map(|c| c.clone()).unwrap_or_default()
    }
}

impl ControlHandler for RecordingHandler {
    fn handle(&self, command: ControlCommand) -> Result<String, String> {
        let text = format!("{command:?}");
        if let Ok(mut calls) = self.calls.lock() {
            calls.push(command);
        }
        match &self.refuse_all {
            Some(reason) => Err(reason.clone()),
            None => Ok(format!("done: {text}")),
        }
    }
}
