//! Progress bars on stderr for long commands (`antenna sweep`, `antenna study`, `antenna
//! optimize`): indicatif's, drawn only when stderr is a terminal (at most ten times a second)
//! and cleared at the end, so that redirected output stays clean: off a terminal nothing is
//! written.

use std::time::Duration;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressFinish, ProgressState, ProgressStyle};

/// Redraws per second, at most.
const REDRAW_HZ: u8 = 10;
/// The bar's line: `[########----------------------] 50/200 steps (25 %), 10.0 s, 30 s left`,
/// then the message (e.g. `", best 46.3 mm"`).
const TEMPLATE: &str = "[{bar:30}] {pos}/{len} {prefix} ({percent} %), {elapsed_s}{left}{msg}";

/// A progress bar over `total` `unit`s (e.g. "steps") on stderr, drawn when `enabled` and
/// stderr is a terminal, cleared when finished or dropped. Its position is the units done;
/// its message follows the line.
pub fn bar(total: usize, unit: &'static str, enabled: bool) -> ProgressBar {
    let target = if enabled {
        ProgressDrawTarget::stderr_with_hz(REDRAW_HZ)
    } else {
        ProgressDrawTarget::hidden()
    };
    let style = ProgressStyle::with_template(TEMPLATE)
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("#-")
        .with_key("elapsed_s", write_elapsed)
        .with_key("left", write_left);
    ProgressBar::with_draw_target(Some(total as u64), target)
        .with_style(style)
        .with_prefix(unit)
        .with_finish(ProgressFinish::AndClear)
}

/// `10.0 s`: the time since the bar started.
fn write_elapsed(state: &ProgressState, w: &mut dyn std::fmt::Write) {
    let _ = write!(w, "{:.1} s", state.elapsed().as_secs_f64());
}

/// indicatif's estimate of the time left, while some but not all units are done.
fn write_left(state: &ProgressState, w: &mut dyn std::fmt::Write) {
    let running = state
        .len()
        .is_some_and(|len| (1..len).contains(&state.pos()));
    if running {
        let _ = w.write_str(&time_left(state.eta()));
    }
}

/// `, 1.0 s left` (one decimal under 10 s), `, 30 s left`.
fn time_left(left: Duration) -> String {
    let left_s = left.as_secs_f64();
    let decimals = if left_s < 10.0 { 1 } else { 0 };
    format!(", {left_s:.decimals$} s left")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_time_left_has_a_decimal_under_ten_seconds() {
        assert_eq!(time_left(Duration::from_secs(30)), ", 30 s left");
        assert_eq!(time_left(Duration::from_secs(1)), ", 1.0 s left");
    }

    #[test]
    fn a_bar_not_enabled_is_hidden_and_counts() {
        let bar = bar(200, "steps", false);
        assert!(bar.is_hidden());
        bar.set_position(50);
        assert_eq!((bar.position(), bar.length()), (50, Some(200)));
        bar.finish_and_clear();
        assert!(bar.is_finished());
    }
}
