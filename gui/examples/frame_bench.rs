//! Frame time of the monitor with a long chain and a full history, in a real window:
//! `scripts/bench-monitor` runs it under Xvfb with Mesa's software OpenGL and writes the
//! figures into docs/benchmarks/monitor.md.
//!
//! A stream server (antennad's own `StreamServer`) announces a rig of `--segments` segments
//! and publishes one `samples` line per millisecond through TCP to the monitor's real client;
//! before the window opens, the client's history is filled with `--history-s` seconds of
//! synthetic polls at 1 kHz (touches, a moving stage). The monitor then follows the newest
//! sample, redrawing as fast as it can (no vsync), with the prediction worker solving every
//! new stage position. The time between the starts of consecutive frames (the app's work,
//! tessellation, software rasterization and the buffer swap) is recorded after a warm-up;
//! p50, p99 and the mean rate are printed and, with `--json`, written to a file.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use antenna_data::stream::{RigInfo, SegmentSample, StreamMessage};
use antenna_monitor::history::{Health, Sample, SegmentReading};
use antenna_monitor::{AppOptions, MonitorApp, is_software_gl, tune_for_software_gl};
use anyhow::{Context, Result, bail};
use clap::Parser;
use host_daemon::net::{ControlToken, RecordingHandler, ServerOptions, StreamServer};

/// Measures the monitor's frame time (see the file's documentation).
#[derive(Debug, Parser)]
struct Args {
    /// Segments in the chain.
    #[arg(long, default_value_t = 150)]
    segments: usize,
    /// Seconds of history at 1 kHz before the window opens.
    #[arg(long, default_value_t = 60.0)]
    history_s: f64,
    /// Frames measured.
    #[arg(long, default_value_t = 600)]
    frames: usize,
    /// Frames drawn before measuring.
    #[arg(long, default_value_t = 60)]
    warmup: usize,
    /// Leave the prediction out (a rig without a stiffness profile), to see its share.
    #[arg(long)]
    no_prediction: bool,
    /// Window width, points.
    #[arg(long, default_value_t = 1280.0)]
    width: f32,
    /// Window height, points.
    #[arg(long, default_value_t = 800.0)]
    height: f32,
    /// Keep egui's anti-aliasing feathering even on a software rasterizer (the monitor turns
    /// it off there), to see its share.
    #[arg(long)]
    force_feathering: bool,
    /// Write the figures here as JSON.
    #[arg(long)]
    json: Option<PathBuf>,
}

const RATE_HZ: f64 = 1000.0;
const LINK_M: f64 = 0.003;

/// The synthetic chain at `t_s`: a travelling bend, the distal tenth touching in bursts.
fn synthetic(t_s: f64, segments: usize) -> (Vec<f64>, Vec<bool>, f64) {
    let angles = (0..segments)
        .map(|k| 0.02 * (t_s * 2.0 + k as f64 * 0.05).sin() - 0.003)
        .collect();
    let touching = (t_s * 0.5).fract() < 0.6;
    let touches = (0..segments)
        .map(|k| touching && k >= segments - segments / 10)
        .collect();
    let stage_m = 0.15 + 0.1 * (t_s * 0.2).sin();
    (angles, touches, stage_m)
}

struct Bench {
    app: MonitorApp,
    starts: Vec<Instant>,
    /// Time in the app's `ui` (its work, before tessellation and painting), ms.
    ui_ms: Vec<f64>,
    /// eframe's measure of the previous frame's CPU time (the app, tessellation, painting;
    /// not the buffer swap), ms.
    cpu_ms: Vec<f64>,
    warmup: usize,
    frames: usize,
    json: Option<PathBuf>,
    segments: usize,
    history_s: f64,
    stop: Arc<AtomicBool>,
    result: Option<String>,
}

impl eframe::App for Bench {
    fn ui(&mut self, ui: &mut egui::Ui, frame: &mut eframe::Frame) {
        if let Some(cpu_s) = frame.info().cpu_usage {
            self.cpu_ms.push(f64::from(cpu_s) * 1e3);
        }
        let start = Instant::now();
        self.starts.push(start);
        self.app.ui(ui);
        self.ui_ms.push(start.elapsed().as_secs_f64() * 1e3);
        ui.ctx().request_repaint();
        if self.result.is_none() && self.starts.len() > self.warmup + self.frames {
            self.result = Some(self.report());
            self.stop.store(true, Ordering::Relaxed);
            ui.ctx().send_viewport_cmd(egui::ViewportCommand::Close);
        }
    }
}

