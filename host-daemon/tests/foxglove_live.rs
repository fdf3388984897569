//! antennad's Foxglove WebSocket server (issue #48), seen as Foxglove's app sees it: a client
//! of subprotocol `foxglove.sdk.v1` reads `serverInfo` (no capability: view-only) and the
//! channels' `advertise`, subscribes, and decodes the binary message frames (opcode 0x01,
//! subscription id u32 LE, log time u64 LE, payload). The transforms match the chain the
//! samples of the same poll give; a client cannot publish; a port in use stops antennad (or
//! with `required = false` leaves it without Foxglove); a client that never reads stalls
//! neither polling, nor recording, nor the TCP stream.
#![cfg(feature = "foxglove")]
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod net_support;

use antenna_data::stream::StreamMessage;
use foxglove::Decode;
use foxglove::messages::{FrameTransforms, SceneUpdate};
use host_daemon::service::config::Config;
use host_daemon::service::daemon::{Daemon, DaemonHandle, DaemonOptions};
use net_support::Client;
use serde_json::{Value, json};
use std::collections::{BTreeMap, HashMap};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::path::PathBuf;
use std::time::Duration;
use tungstenite::client::IntoClientRequest;
use tungstenite::http::HeaderValue;
use tungstenite::{Message, WebSocket};

/// How long any single read may wait before the test fails.
const READ_TIMEOUT: Duration = Duration::from_secs(20);

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("antennad-fox-{name}-{}", std::process::id()));
    std::fs::remove_dir_all(&dir).ok();
    dir
}

/// The simulated rig with both servers on free loopback ports.
fn config(name: &str) -> Config {
    let mut config = Config::default();
    config.server.listen = "127.0.0.1:0".to_owned();
    config.foxglove.listen = "127.0.0.1:0".to_owned();
    config.data_dir = temp_dir(name);
    config
}

fn options() -> DaemonOptions {
    DaemonOptions {
        foxglove: true,
        record: false,
        ..DaemonOptions::default()
    }
}

/// A Foxglove client: the WebSocket, `serverInfo`, and the advertised channels by topic.
struct FoxgloveClient {
    socket: WebSocket<TcpStream>,
    server_info: Value,
    channels: HashMap<String, Value>,
    /// The `status` messages received.
    statuses: Vec<Value>,
}

/// One message frame: subscription, log time, payload.
struct MessageData {
    subscription: u32,
    log_time_ns: u64,
    payload: Vec<u8>,
}

impl FoxgloveClient {
    fn connect(addr: SocketAddr) -> Self {
        let stream = TcpStream::connect(addr).unwrap();
        stream.set_read_timeout(Some(READ_TIMEOUT)).unwrap();
        let mut request = format!("ws://{addr}").into_client_request().unwrap();
        request.headers_mut().insert(
            "Sec-WebSocket-Protocol",
            HeaderValue::from_static("foxglove.sdk.v1"),
        );
        let (socket, response) = tungstenite::client(request, stream).unwrap();
        assert_eq!(
            response
                .headers()
                .get("Sec-WebSocket-Protocol")
                .and_then(|v| v.to_str().ok()),
            Some("foxglove.sdk.v1")
        );
        let mut client = Self {
            socket,
            server_info: Value::Null,
            channels: HashMap::new(),
            statuses: Vec::new(),
        };
        // serverInfo first, then the channels (every one of antennad's five).
        while client.server_info.is_null() || client.channels.len() < 5 {
            match client.next_text() {
                Some(op) => client.take_control(op),
                None => panic!("a message frame before the channels were advertised"),
            }
        }
        client
    }

    fn take_control(&mut self, op: Value) {
        match op["op"].as_str() {
            Some("serverInfo") => self.server_info = op,
            Some("status") => self.statuses.push(op),
            Some("advertise") => {
                for channel in op["channels"].as_array().unwrap() {
                    let topic = channel["topic"].as_str().unwrap().to_owned();
                    self.channels.insert(topic, channel.clone());
                }
            }
            _ => {}
        }
    }

    /// The next text frame as JSON; `None` if a binary frame came first (it is dropped).
    fn next_text(&mut self) -> Option<Value> {
        match self.socket.read().unwrap() {
            Message::Text(text) => Some(serde_json::from_str(text.as_str()).unwrap()),
            _ => None,
        }
    }

