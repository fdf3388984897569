//! A one-line progress bar on stderr for long commands (`antenna sweep`, `antenna study`):
//! drawn only when stderr is a terminal, at most ten times a second, and cleared at the end,
//! so that redirected output stays clean.

use std::io::{IsTerminal as _, Write as _};
use std::time::{Duration, Instant};

/// Width of the bar, characters.
const BAR_WIDTH: usize = 30;
/// Least time between two redraws.
const REDRAW_EVERY: Duration = Duration::from_millis(100);

/// A progress bar over `total` units of work.
#[derive(Debug)]
pub struct Progress {
    total: usize,
    unit: &'static str,
    started: Instant,
    last_drawn: Option<Instant>,
    enabled: bool,
}

impl Progress {
    /// A bar over `total` `unit`s (e.g. "steps"), shown when stderr is a terminal.
    pub fn new(total: usize, unit: &'static str) -> Progress {
        Progress {
            total,
            unit,
            started: Instant::now(),
            last_drawn: None,
            enabled: std::io::stderr().is_terminal(),
        }
    }

    /// Whether the bar is drawn at all.
    pub fn is_enabled(&self) -> bool {
        self.enabled
    }

    /// Shows that `done` units are done (redrawn at most every 100 ms, and at the end).
    pub fn set(&mut self, done: usize) {
        self.set_noted(done, "");
    }

    /// As [`Self::set`], with `note` after the bar's text (e.g. `", best 46.3 mm"`).
    pub fn set_noted(&mut self, done: usize, note: &str) {
        if !self.enabled {
            return;
        }
        let now = Instant::now();
        let due = self
            .last_drawn
            .is_none_or(|t| now.duration_since(t) >= REDRAW_EVERY);
        if !due && done < self.total {
            return;
        }
        self.last_drawn = Some(now);
        let line = self.line(done, now.duration_since(self.started));
        let mut err = std::io::stderr().lock();
        let _ = write!(err, "\r{line}{note}\x1b[K");
        let _ = err.flush();
    }

    /// The bar's text for `done` units after `elapsed`.
    pub fn line(&self, done: usize, elapsed: Duration) -> String {
        let fraction = if self.total == 0 {
            1.0
        } else {
            (done as f64 / self.total as f64).clamp(0.0, 1.0)
        };
        let filled = (fraction * BAR_WIDTH as f64).round() as usize;
        let bar: String = "#".repeat(filled) + &"-".repeat(BAR_WIDTH - filled);
        let elapsed_s = elapsed.as_secs_f64();
        let eta = if done > 0 && done < self.total {
            let left_s = elapsed_s * (self.total - done) as f64 / done as f64;
            let decimals = if left_s < 10.0 { 1 } else { 0 };
            format!(", {left_s:.decimals$} s left")
        } else {
            String::new()
        };
        format!(
            "[{bar}] {done}/{} {} ({:.0} %), {elapsed_s:.1} s{eta}",
            self.total,
            self.unit,
            100.0 * fraction
        )
    }

    /// Clears the bar's line.
    pub fn finish(&mut self) {
        if self.enabled && self.last_drawn.is_some() {
            let mut err = std::io::stderr().lock();
            let _ = write!(err, "\r\x1b[K");
            let _ = err.flush();
        }
        self.enabled = false;
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        self.finish();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_line_shows_the_fraction_and_what_is_left() {
        let p = Progress::new(200, "steps");
        let line = p.line(50, Duration::from_secs(10));
        assert!(line.starts_with("[########----------------------] 50/200 steps (25 %)"));
        assert!(line.ends_with("10.0 s, 30 s left"), "{line}");
        let soon = p.line(150, Duration::from_secs(3));
        assert!(soon.ends_with("3.0 s, 1.0 s left"), "{soon}");
        assert!(p.line(200, Duration::from_secs(1)).contains("(100 %)"));
        assert!(
            Progress::new(0, "runs")
                .line(0, Duration::ZERO)
                .contains("(100 %)")
        );
    }
}
