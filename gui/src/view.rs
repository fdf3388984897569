//! [`ViewState`]: which time window the plots show and which instant the chain panel draws.
//!
//! Acquisition never stops; only the view does. Following, the window ends at the newest
//! sample and the chain is the newest one. Paused (or after a pan or a scrub), the window
//! and the cursor stay where they are while samples keep arriving in the history behind
//! them. Zooming changes the window's width (following, its end stays on the newest sample).

/// The narrowest window, seconds.
pub const MIN_WINDOW_S: f64 = 0.01;

/// The view (see the module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct ViewState {
    follow: bool,
    window_s: f64,
    /// The window's end when not following, seconds.
    end_s: f64,
    /// The instant the chain panel draws, when not the window's end.
    cursor_s: Option<f64>,
}

impl ViewState {
    /// Following the newest sample with a window `window_s` wide.
    pub fn new(window_s: f64) -> Self {
        Self {
            follow: true,
            window_s: window_s.max(MIN_WINDOW_S),
            end_s: 0.0,
            cursor_s: None,
        }
    }

    /// Whether the view follows the newest sample.
    pub fn is_following(&self) -> bool {
        self.follow
    }

    /// The window's width, seconds.
    pub fn window_s(&self) -> f64 {
        self.window_s
    }

    /// The window `(t0_s, t1_s)` given the newest sample's time (`None`: no data yet).
    pub fn window(&self, latest_s: Option<f64>) -> Option<(f64, f64)> {
        let end = if self.follow { latest_s? } else { self.end_s };
        Some((end - self.window_s, end))
    }

    /// The instant the chain panel draws.
    pub fn cursor_s(&self, latest_s: Option<f64>) -> Option<f64> {
        if self.follow {
            return latest_s;
        }
        Some(self.cursor_s.unwrap_or(self.end_s))
    }

    /// Freezes the view at the newest sample; data keeps arriving behind it.
    pub fn pause(&mut self, latest_s: Option<f64>) {
        if self.follow
            && let Some(latest) = latest_s
        {
            self.end_s = latest;
            self.cursor_s = None;
            self.follow = false;
        }
    }

    /// Follows the newest sample again.
    pub fn follow_latest(&mut self) {
        self.follow = true;
        self.cursor_s = None;
    }

    /// Multiplies the window's width by `factor` (< 1 zooms in), at most `max_window_s`.
    /// Paused, the window keeps its centre, or the cursor if there is one.
    pub fn zoom(&mut self, factor: f64, max_window_s: f64) {
        if !(factor.is_finite() && factor > 0.0) {
            return;
        }
        let old = self.window_s;
        self.window_s =
            (self.window_s * factor).clamp(MIN_WINDOW_S, max_window_s.max(MIN_WINDOW_S));
        if !self.follow {
            let centre = self.cursor_s.unwrap_or(self.end_s - old / 2.0);
            self.end_s = centre + self.window_s / 2.0;
        }
    }

    /// Adopts a window the user made in a plot (a pan or a wheel zoom). A window still
    /// ending at the newest sample keeps following; any other stops following.
    pub fn set_window(&mut self, t0_s: f64, t1_s: f64, latest_s: Option<f64>, max_window_s: f64) {
        if t1_s.partial_cmp(&t0_s) != Some(std::cmp::Ordering::Greater) {
            return;
        }
        self.window_s = (t1_s - t0_s).clamp(MIN_WINDOW_S, max_window_s.max(MIN_WINDOW_S));
        let at_latest = latest_s.is_some_and(|l| (t1_s - l).abs() <= 1e-3 * self.window_s);
        if self.follow && at_latest {
            return;
        }
        self.follow = false;
        self.end_s = t1_s;
        if let Some(c) = self.cursor_s
            && !(t0_s..=t1_s).contains(&c)
        {
            self.cursor_s = None;
        }
    }

    /// Shows exactly `t0_s..=t1_s` with the chain at `cursor_s` (stops following).
    pub fn show_range(&mut self, t0_s: f64, t1_s: f64, cursor_s: f64) {
        self.follow = false;
        self.window_s = (t1_s - t0_s).max(MIN_WINDOW_S);
        self.end_s = t0_s + self.window_s;
        self.cursor_s = Some(cursor_s);
    }

    /// Moves the chain panel's instant to `t_s` (stops following); the window moves with it
    /// if `t_s` falls outside.
    pub fn scrub(&mut self, t_s: f64, latest_s: Option<f64>) {
        if let Some((t0, t1)) = self.window(latest_s) {
            if !self.follow && (t0..=t1).contains(&t_s) {
                // stays
            } else if (t0..=t1).contains(&t_s) {
                self.end_s = t1;
            } else {
                self.end_s = t_s + self.window_s / 2.0;
            }
        } else {
            self.end_s = t_s;
        }
        self.follow = false;
        self.cursor_s = Some(t_s);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pause_freezes_the_window_while_data_arrives() {
        let mut v = ViewState::new(10.0);
        assert_eq!(v.window(Some(20.0)), Some((10.0, 20.0)));
        v.pause(Some(20.0));
        assert_eq!(v.window(Some(25.0)), Some((10.0, 20.0)));
        assert_eq!(v.cursor_s(Some(25.0)), Some(20.0));
        v.zoom(0.5, 60.0);
        assert_eq!(v.window(Some(25.0)), Some((12.5, 17.5)));
        v.scrub(13.0, Some(25.0));
        assert_eq!(v.cursor_s(Some(30.0)), Some(13.0));
        assert_eq!(v.window(Some(30.0)), Some((12.5, 17.5)));
        v.scrub(40.0, Some(45.0));
        assert_eq!(v.window(Some(45.0)), Some((37.5, 42.5)));
        v.follow_latest();
        assert_eq!(v.window(Some(50.0)), Some((45.0, 50.0)));
        assert_eq!(v.cursor_s(Some(50.0)), Some(50.0));
    }

    #[test]
    fn a_pan_stops_following_a_wheel_zoom_at_the_end_does_not() {
        let mut v = ViewState::new(10.0);
        v.set_window(12.0, 20.0, Some(20.0), 60.0);
        assert!(v.is_following());
        assert_eq!(v.window_s(), 8.0);
        v.set_window(5.0, 13.0, Some(20.0), 60.0);
        assert!(!v.is_following());
        assert_eq!(v.window(Some(30.0)), Some((5.0, 13.0)));
        v.zoom(100.0, 60.0);
        assert_eq!(v.window_s(), 60.0);
    }
}