    /// The next message frame, the control messages before it taken in.
    fn next_message(&mut self) -> MessageData {
        loop {
            match self.socket.read().unwrap() {
                Message::Binary(bytes) => {
                    assert!(bytes.len() >= 13, "short frame: {} bytes", bytes.len());
                    if bytes[0] != 0x01 {
                        continue;
                    }
                    return MessageData {
                        subscription: u32::from_le_bytes(bytes[1..5].try_into().unwrap()),
                        log_time_ns: u64::from_le_bytes(bytes[5..13].try_into().unwrap()),
                        payload: bytes[13..].to_vec(),
                    };
                }
                Message::Text(text) => {
                    let op: Value = serde_json::from_str(text.as_str()).unwrap();
                    self.take_control(op);
                }
                _ => {}
            }
        }
    }

    fn channel_id(&self, topic: &str) -> u64 {
        self.channels[topic]["id"].as_u64().unwrap()
    }

    /// Subscribes to `topics`, subscription ids 1, 2, ... in that order.
    fn subscribe(&mut self, topics: &[&str]) {
        let subscriptions: Vec<Value> = topics
            .iter()
            .enumerate()
            .map(|(k, topic)| json!({ "id": k + 1, "channelId": self.channel_id(topic) }))
            .collect();
        self.send(&json!({ "op": "subscribe", "subscriptions": subscriptions }));
    }

    fn send(&mut self, op: &Value) {
        self.socket.send(Message::text(op.to_string())).unwrap();
    }
}

/// A pose in the plane: position and heading.
#[derive(Debug, Clone, Copy)]
struct Pose2 {
    x: f64,
    y: f64,
    angle: f64,
}

impl Pose2 {
    fn then(self, dx: f64, dy: f64, turn: f64) -> Self {
        let (sin, cos) = self.angle.sin_cos();
        Self {
            x: self.x + cos * dx - sin * dy,
            y: self.y + sin * dx + cos * dy,
            angle: self.angle + turn,
        }
    }
}

/// Every frame of `transforms` in `world`, chained from the decoded transforms alone.
fn world_poses(transforms: &FrameTransforms) -> BTreeMap<String, Pose2> {
    let mut poses = BTreeMap::from([(
        "world".to_owned(),
        Pose2 {
            x: 0.0,
            y: 0.0,
            angle: 0.0,
        },
    )]);
    // Parents come before their children, but do not rely on it.
    for _ in 0..transforms.transforms.len() {
        for t in &transforms.transforms {
            let Some(parent) = poses.get(&t.parent_frame_id).copied() else {
                continue;
            };
            let v = t.translation.as_ref().unwrap();
            let q = t.rotation.as_ref().unwrap();
            assert!(v.z == 0.0 && q.x == 0.0 && q.y == 0.0, "{t:?}");
            let turn = 2.0 * q.z.atan2(q.w);
            poses.insert(t.child_frame_id.clone(), parent.then(v.x, v.y, turn));
        }
    }
    poses
}

/// Every link frame in `world` as the configuration's scene and a poll's samples place it:
/// the base pivot at `[base] position_m` plus the stage along the direction of motion, the
/// base link at the scene's base angle plus the servo, each link turned by its joint angle.
fn expected_poses(config: &Config, samples: &StreamMessage) -> Option<Vec<Pose2>> {
    let StreamMessage::Samples {
        segments,
        stage_position_m,
        base_angle_deg,
        ..
    } = samples
    else {
        panic!("not samples: {samples:?}");
    };
    let scene = &config.sim.rig.scene;
    let v = scene.motion.velocity_m_per_s;
    let travel = if v.x == 0.0 && v.y == 0.0 {
        0.0
    } else {
        v.y.atan2(v.x)
    };
    let stage_m = (*stage_position_m)?;
    let carriage = Pose2 {
        x: scene.base_position_m.x + stage_m * travel.cos(),
        y: scene.base_position_m.y + stage_m * travel.sin(),
        angle: travel,
    };
    // The base link's angle is the scene's base angle plus the servo, in the scene frame
    // (as the simulated rig places it), whatever the direction of travel.
    let mut link = Pose2 {
        angle: scene.chain.base_angle_rad() + (*base_angle_deg)?.to_radians(),
        ..carriage
    };
    let lengths = scene.chain.link_lengths_m();
    let mut poses = vec![link];
    for (k, segment) in segments.iter().enumerate() {
        link = link.then(lengths[k], 0.0, segment.angle_rad?);
        poses.push(link);
    }
    Some(poses)
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() < 1e-9
}

fn angle_close(a: f64, b: f64) -> bool {
    let d = (a - b).rem_euclid(std::f64::consts::TAU);
    d.min(std::f64::consts::TAU - d) < 1e-9
}