impl Bench {
    fn report(&self) -> String {
        let mut ms: Vec<f64> = self.starts[self.warmup..]
            .windows(2)
            .map(|w| (w[1] - w[0]).as_secs_f64() * 1e3)
            .collect();
        let total_s: f64 = ms.iter().sum::<f64>() * 1e-3;
        ms.sort_by(f64::total_cmp);
        let pick = |q: f64| ms[((ms.len() - 1) as f64 * q).round() as usize];
        let (p50, p99) = (pick(0.5), pick(0.99));
        let mut ui_ms = self.ui_ms[self.warmup..].to_vec();
        ui_ms.sort_by(f64::total_cmp);
        let ui_p50 = ui_ms[ui_ms.len() / 2];
        let mut cpu_ms = self.cpu_ms[self.warmup.min(self.cpu_ms.len())..].to_vec();
        cpu_ms.sort_by(f64::total_cmp);
        let cpu_p50 = cpu_ms.get(cpu_ms.len() / 2).copied().unwrap_or(f64::NAN);
        let fps = ms.len() as f64 / total_s;
        let held = self.app.live().map_or(0, |c| c.lock().history.len());
        let text = format!(
            "{{\"segments\":{},\"history_s\":{},\"samples_held\":{held},\"frames\":{},\
             \"p50_ms\":{p50:.2},\"p99_ms\":{p99:.2},\"mean_fps\":{fps:.1},\"p50_fps\":{:.1},\"ui_p50_ms\":{ui_p50:.2},\"cpu_p50_ms\":{cpu_p50:.2}}}",
            self.segments,
            self.history_s,
            ms.len(),
            1e3 / p50
        );
        println!(
            "frame_bench: {} segments, {held} samples held ({} s at 1 kHz), {} frames: \
             p50 {p50:.2} ms, p99 {p99:.2} ms, mean {fps:.1} fps; the app's own ui pass \
             p50 {ui_p50:.2} ms, with tessellation and painting p50 {cpu_p50:.2} ms",
            self.segments,
            self.history_s,
            ms.len()
        );
        if let Some(path) = &self.json
            && let Err(e) = std::fs::write(path, &text)
        {
            eprintln!("frame_bench: writing {}: {e}", path.display());
        }
        text
    }
}

