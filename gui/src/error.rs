//! [`MonitorError`]: what went wrong in the monitor's library, and where.

use std::path::PathBuf;

/// Errors of the monitor's library; each names what failed and where.
#[derive(Debug, thiserror::Error)]
pub enum MonitorError {
    /// A sample did not have the history's number of segments.
    #[error("a sample with {found} segments does not fit a history of {expected} segments")]
    SegmentCount {
        /// Segments the history holds per sample.
        expected: usize,
        /// Segments in the sample.
        found: usize,
    },
    /// A sample older than the newest one held, or with a time that is not finite.
    #[error("a sample at t = {t_s} s arrived after one at t = {latest_t_s} s")]
    TimeOrder {
        /// The refused sample's time, seconds.
        t_s: f64,
        /// The newest held sample's time, seconds.
        latest_t_s: f64,
    },
    /// The rig's geometry is unusable.
    #[error("rig geometry: {0}")]
    Geometry(String),
    /// Reading a trial recording failed.
    #[error("{}: {source}", path.display())]
    Recording {
        /// The file.
        path: PathBuf,
        /// Why.
        source: antenna_data::record::RecordError,
    },
    /// A recording holds no segment poll.
    #[error("{}: the recording holds no segment poll", path.display())]
    EmptyRecording {
        /// The file.
        path: PathBuf,
    },
    /// Writing an export failed.
    #[error("writing {}: {source}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// Drawing an exported figure failed.
    #[error("drawing {}: {message}", path.display())]
    Draw {
        /// The file.
        path: PathBuf,
        /// The plotting backend's message.
        message: String,
    },
    /// Nothing to export in the visible range.
    #[error("nothing to export: no sample between {t0_s:.3} s and {t1_s:.3} s")]
    NothingToExport {
        /// The range's start, seconds.
        t0_s: f64,
        /// The range's end, seconds.
        t1_s: f64,
    },
    /// The posture prediction failed.
    #[error("prediction: {0}")]
    Prediction(String),
    /// A simulated sweep could not be run or drawn.
    #[error("sweep: {0}")]
    Sweep(String),
    /// A scene file that cannot be read, does not parse or cannot be swept; the message names
    /// the file, the key and, where known, its line and column.
    #[error("scene file {0}")]
    Scene(#[from] antenna_scene::SceneError),
    /// A simulated sweep stopped before its end (its placement or a step failed); the steps
    /// before it are kept.
    #[error("the sweep stopped at t = {t_s:.3} s, {frames_kept} frames kept: {source}")]
    SweepStopped {
        /// When it stopped: the failed step's time (0 for the placement), seconds.
        t_s: f64,
        /// The frames computed before it (the placed posture counts as one).
        frames_kept: usize,
        /// What failed, worded with the scene file, the key or the step.
        source: antenna_scene::SweepFailure,
    },
    /// A `--jsonl` file of `antenna follow` that cannot be read or played; `line` is 1-based
    /// (0: the file could not be read).
    #[error("{}:{line}: {message}", path.display())]
    FollowFile {
        /// The file.
        path: PathBuf,
        /// The line.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A follow scene's closed-loop run could not start, or stopped before its end (the
    /// steps before it are kept).
    #[error("follow: {0}")]
    Follow(String),
    /// A control command was not sent.
    #[error("control: {0}")]
    Control(String),
}

impl From<antenna_figure::FigureError> for MonitorError {
    fn from(e: antenna_figure::FigureError) -> Self {
        use antenna_figure::FigureError;
        match e {
            FigureError::Write { path, source } => MonitorError::Write { path, source },
            FigureError::Encode { path, message } => MonitorError::Draw { path, message },
            FigureError::Font => MonitorError::Draw {
                path: std::path::PathBuf::new(),
                message: e.to_string(),
            },
        }
    }
}