#[test]
fn a_client_sees_the_polled_chain_view_only() {
    let config = config("chain");
    let daemon = Daemon::start(config.clone(), options()).unwrap();
    let addr = daemon.foxglove_addr().expect("a Foxglove server");
    assert!(addr.ip().is_loopback() && addr.port() != 0, "{addr}");
    assert!(
        daemon
            .log_lines()
            .iter()
            .any(|l| l.contains(&format!("ws://{addr}"))),
        "{:#?}",
        daemon.log_lines()
    );
    let mut client = FoxgloveClient::connect(addr);

    // View-only: no capability, no service.
    let info = &client.server_info;
    assert_eq!(info["name"], "antennad", "{info}");
    assert_eq!(info["capabilities"], json!([]), "{info}");
    // The channels, with the standard schemas and the JSON ones.
    let schema = |topic: &str| {
        let c = &client.channels[topic];
        (
            c["encoding"].as_str().unwrap().to_owned(),
            c["schemaName"].as_str().unwrap().to_owned(),
        )
    };
    assert_eq!(
        schema("/antenna/transforms"),
        ("protobuf".to_owned(), "foxglove.FrameTransforms".to_owned())
    );
    assert_eq!(
        schema("/antenna/scene"),
        ("protobuf".to_owned(), "foxglove.SceneUpdate".to_owned())
    );
    for (topic, name) in [
        ("/antenna/samples", "antenna.stream.Samples"),
        ("/antenna/status", "antenna.stream.Status"),
        ("/antenna/estimate", "antenna.stream.Estimate"),
    ] {
        assert_eq!(schema(topic), ("json".to_owned(), name.to_owned()));
        let c = &client.channels[topic];
        assert_eq!(c["schemaEncoding"], "jsonschema");
        let described: Value = serde_json::from_str(c["schema"].as_str().unwrap()).unwrap();
        assert_eq!(described["title"], name);
    }

    // The layout in the repository shows what the server sends.
    check_layout(&client);

    // A client that publishes is refused (the server has no clientPublish).
    client.send(&json!({
        "op": "advertise",
        "channels": [{ "id": 1, "topic": "/cmd", "encoding": "json", "schemaName": "cmd" }],
    }));
    client.subscribe(&[
        "/antenna/transforms",
        "/antenna/samples",
        "/antenna/estimate",
        "/antenna/scene",
    ]);
    let mut scenes: Vec<SceneUpdate> = Vec::new();
    let mut samples: BTreeMap<u64, StreamMessage> = BTreeMap::new();
    let mut transforms: Vec<(u64, FrameTransforms)> = Vec::new();
    let mut estimates = Vec::new();
    let mut compared = 0;
    let mut messages = 0;
    let refusal =
        |client: &FoxgloveClient| client.statuses.iter().find(|s| s["level"] == 2).cloned();
    let estimates_matched = |estimates: &[(u64, StreamMessage)],
                             samples: &BTreeMap<u64, StreamMessage>| {
        estimates
            .iter()
            .filter(|(log_time_ns, _)| samples.contains_key(log_time_ns))
            .count()
    };
    while compared < 10
        || refusal(&client).is_none()
        || estimates_matched(&estimates, &samples) < 3
        || scenes.is_empty()
    {
        messages += 1;
        assert!(
            messages < 200_000,
            "{compared} transforms compared, statuses {:?}",
            client.statuses
        );
        let m = client.next_message();
        match m.subscription {
            1 => {
                let t = FrameTransforms::decode(m.payload.as_slice()).unwrap();
                transforms.push((m.log_time_ns, t));
            }
            2 => {
                let message: StreamMessage = serde_json::from_slice(&m.payload).unwrap();
                assert!(
                    matches!(message, StreamMessage::Samples { .. }),
                    "{message:?}"
                );
                samples.insert(m.log_time_ns, message);
            }
            3 => {
                let message: StreamMessage = serde_json::from_slice(&m.payload).unwrap();
                estimates.push((m.log_time_ns, message));
            }
            4 => scenes.push(SceneUpdate::decode(m.payload.as_slice()).unwrap()),
            other => panic!("no subscription {other}"),
        }
        // Compare every transforms message whose poll's samples came.
        transforms.retain(|(log_time_ns, t)| {
            let Some(poll) = samples.get(log_time_ns) else {
                return true;
            };
            let Some(expected) = expected_poses(&config, poll) else {
                return false; // a reading missing (the stage before its first sample)
            };
            let seen = world_poses(t);
            assert_eq!(seen.len(), expected.len() + 2, "{t:?}");
            for (k, pose) in expected.iter().enumerate() {
                let got = seen[&format!("link_{k}")];
                assert!(
                    close(got.x, pose.x)
                        && close(got.y, pose.y)
                        && angle_close(got.angle, pose.angle),
                    "link_{k}: {got:?} != {pose:?}"
                );
            }
            // Stamped with the poll's time, as its log time.
            for f in &t.transforms {
                let stamp = f.timestamp.unwrap();
                assert_eq!(
                    u64::from(stamp.sec()) * 1_000_000_000 + u64::from(stamp.nsec()),
                    *log_time_ns
                );
            }
            compared += 1;
            false
        });
    }
    let refused = refusal(&client).unwrap();
    assert!(
        refused["message"]
            .as_str()
            .unwrap()
            .contains("clientPublish"),
        "{refused}"
    );
    // Samples and transforms share their polls' times: one per poll.
    let times: Vec<u64> = samples.keys().copied().collect();
    assert!(times.windows(2).all(|w| w[0] < w[1]));
    // Every estimate is the stream's, stamped with the time of the poll it used.
    for (log_time_ns, estimate) in &estimates {
        let StreamMessage::Estimate(estimate) = estimate else {
            panic!("not an estimate: {estimate:?}");
        };
        if let Some(StreamMessage::Samples { seq, .. }) = samples.get(log_time_ns) {
            assert_eq!(*seq, estimate.seq);
        }
    }
    // The first scene is whole: every link in its own frame (locked to it), the simulated
    // rig's wall in `world`.
    let first = &scenes[0];
    let links = config.sim.rig.scene.chain.link_lengths_m().len();
    for k in 0..links {
        let link = first
            .entities
            .iter()
            .find(|e| e.id == format!("link_{k}"))
            .unwrap_or_else(|| panic!("no link_{k} in {first:?}"));
        assert_eq!(link.frame_id, format!("link_{k}"));
        assert!(link.frame_locked);
    }
    assert!(
        first
            .entities
            .iter()
            .any(|e| e.id == "wall_0" && e.frame_id == "world"),
        "{first:?}"
    );
    daemon.shutdown().unwrap();
}

