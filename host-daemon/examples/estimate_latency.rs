//! The live wall estimate's latency and what it costs the polling: antennad on the simulated
//! rig at 1 kHz running the default trial, recording it, with a TCP stream client and a
//! Foxglove WebSocket client (subscribed to `/antenna/estimate`) on loopback. A measurement,
//! not a test:
//!
//! ```text
//! cargo run --release -p host-daemon --example estimate_latency [-- SECONDS [BUSY...]]
//! ```
//!
//! Latency: from the newest poll's `t_ns` to the estimate line's arrival at each client, read
//! on the daemon's clock (`DaemonHandle::clock`). Poll jitter: |period - 1 ms| from the polls'
//! time stamps (the hub's event tap). Three interleaved pairs of runs, with the estimate
//! (`contact-line`, the default) and without (`estimator = "none"`), per background load
//! (`BUSY` busy-looping processes; default `0 2`). It prints one Markdown table row per run.

use anyhow::{Context, Result, anyhow};
use host_daemon::service::acquisition::AcquisitionEvent;
use host_daemon::service::config::{Config, EstimatorName};
use host_daemon::service::daemon::{Daemon, DaemonOptions, EventTap};
use serde_json::{Value, json};
use std::io::{BufRead, BufReader};
use std::net::{SocketAddr, TcpStream};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;
use tungstenite::client::IntoClientRequest;
use tungstenite::http::HeaderValue;
use tungstenite::{Message, WebSocket};

mod support;
use support::{Load, percentile};

/// Latencies, microseconds, of the estimates a client received.
type Latencies = Arc<Mutex<Vec<f64>>>;

