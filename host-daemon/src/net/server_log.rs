//! [`ServerLog`]: where the server says who did what (failed authentications, `stop_all`,
//! connections dropped or refused), each line naming the peer's address and never a token.

use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Connection notices (drops and refusals) logged per second at most; the rest are counted.
const NOTICES_PER_SECOND: u32 = 10;

type Sink = Arc<dyn Fn(String) + Send + Sync>;

/// A line sink for the server's notices (default: none).
#[derive(Clone, Default)]
pub struct ServerLog {
    sink: Option<Sink>,
    notices: Arc<Mutex<NoticeWindow>>,
}

#[derive(Debug, Default)]
struct NoticeWindow {
    started: Option<Instant>,
    logged: u32,
    suppressed: u64,
}

impl std::fmt::Debug for ServerLog {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ServerLog")
            .field("sink", &self.sink.is_some())
            .finish()
    }
}

impl ServerLog {
    /// Lines go to `sink`.
    pub fn new(sink: impl Fn(String) + Send + Sync + 'static) -> Self {
        Self {
            sink: Some(Arc::new(sink)),
            notices: Arc::default(),
        }
    }

    /// Logs `text`.
    pub fn line(&self, text: String) {
        if let Some(sink) = &self.sink {
            sink(text);
        }
    }

    /// Logs a connection notice, at most ten a second (a flood of
    /// connections must not flood the log); the count of those left out comes with the next
    /// one logged.
    pub fn notice(&self, text: String) {
        if self.sink.is_none() {
            return;
        }
        let now = Instant::now();
        let mut window = self.notices.lock().unwrap_or_else(|p| p.into_inner());
        let fresh = window
            .started
            .is_none_or(|t| now.duration_since(t) >= Duration::from_secs(1));
        if fresh {
            window.started = Some(now);
            window.logged = 0;
        }
        if window.logged >= NOTICES_PER_SECOND {
            window.suppressed += 1;
            return;
        }
        window.logged += 1;
        let suppressed = std::mem::take(&mut window.suppressed);
        drop(window);
        if suppressed > 0 {
            self.line(format!(
                "{text} ({suppressed} connection notices left out before it)"
            ));
        } else {
            self.line(text);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn notices_are_rate_limited_and_counted() {
        let lines = Arc::new(Mutex::new(Vec::new()));
        let sink = Arc::clone(&lines);
        let log = ServerLog::new(move |l| sink.lock().unwrap().push(l));
        for i in 0..25 {
            log.notice(format!("notice {i}"));
        }
        log.line("always".to_owned());
        let lines = lines.lock().unwrap();
        assert_eq!(lines.len(), NOTICES_PER_SECOND as usize + 1);
        assert_eq!(lines.last().map(String::as_str), Some("always"));
    }
}
