//! Lines for standard output that can neither kill nor stall the daemon.
//!
//! `println!` panics when standard output is gone (a closed pipe: `EPIPE`), and any write
//! blocks while the reader does not read (a full pipe, a paused terminal). The sample lines
//! are written from the hub thread, which must not stop for either. A [`LineSink`] hands each
//! line to a writer thread through a bounded queue: [`LineSink::line`] never blocks (a line
//! that finds the queue full is dropped and counted), and a write error ends the writing, not
//! the daemon (the lines are dropped from then on). [`stdout`] is the process's one sink for
//! standard output.
//!
//! ```
//! use host_daemon::service::stdout_lines::LineSink;
//! use std::time::Duration;
//!
//! let (sink, written) = LineSink::to_buffer(16);
//! sink.line("  0.25    12.5    3.0");
//! assert!(sink.flush(Duration::from_secs(5)));
//! assert_eq!(written.lock().unwrap().as_slice(), b"  0.25    12.5    3.0\n");
//! ```

use std::io::Write;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, SyncSender, TrySendError, sync_channel};
use std::sync::{Arc, Mutex, OnceLock};
use std::time::{Duration, Instant};

/// Lines queued for standard output before new ones are dropped: some seconds of sample
/// lines at any sensible print rate.
const STDOUT_QUEUE_LINES: usize = 4096;

enum Message {
    Line(String),
    /// Answered once every line queued before it has been written (or dropped).
    Flush(SyncSender<()>),
}

/// A line writer on its own thread (see the module documentation). Cloning shares the queue.
#[derive(Debug, Clone)]
pub struct LineSink {
    queue: SyncSender<Message>,
    state: Arc<SinkState>,
}

#[derive(Debug, Default)]
struct SinkState {
    /// Lines dropped because the queue was full or the writer had failed.
    dropped: AtomicU64,
    /// The writer's first error, once it has failed.
    failed: AtomicBool,
    error: Mutex<Option<String>>,
}

impl LineSink {
    /// A sink writing to `writer` on a new thread, holding up to `capacity` lines.
    pub fn spawn(writer: impl Write + Send + 'static, capacity: usize) -> std::io::Result<Self> {
        let (queue, lines) = sync_channel(capacity.max(1));
        let state = Arc::new(SinkState::default());
        let thread_state = Arc::clone(&state);
        std::thread::Builder::new()
            .name("antennad-stdout".to_owned())
            .spawn(move || write_lines(writer, &lines, &thread_state))?;
        Ok(Self { queue, state })
    }

    /// A sink writing into a shared buffer (tests, examples).
    pub fn to_buffer(capacity: usize) -> (Self, Arc<Mutex<Vec<u8>>>) {
        let buffer = Arc::new(Mutex::new(Vec::new()));
        let writer = SharedBuffer(Arc::clone(&buffer));
        let sink = match Self::spawn(writer, capacity) {
            Ok(sink) => sink,
            // No thread to be had: a sink whose writer is already gone drops every line.
            Err(e) => Self::failed(&e.to_string()),
        };
        (sink, buffer)
    }

    /// Queues `text` and a newline; never blocks. Dropped (and counted) when the queue is
    /// full or the writer has failed.
    pub fn line(&self, text: impl Into<String>) {
        match self.queue.try_send(Message::Line(text.into())) {
            Ok(()) => {}
            Err(TrySendError::Full(_) | TrySendError::Disconnected(_)) => {
                self.state.dropped.fetch_add(1, Ordering::Relaxed);
            }
        }
    }

    /// Waits up to `timeout` for every line queued so far to be written; whether they were.
    /// (At exit: the last lines get out, but a reader that never reads cannot hold the
    /// daemon.)
    pub fn flush(&self, timeout: Duration) -> bool {
        let deadline = Instant::now() + timeout;
        let (done, answer) = sync_channel(1);
        let mut message = Message::Flush(done);
        // `SyncSender` has no send with a deadline: a full queue is retried briefly.
        loop {
            match self.queue.try_send(message) {
                Ok(()) => break,
                Err(TrySendError::Disconnected(_)) => return false,
                Err(TrySendError::Full(back)) => {
                    if Instant::now() >= deadline {
                        return false;
                    }
                    message = back;
                    std::thread::sleep(Duration::from_millis(5));
                }
            }
        }
        answer
            .recv_timeout(deadline.saturating_duration_since(Instant::now()))
            .is_ok()
    }

    /// Lines dropped so far (a full queue, or a failed writer).
    pub fn dropped(&self) -> u64 {
        self.state.dropped.load(Ordering::Relaxed)
    }

    /// The write error that ended the writing, if one did (`Broken pipe` for a closed pipe).
    pub fn error(&self) -> Option<String> {
        if !self.state.failed.load(Ordering::Relaxed) {
            return None;
        }
        self.state.error.lock().ok().and_then(|e| e.clone())
    }