/// Every topic of `docs/foxglove/antenna-layout.json` is one the server advertises, and every
/// plotted field is in its channel's JSON schema (`segments[k].angle_rad`: `segments`, then
/// the item's `angle_rad`).
fn check_layout(client: &FoxgloveClient) {
    let text = include_str!("../../docs/foxglove/antenna-layout.json");
    let layout: Value = serde_json::from_str(text).unwrap();
    let mut paths = Vec::new();
    for (id, panel) in layout["configById"].as_object().unwrap() {
        if let Some(topics) = panel["topics"].as_object() {
            paths.extend(topics.keys().cloned());
        }
        if let Some(series) = panel["paths"].as_array() {
            paths.extend(
                series
                    .iter()
                    .map(|p| p["value"].as_str().unwrap().to_owned()),
            );
        }
        if let Some(topic) = panel["topicPath"].as_str() {
            paths.push(topic.to_owned());
        }
        assert!(
            id.starts_with("3D!") || id.starts_with("Plot!") || id.starts_with("RawMessages!"),
            "{id}"
        );
    }
    assert!(paths.iter().any(|p| p.contains("angle_rad")), "{paths:?}");
    assert!(
        paths.iter().any(|p| p.starts_with("/antenna/estimate.")),
        "{paths:?}"
    );
    assert!(paths.iter().any(|p| p == "/antenna/scene"), "{paths:?}");
    for path in &paths {
        let (topic, fields) = path.split_once('.').unwrap_or((path.as_str(), ""));
        let channel = client
            .channels
            .get(topic)
            .unwrap_or_else(|| panic!("{path}: {topic} is not advertised"));
        if fields.is_empty() {
            continue;
        }
        let mut schema: Value = serde_json::from_str(channel["schema"].as_str().unwrap()).unwrap();
        for field in fields.split('.') {
            let (name, indexed) = match field.split_once('[') {
                Some((name, _)) => (name, true),
                None => (field, false),
            };
            schema = schema["properties"][name].clone();
            assert!(!schema.is_null(), "{path}: no {name}");
            if indexed {
                schema = schema["items"].clone();
            }
        }
    }
}

