//! What the Foxglove server costs antennad (issue #48): the default trial on the simulated
//! rig at 1 kHz, `SCHED_FIFO` 50 when permitted, run without the server, with the server and
//! no client, with one client subscribed to every channel but the samples (the 3D ones at
//! 50 Hz, the status, the estimates) and with one subscribed to every channel (every poll's
//! samples too), interleaved, `RUNS` times each. A measurement, not a test:
//!
//! ```text
//! cargo run --release -p host-daemon --example foxglove_cost [-- SECONDS RUNS [BUSY]]
//! ```
//!
//! The client is this program again (`--client ADDR`), in its own process, so its CPU is not
//! the daemon's; it reads everything and counts what it got. Each row gives the poll's period
//! jitter (|period - 1 ms|, from the event tap's poll time stamps), the daemon process's CPU
//! share over the run and its RSS after it; `BUSY` busy-looping processes run beside it
//! (default 0).

use anyhow::{Context, Result, bail};
use host_daemon::service::acquisition::AcquisitionEvent;
use host_daemon::service::config::Config;
use host_daemon::service::daemon::{Daemon, DaemonOptions, EventTap};
use std::net::{SocketAddr, TcpStream};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tungstenite::Message;
use tungstenite::client::IntoClientRequest;
use tungstenite::http::HeaderValue;

mod support;
use support::{Load, cpu_s, percentile, status_kb};

/// The client: connects as Foxglove does, subscribes to every channel (`only_3d`: all but
/// the samples, every poll's) and reads until the server goes; prints the messages and bytes
/// it got.
fn client(addr: &str, only_3d: bool) -> Result<()> {
    let addr: SocketAddr = addr.parse().context("ADDR")?;
    let stream = TcpStream::connect(addr)?;
    let mut request = format!("ws://{addr}").into_client_request()?;
    request.headers_mut().insert(
        "Sec-WebSocket-Protocol",
        HeaderValue::from_static("foxglove.sdk.v1"),
    );
    let (mut socket, _) = tungstenite::client(request, stream)?;
    let (mut messages, mut bytes, mut subscribed) = (0u64, 0u64, 0usize);
    loop {
        match socket.read() {
            Ok(Message::Text(text)) => {
                let op: serde_json::Value = serde_json::from_str(text.as_str())?;
                if op["op"] == "advertise" {
                    let subscriptions: Vec<serde_json::Value> = op["channels"]
                        .as_array()
                        .context("channels")?
                        .iter()
                        .filter(|c| !(only_3d && c["topic"] == "/antenna/samples"))
                        .map(|c| {
                            subscribed += 1;
                            serde_json::json!({ "id": subscribed, "channelId": c["id"] })
                        })
                        .collect();
                    socket.send(Message::text(
                        serde_json::json!({ "op": "subscribe", "subscriptions": subscriptions })
                            .to_string(),
                    ))?;
                }
            }
            Ok(Message::Binary(payload)) => {
                messages += 1;
                bytes += payload.len() as u64;
            }
            Ok(_) => {}
            Err(_) => break,
        }
    }
    eprintln!("client: {subscribed} channels, {messages} messages, {bytes} bytes");
    Ok(())
}

/// One run: the default trial for `seconds`; returns the table row's figures.
fn run(seconds: f64, foxglove: bool, client: Option<&str>) -> Result<String> {
    let mut config = Config::default();
    config.server.listen = "127.0.0.1:0".to_owned();
    config.foxglove.listen = "127.0.0.1:0".to_owned();
    config.foxglove.enabled = Some(foxglove);
    let stamps: Arc<Mutex<Vec<u64>>> =
        Arc::new(Mutex::new(Vec::with_capacity((seconds * 1200.0) as usize)));
    let on_event = {
        let stamps = Arc::clone(&stamps);
        EventTap::new(move |event| {
            if let (AcquisitionEvent::Poll(p), Ok(mut stamps)) = (event, stamps.lock()) {
                stamps.push(p.t_ns);
            }
        })
    };
    let cpu_before = cpu_s()?;
    let wall = Instant::now();
    let daemon = Daemon::start(
        config.clone(),
        DaemonOptions {
            serve: true,
            foxglove: true,
            ..DaemonOptions::tapped_trial(Duration::from_secs_f64(seconds), on_event)
        },
    )?;
    let mut child = match (client, daemon.foxglove_addr()) {
        (Some(channels), Some(addr)) => Some(
            std::process::Command::new(std::env::current_exe()?)
                .args(["--client", &addr.to_string(), channels])
                .spawn()
                .context("starting the client")?,
        ),
        (Some(_), None) => bail!("no Foxglove server"),
        _ => None,
    };
    let summary = daemon.wait()?;
    let cpu = (cpu_s()? - cpu_before) / wall.elapsed().as_secs_f64();
    if let Some(child) = &mut child {
        child.wait()?;
    }
    let stamps = std::mem::take(&mut *stamps.lock().map_err(|_| anyhow::anyhow!("tap"))?);
    let period_us = 1e6 / config.bus.poll_hz;
    let mut jitter: Vec<f64> = stamps
        .windows(2)
        .map(|w| ((w[1] - w[0]) as f64 / 1e3 - period_us).abs())
        .collect();
    jitter.sort_by(f64::total_cmp);
    Ok(format!(
        "{} | {} | {:.1} / {:.1} / {:.0} | {:.1} | {:.1} |",
        summary.polls,
        summary.skipped,
        percentile(&jitter, 0.5),
        percentile(&jitter, 0.99),
        jitter.last().copied().unwrap_or(0.0),
        100.0 * cpu,
        status_kb("VmRSS:")? as f64 / 1024.0
    ))
}

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().map(String::as_str) == Some("--client") {
        let only_3d = args.get(2).map(String::as_str) == Some("3d");
        return client(args.get(1).context("--client ADDR")?, only_3d);
    }
    let seconds: f64 = args
        .first()
        .map_or(Ok(10.0), |s| s.parse())
        .context("SECONDS")?;
    let runs: usize = args.get(1).map_or(Ok(3), |s| s.parse()).context("RUNS")?;
    let busy: usize = args.get(2).map_or(Ok(0), |s| s.parse()).context("BUSY")?;
    let _load = Load::start(busy)?;
    println!(
        "default trial at 1 kHz on the simulated rig, {seconds} s per run, {busy} busy \
         processes, {} cores",
        std::thread::available_parallelism().map_or(0, |n| n.get())
    );
    println!(
        "| run | Foxglove | polls | skipped | jitter p50 / p99 / max (us) | CPU (% of a core) | \
         RSS (MB) |"
    );
    println!("|---|---|---|---|---|---|---|");
    for k in 1..=runs {
        for (name, foxglove, client) in [
            ("no server", false, None),
            ("server, no client", true, None),
            ("server, one client (all but the samples)", true, Some("3d")),
            ("server, one client (every channel)", true, Some("all")),
        ] {
            println!("| {k} | {name} | {}", run(seconds, foxglove, client)?);
        }
    }
    println!(
        "peak RSS (VmHWM): {:.1} MB",
        status_kb("VmHWM:")? as f64 / 1024.0
    );
    Ok(())
}