    /// A sink with no writer: every line is dropped.
    fn failed(why: &str) -> Self {
        let (queue, _) = sync_channel(1);
        let state = Arc::new(SinkState::default());
        state.failed.store(true, Ordering::Relaxed);
        if let Ok(mut error) = state.error.lock() {
            *error = Some(why.to_owned());
        }
        Self { queue, state }
    }
}

/// The process's sink for standard output (started on first use).
pub fn stdout() -> &'static LineSink {
    static STDOUT: OnceLock<LineSink> = OnceLock::new();
    STDOUT.get_or_init(|| {
        LineSink::spawn(std::io::stdout(), STDOUT_QUEUE_LINES)
            .unwrap_or_else(|e| LineSink::failed(&format!("starting the stdout writer: {e}")))
    })
}

/// The writer thread: writes each line, flushing when the queue runs dry; after the first
/// error it only drains (and counts) what comes.
fn write_lines(mut writer: impl Write, lines: &Receiver<Message>, state: &SinkState) {
    while let Ok(message) = lines.recv() {
        let mut next = Some(message);
        while let Some(message) = next.take() {
            match message {
                Message::Line(text) => {
                    if state.failed.load(Ordering::Relaxed) {
                        state.dropped.fetch_add(1, Ordering::Relaxed);
                    } else if let Err(e) = writeln!(writer, "{text}") {
                        fail(state, &e);
                    }
                }
                Message::Flush(done) => {
                    if !state.failed.load(Ordering::Relaxed)
                        && let Err(e) = writer.flush()
                    {
                        fail(state, &e);
                    }
                    let _ = done.send(());
                }
            }
            next = lines.try_recv().ok();
        }
        if !state.failed.load(Ordering::Relaxed)
            && let Err(e) = writer.flush()
        {
            fail(state, &e);
        }
    }
}

fn fail(state: &SinkState, e: &std::io::Error) {
    if let Ok(mut error) = state.error.lock() {
        *error = Some(e.to_string());
    }
    state.failed.store(true, Ordering::Relaxed);
    state.dropped.fetch_add(1, Ordering::Relaxed);
}

/// A writer into a shared buffer.
struct SharedBuffer(Arc<Mutex<Vec<u8>>>);

impl Write for SharedBuffer {
    fn write(&mut self, bytes: &[u8]) -> std::io::Result<usize> {
        self.0
            .lock()
            .map_err(|_| std::io::Error::other("the buffer's lock is poisoned"))?
            .extend_from_slice(bytes);
        Ok(bytes.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A writer that fails every write, as a closed pipe does.
    struct Closed;

    impl Write for Closed {
        fn write(&mut self, _: &[u8]) -> std::io::Result<usize> {
            Err(std::io::ErrorKind::BrokenPipe.into())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Err(std::io::ErrorKind::BrokenPipe.into())
        }
    }

    /// A writer that never returns, as a full pipe nobody reads.
    struct Stuck;

    impl Write for Stuck {
        fn write(&mut self, _: &[u8]) -> std::io::Result<usize> {
            loop {
                std::thread::park();
            }
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn lines_are_written_in_order() {
        let (sink, buffer) = LineSink::to_buffer(64);
        for k in 0..10 {
            sink.line(format!("line {k}"));
        }
        assert!(sink.flush(Duration::from_secs(10)));
        let text = String::from_utf8(buffer.lock().unwrap().clone()).unwrap();
        let expected: String = (0..10).map(|k| format!("line {k}\n")).collect();
        assert_eq!(text, expected);
        assert_eq!(sink.dropped(), 0);
        assert_eq!(sink.error(), None);
    }

    #[test]
    fn a_closed_writer_drops_lines_and_says_why() {
        let sink = LineSink::spawn(Closed, 8).unwrap();
        for k in 0..5 {
            sink.line(format!("line {k}"));
        }
        sink.flush(Duration::from_secs(10));
        let error = sink.error().unwrap();
        assert!(error.to_lowercase().contains("broken pipe"), "{error}");
        assert_eq!(sink.dropped(), 5);
    }

    /// A writer that never returns stalls neither `line` nor `flush` beyond its timeout
    /// (bounds generous for a loaded machine: the calls themselves take microseconds).
    #[test]
    fn a_stuck_writer_blocks_nobody() {
        let sink = LineSink::spawn(Stuck, 4).unwrap();
        let started = Instant::now();
        for k in 0..1000 {
            sink.line(format!("line {k}"));
        }
        assert!(started.elapsed() < Duration::from_secs(2));
        // One line is in the stuck write, four wait in the queue: the rest are dropped.
        assert!(sink.dropped() >= 1000 - 5, "{}", sink.dropped());
        let started = Instant::now();
        assert!(!sink.flush(Duration::from_millis(200)));
        assert!(started.elapsed() < Duration::from_secs(3));
    }
}