#[test]
fn a_port_in_use_names_foxglove_listen() {
    let taken = TcpListener::bind("127.0.0.1:0").unwrap();
    let mut config = config("busy");
    config.foxglove.listen = taken.local_addr().unwrap().to_string();
    let error = Daemon::start(config.clone(), options()).unwrap_err();
    let text = format!("{error:#}");
    assert!(text.contains("`foxglove.listen`"), "{text}");
    assert!(text.contains(&config.foxglove.listen), "{text}");

    // Not required: a warning, and antennad runs without Foxglove.
    config.foxglove.required = false;
    let daemon = Daemon::start(config, options()).unwrap();
    assert_eq!(daemon.foxglove_addr(), None);
    assert!(daemon.local_addr().is_some());
    assert!(
        daemon
            .log_lines()
            .iter()
            .any(|l| l.contains("`foxglove.listen`") && l.contains("without Foxglove")),
        "{:#?}",
        daemon.log_lines()
    );
    daemon.shutdown().unwrap();
}

#[test]
fn foxglove_runs_only_when_asked_and_enabled() {
    // Hardware configured: off unless turned on (here the bus stays simulated).
    let mut config = config("off");
    config.foxglove.enabled = Some(false);
    let daemon = Daemon::start(config.clone(), options()).unwrap();
    assert_eq!(daemon.foxglove_addr(), None);
    daemon.shutdown().unwrap();
    // An in-process daemon without `foxglove` in its options has none either.
    config.foxglove.enabled = Some(true);
    let daemon = Daemon::start(config.clone(), DaemonOptions::default()).unwrap();
    assert_eq!(daemon.foxglove_addr(), None);
    daemon.shutdown().unwrap();
    // Nor without a server at all.
    let daemon = Daemon::start(
        config,
        DaemonOptions {
            serve: false,
            ..options()
        },
    )
    .unwrap();
    assert_eq!(daemon.foxglove_addr(), None);
    daemon.shutdown().unwrap();
}

/// Reads the TCP stream until `n` samples have come; the first and last `seq` (a `seq` counts
/// poll deadlines: one the polling thread skipped on a busy machine is a gap; a client that
/// lags is told so with `lagged`, which is allowed here: the point is that samples keep coming).
fn follow_samples(client: &mut Client, n: u64) -> (u64, u64) {
    let (mut first, mut last, mut count) = (None, 0, 0);
    while count < n {
        if let StreamMessage::Samples { seq, .. } = client.next_message() {
            assert!(first.is_none() || seq > last, "{seq} after {last}");
            first.get_or_insert(seq);
            last = seq;
            count += 1;
        }
    }
    (first.unwrap_or(0), last)
}

fn start_recording(config: Config) -> DaemonHandle {
    Daemon::start(
        config,
        DaemonOptions {
            first_trial: Some(None),
            first_trial_duration: Some(Duration::from_secs(600)),
            record: true,
            ..options()
        },
    )
    .unwrap()
}

#[test]
fn a_client_that_never_reads_stalls_nothing() {
    let config = config("stalled");
    let data_dir = config.data_dir.clone();
    let daemon = start_recording(config);
    let mut tcp = Client::connect(daemon.local_addr().unwrap());
    assert!(matches!(tcp.next_message(), StreamMessage::Hello { .. }));

    // Subscribes to everything, then never reads again.
    let mut stalled = FoxgloveClient::connect(daemon.foxglove_addr().unwrap());
    let topics: Vec<String> = stalled.channels.keys().cloned().collect();
    let topics: Vec<&str> = topics.iter().map(String::as_str).collect();
    stalled.subscribe(&topics);

    // Polling and the TCP stream go on: 5,000 polls (5 s at 1 kHz, over 5 MB offered to the
    // stalled client, more than loopback buffers hold).
    let (first, last) = follow_samples(&mut tcp, 5000);
    assert!(last - first >= 4999, "{first}..={last}");
    // A second Foxglove client still gets its messages.
    let mut reader = FoxgloveClient::connect(daemon.foxglove_addr().unwrap());
    reader.subscribe(&["/antenna/samples"]);
    let m = reader.next_message();
    let StreamMessage::Samples { seq, .. } = serde_json::from_slice(&m.payload).unwrap() else {
        panic!("not samples");
    };
    assert!(seq > last, "{seq} <= {last}");
    follow_samples(&mut tcp, 100);

    let summary = daemon.shutdown().unwrap();
    drop(stalled);
    // The hub kept up: no acquisition event dropped; the trial recorded every poll the TCP
    // client saw.
    assert_eq!(summary.dropped, 0);
    let trial = &summary.trials[0];
    assert!(trial.recorded.segments >= 5100, "{:?}", trial.recorded);
    assert!(trial.path.as_ref().is_some_and(|p| p.exists()));
    std::fs::remove_dir_all(data_dir).ok();
}
