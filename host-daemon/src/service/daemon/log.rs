//! The daemon's log: lines for humans through `tracing`, kept for
//! [`super::DaemonHandle::log_lines`]; sample lines to stdout when asked.

use super::LOG_LINES_KEPT;
use std::collections::VecDeque;
use std::sync::{Arc, Mutex};

/// Lines for humans: logged through `tracing` (target `antennad`, at the level given) and
/// kept; sample lines go to stdout instead, if asked (`echo`), and are kept too.
#[derive(Debug, Clone)]
pub(super) struct Log {
    pub(super) echo: bool,
    pub(super) lines: Arc<Mutex<VecDeque<String>>>,
}

impl Log {
    /// An informational line.
    pub(super) fn line(&self, text: String) {
        tracing::info!(target: "antennad", "{}", Self::message(&text));
        self.keep(text);
    }

    /// Something is wrong, and the daemon goes on (a segment gone stale, a disk filling up).
    pub(super) fn warn(&self, text: String) {
        tracing::warn!(target: "antennad", "{}", Self::message(&text));
        self.keep(text);
    }

    /// Something failed (a recording).
    pub(super) fn error(&self, text: String) {
        tracing::error!(target: "antennad", "{}", Self::message(&text));
        self.keep(text);
    }

    /// A sample line (or the table's header): data, for stdout.
    pub(super) fn sample(&self, text: String) {
        if self.echo {
            crate::service::stdout_lines::stdout().line(text.as_str());
        }
        self.keep(text);
    }

    /// `text` as a log message: the logger names the target (`antennad`) itself.
    pub(super) fn message(text: &str) -> &str {
        let text = text.trim_start();
        text.strip_prefix("antennad: ").unwrap_or(text)
    }

    pub(super) fn keep(&self, text: String) {
        if let Ok(mut lines) = self.lines.lock() {
            if lines.len() >= LOG_LINES_KEPT {
                lines.pop_front();
            }
            lines.push_back(text);
        }
    }

    pub(super) fn lines(&self) -> Vec<String> {
        self.lines
            .lock()
            .map(|l| l.iter().cloned().collect())
            .unwrap_or_default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_log_keeps_the_last_lines_in_order() {
        let log = Log {
            echo: false,
            lines: Arc::new(Mutex::new(VecDeque::new())),
        };
        for k in 0..LOG_LINES_KEPT + 3 {
            log.line(format!("line {k}"));
        }
        log.warn("a warning".to_owned());
        let lines = log.lines();
        assert_eq!(lines.len(), LOG_LINES_KEPT);
        assert_eq!(lines[0], "line 4");
        assert_eq!(lines.last().map(String::as_str), Some("a warning"));
        assert_eq!(Log::message("  antennad: started"), "started");
        assert_eq!(Log::message("plain"), "plain");
    }
}
