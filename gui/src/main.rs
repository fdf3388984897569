//! `antenna-monitor`: the desktop monitor (see the library's documentation).

use std::path::PathBuf;
use std::time::Duration;

use antenna_monitor::screenshot::{MIN_CHAIN_EXTENT_PX, MIN_CHAIN_PIXELS, check_png};
use antenna_monitor::{AppOptions, MonitorApp, is_software_gl, tune_for_software_gl};
use anyhow::{Context, Result, bail};
use clap::Parser;

/// The egui desktop monitor for antennad's live chain, recorded trials, simulated sweeps and
/// closed-loop wall-following runs.
#[derive(Debug, Parser)]
#[command(
    version,
    after_help = "Examples:\n  antenna-monitor --connect 127.0.0.1:7878\n  \
                  antenna-monitor --connect 127.0.0.1:7878 --token \"$ANTENNA_TOKEN\"\n  \
                  antenna-monitor --trial data/wall-sweep.mcap\n  \
                  antenna-monitor --scene examples/sweep_line_wall.toml\n  \
                  antenna-monitor --scene examples/follow/straight_wall.toml\n  \
                  antenna-monitor --follow run.jsonl   # from antenna follow SCENE --jsonl"
)]
struct Args {
    /// antennad's stream, host:port (the default when no trial or scene is given:
    /// 127.0.0.1:7878).
    #[arg(long, value_name = "ADDR")]
    connect: Option<String>,
    /// The control token antennad printed at start (watching needs none). Without it, the
    /// environment variable ANTENNA_TOKEN is used if set.
    #[arg(long)]
    token: Option<String>,
    /// Open a recorded trial (MCAP) to scrub instead of connecting.
    #[arg(long, value_name = "FILE", conflicts_with = "connect")]
    trial: Option<PathBuf>,
    /// Run a scene file's sweep, or a follow scene's closed-loop run (sim-core, on a worker
    /// thread), and animate it instead of connecting.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["connect", "trial"])]
    scene: Option<PathBuf>,
    /// Play a closed-loop run written by `antenna follow SCENE --jsonl` instead of
    /// connecting.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["connect", "trial", "scene"])]
    follow: Option<PathBuf>,
    /// Seconds of live history kept (the plots' longest window).
    #[arg(long, default_value_t = 60.0)]
    history_s: f64,
    /// Where exports (CSV, PNG, SVG) are written.
    #[arg(long, default_value = ".")]
    export_dir: PathBuf,
    /// Before opening the window, wait until the live history spans this many seconds and
    /// the first prediction is in (a scene's sweep or follow run: until it has run this many
    /// seconds, or ended; at most 10 s longer): for screenshots.
    #[arg(long, value_name = "S")]
    wait_for_history_s: Option<f64>,
    /// After the wait, put the cursor at this time, seconds (for screenshots of a run's
    /// middle).
    #[arg(long, value_name = "S", hide = true)]
    at_s: Option<f64>,
    /// Window size in points, WIDTHxHEIGHT.
    #[arg(long, default_value = "1280x800")]
    size: String,
    /// Check a screenshot of this app for the chain being drawn and exit (0: drawn, 1: not);
    /// scripts/monitor-screenshot uses it.
    #[arg(long, value_name = "PNG", hide = true)]
    check_screenshot: Option<PathBuf>,
}

fn main() -> Result<()> {
    let args = Args::parse();
    if let Some(path) = &args.check_screenshot {
        return check_screenshot(path);
    }
    if !(args.history_s.is_finite() && args.history_s > 0.0) {
        bail!("--history-s must be positive, got {}", args.history_s);
    }
    let (width, height) = args
        .size
        .split_once('x')
        .and_then(|(w, h)| Some((w.parse::<f32>().ok()?, h.parse::<f32>().ok()?)))
        .with_context(|| format!("--size {:?}: expected WIDTHxHEIGHT", args.size))?;
    let connect = match (&args.connect, &args.trial, &args.scene, &args.follow) {
        (None, None, None, None) => Some("127.0.0.1:7878".to_owned()),
        (c, ..) => c.clone(),
    };
    let mut app = MonitorApp::new(AppOptions {
        connect,
        token: args
            .token
            .or_else(|| std::env::var("ANTENNA_TOKEN").ok())
            .unwrap_or_default(),
        trial: args.trial,
        scene: args.scene,
        follow: args.follow,
        history_s: args.history_s,
        export_dir: args.export_dir,
    });
    if let Some((message, true)) = app.message() {
        bail!("{message}");
    }
    if let Some(s) = args.wait_for_history_s
        && !app.wait_for_data(s, Duration::from_secs_f64(s.max(0.0) + 10.0))
    {
        eprintln!(
            "antenna-monitor: no data within {} s; opening anyway",
            s + 10.0
        );
    }
    if let Some(t_s) = args.at_s {
        if !t_s.is_finite() {
            bail!("--at-s must be finite, got {t_s}");
        }
        app.scrub_to(t_s);
    }
    let options = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_title("antenna-monitor")
            .with_inner_size([width, height]),
        renderer: eframe::Renderer::Glow,
        ..Default::default()
    };
    eframe::run_native(
        "antenna-monitor",
        options,
        Box::new(move |cc| {
            if cc.gl.as_deref().is_some_and(is_software_gl) {
                tune_for_software_gl(&cc.egui_ctx);
            }
            Ok(Box::new(app))
        }),
    )
    .map_err(|e| anyhow::anyhow!("the window failed: {e}"))
}

/// `--check-screenshot`: is the chain drawn in this PNG?
fn check_screenshot(path: &std::path::Path) -> Result<()> {
    let bytes = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
    let report = check_png(&bytes)
        .map_err(anyhow::Error::msg)
        .with_context(|| format!("checking {}", path.display()))?;
    println!(
        "check-screenshot: {}: {}x{} px, {} chain-coloured pixels in the chain panel (need \
         {MIN_CHAIN_PIXELS}), spanning {:?} (need {MIN_CHAIN_EXTENT_PX} px)",
        path.display(),
        report.size_px.0,
        report.size_px.1,
        report.chain_pixels,
        report.chain_box_px
    );
    if !report.chain_drawn() {
        bail!(
            "{}: the chain is not drawn (a blank window?)",
            path.display()
        );
    }
    println!("check-screenshot: the chain is drawn");
    Ok(())
}