/// Reads the TCP stream until it closes, keeping each estimate's latency.
fn tcp_client(
    addr: SocketAddr,
    clock: host_daemon::service::clock::TrialClock,
    out: Latencies,
) -> Result<JoinHandle<()>> {
    let stream = TcpStream::connect(addr).context("connecting to the TCP stream")?;
    Ok(std::thread::spawn(move || {
        let mut reader = BufReader::new(stream);
        let mut line = String::new();
        while reader.read_line(&mut line).is_ok_and(|n| n > 0) {
            let arrived_ns = clock.elapsed_ns();
            if line.starts_with(r#"{"type":"estimate""#)
                && let Ok(v) = serde_json::from_str::<Value>(&line)
                && let Some(t_ns) = v["t_ns"].as_u64()
                && let Ok(mut out) = out.lock()
            {
                out.push(arrived_ns.saturating_sub(t_ns) as f64 / 1e3);
            }
            line.clear();
        }
    }))
}

/// A Foxglove client subscribed to `/antenna/estimate`, keeping each estimate's latency
/// until the server closes.
fn websocket_client(
    addr: SocketAddr,
    clock: host_daemon::service::clock::TrialClock,
    out: Latencies,
) -> Result<JoinHandle<()>> {
    let stream = TcpStream::connect(addr).context("connecting to Foxglove")?;
    let mut request = format!("ws://{addr}").into_client_request()?;
    request.headers_mut().insert(
        "Sec-WebSocket-Protocol",
        HeaderValue::from_static("foxglove.sdk.v1"),
    );
    let (mut socket, _) =
        tungstenite::client(request, stream).map_err(|e| anyhow!("WebSocket handshake: {e}"))?;
    let channel = estimate_channel(&mut socket)?;
    socket.send(Message::text(
        json!({"op": "subscribe", "subscriptions": [{"id": 1, "channelId": channel}]}).to_string(),
    ))?;
    Ok(std::thread::spawn(move || {
        while let Ok(message) = socket.read() {
            let arrived_ns = clock.elapsed_ns();
            if let Message::Binary(bytes) = message
                && bytes.len() > 13
                && bytes[0] == 0x01
                && let Ok(v) = serde_json::from_slice::<Value>(&bytes[13..])
                && let Some(t_ns) = v["t_ns"].as_u64()
                && let Ok(mut out) = out.lock()
            {
                out.push(arrived_ns.saturating_sub(t_ns) as f64 / 1e3);
            }
        }
    }))
}

/// The id of the advertised `/antenna/estimate` channel.
fn estimate_channel(socket: &mut WebSocket<TcpStream>) -> Result<u64> {
    for _ in 0..100 {
        if let Message::Text(text) = socket.read()? {
            let op: Value = serde_json::from_str(text.as_str())?;
            if op["op"] == "advertise"
                && let Some(channel) = op["channels"]
                    .as_array()
                    .into_iter()
                    .flatten()
                    .find(|c| c["topic"] == "/antenna/estimate")
            {
                return channel["id"].as_u64().context("a channel id");
            }
        }
    }
    Err(anyhow!("no /antenna/estimate channel advertised"))
}

/// One run: the poll jitter's p99 and the TCP and WebSocket latencies, microseconds.
struct Run {
    polls: u64,
    jitter_p99_us: f64,
    tcp: Vec<f64>,
    websocket: Vec<f64>,
}

fn run(seconds: f64, estimate: bool, data_dir: &std::path::Path) -> Result<Run> {
    let mut config = Config {
        data_dir: data_dir.to_owned(),
        ..Config::default()
    };
    config.server.listen = "127.0.0.1:0".to_owned();
    config.foxglove.listen = "127.0.0.1:0".to_owned();
    config.foxglove.enabled = Some(true);
    if !estimate {
        config.estimate.estimator = EstimatorName::None;
    }
    let stamps: Arc<Mutex<Vec<u64>>> = Arc::new(Mutex::new(Vec::new()));
    let tap = {
        let stamps = Arc::clone(&stamps);
        EventTap::new(move |event| {
            if let AcquisitionEvent::Poll(p) = event
                && let Ok(mut stamps) = stamps.lock()
            {
                stamps.push(p.t_ns);
            }
        })
    };
    let options = DaemonOptions {
        first_trial: Some(None),
        first_trial_duration: Some(Duration::from_secs_f64(seconds)),
        exit_after_trial: true,
        record: true,
        foxglove: true,
        on_event: Some(tap),
        ..DaemonOptions::default()
    };
    let daemon = Daemon::start(config, options)?;
    let clock = daemon.clock();
    let (tcp, websocket): (Latencies, Latencies) = Default::default();
    let tcp_reader = tcp_client(
        daemon.local_addr().context("no TCP server")?,
        clock,
        Arc::clone(&tcp),
    )?;
    let ws_reader = match daemon.foxglove_addr() {
        Some(addr) => Some(websocket_client(addr, clock, Arc::clone(&websocket))?),
        None => None,
    };
    let summary = daemon.wait()?;
    let _ = tcp_reader.join();
    if let Some(reader) = ws_reader {
        let _ = reader.join();
    }
    let stamps = std::mem::take(&mut *stamps.lock().map_err(|_| anyhow!("tap panicked"))?);
    let mut jitter: Vec<f64> = stamps
        .windows(2)
        .map(|w| ((w[1] - w[0]) as f64 / 1e3 - 1000.0).abs())
        .collect();
    jitter.sort_by(f64::total_cmp);
    let sorted = |v: &Latencies| -> Result<Vec<f64>> {
        let mut v = std::mem::take(&mut *v.lock().map_err(|_| anyhow!("a client panicked"))?);
        v.sort_by(f64::total_cmp);
        Ok(v)
    };
    Ok(Run {
        polls: summary.polls,
        jitter_p99_us: percentile(&jitter, 0.99),
        tcp: sorted(&tcp)?,
        websocket: sorted(&websocket)?,
    })
}

fn latency_cell(v: &[f64]) -> String {
    if v.is_empty() {
        return "-".to_owned();
    }
    format!(
        "{} / {:.0} / {:.0} / {:.0}",
        v.len(),
        percentile(v, 0.5),
        percentile(v, 0.99),
        v.last().copied().unwrap_or(f64::NAN)
    )
}

fn main() -> Result<()> {
    let mut args = std::env::args().skip(1);
    let seconds: f64 = args
        .next()
        .map(|s| s.parse())
        .transpose()
        .context("SECONDS")?
        .unwrap_or(10.0);
    let loads: Vec<usize> = args
        .map(|s| s.parse().context("BUSY: a number of busy processes"))
        .collect::<Result<_>>()?;
    let loads = if loads.is_empty() { vec![0, 2] } else { loads };
    let data_dir = std::env::temp_dir().join(format!("estimate-latency-{}", std::process::id()));
    println!(
        "antennad on the simulated rig at 1 kHz, the default trial recorded, {seconds} s per \
         run, {} cores",
        std::thread::available_parallelism().map_or(0, |n| n.get())
    );
    println!(
        "| busy | estimate | polls | poll jitter p99 (us) | TCP: estimates / p50 / p99 / max (us) | \
         WebSocket: estimates / p50 / p99 / max (us) |"
    );
    println!("|---|---|---|---|---|---|");
    for &busy in &loads {
        let _load = Load::start(busy)?;
        std::thread::sleep(Duration::from_secs(if busy > 0 { 3 } else { 0 }));
        for _round in 0..3 {
            for estimate in [true, false] {
                let r = run(seconds, estimate, &data_dir)?;
                println!(
                    "| {busy} | {} | {} | {:.1} | {} | {} |",
                    if estimate { "contact-line" } else { "none" },
                    r.polls,
                    r.jitter_p99_us,
                    latency_cell(&r.tcp),
                    latency_cell(&r.websocket),
                );
                let _ = std::fs::remove_dir_all(&data_dir);
            }
        }
    }
    Ok(())
}