fn main() -> Result<()> {
    let args = Args::parse();
    if args.segments == 0 || args.frames < 2 {
        bail!("--segments must be at least 1 and --frames at least 2");
    }
    let n = args.segments;
    let links = vec![LINK_M; n + 1];
    // A chain of `n` segments against a wall 0.3 m from the track, tilted 30 degrees (the
    // prediction's scene), or the links alone (--no-prediction: no scene, no prediction).
    let scene = format!(
        "[antenna]\nlinks = {}\nlink_length_m = {LINK_M}\nbase_angle_deg = 30.0\n\
         [antenna.stiffness]\nprofile = \"linear\"\nmin_n_m_per_rad = 0.01\n\
         max_n_m_per_rad = 0.05\n[[walls]]\nshape = \"line\"\npoint_m = [0.0, 0.3]\n\
         angle_deg = -30.0\nsolid = \"left\"\nmu = 0.3\n",
        n + 1
    );
    let rig = RigInfo {
        poll_hz: RATE_HZ,
        stage_min_m: 0.0,
        stage_max_m: 0.3,
        scene_toml: (!args.no_prediction).then_some(scene),
        scene_source: Some("frame_bench".to_owned()),
        link_lengths_m: links,
        base_mount_angle_deg: 30.0,
        estimate_wall_side: None,
    };
    let server = StreamServer::bind_with(
        "127.0.0.1:0",
        ControlToken::new("frame-bench-token-0123").context("token")?,
        Arc::new(RecordingHandler::new()),
        ServerOptions {
            segment_addresses: (0..n).map(|k| (k % 256) as u8).collect(),
            rig: Some(rig),
            queue_capacity: 4096,
            ..ServerOptions::default()
        },
    )
    .context("starting the stream server")?;
    let app = MonitorApp::new(AppOptions {
        connect: Some(server.local_addr().to_string()),
        history_s: args.history_s,
        ..AppOptions::default()
    });
    // Wait for the hello, then fill the history.
    let deadline = Instant::now() + Duration::from_secs(10);
    loop {
        if app.live().is_some_and(|c| c.lock().rig.is_some()) {
            break;
        }
        if Instant::now() > deadline {
            bail!("the monitor did not connect to the bench's stream server");
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    let samples = (args.history_s * RATE_HZ) as u64;
    if let Some(client) = app.live() {
        let mut state = client.lock();
        for i in 0..samples {
            let t_s = i as f64 / RATE_HZ;
            let (angles, touches, stage_m) = synthetic(t_s, n);
            state.history.push(&Sample {
                seq: Some(i),
                t_s,
                segments: angles
                    .iter()
                    .zip(&touches)
                    .map(|(&a, &t)| SegmentReading {
                        angle_rad: Some(a),
                        touch_bits: Some(if t { 0x0F } else { 0 }),
                        health: Health::Ok,
                    })
                    .collect(),
                stage_position_m: Some(stage_m),
                servo_angle_rad: Some(0.0),
            })?;
        }
    }
    // Acquisition goes on: one samples line per millisecond after the prefilled history.
    let stop = Arc::new(AtomicBool::new(false));
    let publisher = {
        let stop = Arc::clone(&stop);
        std::thread::spawn(move || {
            let start = Instant::now();
            let mut seq = samples;
            while !stop.load(Ordering::Relaxed) {
                let t_s = seq as f64 / RATE_HZ;
                let due = start + Duration::from_secs_f64(t_s - samples as f64 / RATE_HZ);
                if let Some(wait) = due.checked_duration_since(Instant::now()) {
                    std::thread::sleep(wait);
                }
                let (angles, touches, stage_m) = synthetic(t_s, n);
                server.publish(&StreamMessage::Samples {
                    seq,
                    t_ns: (t_s * 1e9) as u64,
                    segments: angles
                        .iter()
                        .zip(&touches)
                        .enumerate()
                        .map(|(k, (&a, &t))| SegmentSample {
                            address: (k % 256) as u8,
                            angle_rad: Some(a),
                            contact: Some(t),
                            touch_bits: Some(if t { 0x0F } else { 0 }),
                            counter: None,
                            error: None,
                            stale: false,
                        })
                        .collect(),
                    stage_position_m: Some(stage_m),
                    base_angle_deg: Some(0.0),
                });
                seq += 1;
            }
            server.shutdown();
        })
    };
    let (width, height) = (args.width, args.height);
    let bench = Bench {
        app,
        starts: Vec::with_capacity(args.warmup + args.frames + 2),
        ui_ms: Vec::with_capacity(args.warmup + args.frames + 2),
        cpu_ms: Vec::with_capacity(args.warmup + args.frames + 2),
        warmup: args.warmup,
        frames: args.frames,
        json: args.json,
        segments: n,
        history_s: args.history_s,
        stop: Arc::clone(&stop),
        result: None,
    };
    let force_feathering = args.force_feathering;
    let options = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_title("antenna-monitor frame bench")
            .with_inner_size([width, height]),
        renderer: eframe::Renderer::Glow,
        glow_options: eframe::egui_glow::GlowConfiguration {
            vsync: false,
            ..Default::default()
        },
        ..Default::default()
    };
    let outcome = eframe::run_native(
        "antenna-monitor-frame-bench",
        options,
        Box::new(move |cc| {
            // As antenna-monitor's main does.
            if !force_feathering && cc.gl.as_deref().is_some_and(is_software_gl) {
                tune_for_software_gl(&cc.egui_ctx);
            }
            Ok(Box::new(bench))
        }),
    );
    stop.store(true, Ordering::Relaxed);
    let _ = publisher.join();
    outcome.map_err(|e| anyhow::anyhow!("the window failed: {e}"))
}
