//! Control commands: the token guards the handler, malformed and garbage input gets clear
//! error replies, and the server keeps serving everyone.
#![allow(clippy::unwrap_used)]

mod net_support;

use std::sync::Arc;

use antenna_data::stream::{ControlCommand, ErrorCode, StageTarget, StreamMessage};
use std::time::Duration;

use host_daemon::net::{
    ControlHandler, ControlToken, RecordingHandler, ServerOptions, StreamServer,
};
use net_support::{Client, TOKEN, samples, wait_for_clients};

fn server_with(handler: Arc<RecordingHandler>) -> StreamServer {
    StreamServer::bind("127.0.0.1:0", ControlToken::new(TOKEN).unwrap(), handler).unwrap()
}

fn connect(server: &StreamServer) -> Client {
    let mut client = Client::connect(server.local_addr());
    assert!(matches!(client.next_message(), StreamMessage::Hello { .. }));
    client
}

#[test]
fn correct_token_calls_the_handler_for_every_command() {
    let handler = Arc::new(RecordingHandler::new());
    let server = server_with(Arc::clone(&handler));
    let mut c = connect(&server);
    let requests = [
        r#"{"id":1,"token":"TOKEN","cmd":"start_trial","name":"wall-a","metadata":{"wall":"brick"}}"#,
        r#"{"id":2,"token":"TOKEN","cmd":"move_stage","position_m":0.3,"speed_m_per_s":0.01}"#,
        r#"{"id":3,"token":"TOKEN","cmd":"move_stage","relative_m":-0.05}"#,
        r#"{"id":4,"token":"TOKEN","cmd":"set_base_angle","angle_deg":15.0}"#,
        r#"{"id":5,"token":"TOKEN","cmd":"stop_trial"}"#,
        r#"{"id":6,"token":"TOKEN","cmd":"stop_all"}"#,
    ];
    for (i, request) in requests.iter().enumerate() {
        c.send_line(&request.replace("TOKEN", TOKEN));
        let reply = c.next_reply();
        assert_eq!(reply.id, Some(i as u64 + 1));
        assert!(reply.ok, "{reply:?}");
        assert_eq!(reply.error, None);
    }
    let calls = handler.calls();
    assert_eq!(calls.len(), 6);
    assert!(
        matches!(&calls[0], ControlCommand::StartTrial { name, metadata }
        if name == "wall-a" && metadata.get("wall").map(String::as_str) == Some("brick"))
    );
    assert_eq!(
        calls[1],
        ControlCommand::MoveStage {
            target: StageTarget::Absolute { position_m: 0.3 },
            speed_m_per_s: Some(0.01)
        }
    );
    assert_eq!(
        calls[2],
        ControlCommand::MoveStage {
            target: StageTarget::Relative { distance_m: -0.05 },
            speed_m_per_s: None
        }
    );
    assert_eq!(calls[3], ControlCommand::SetBaseAngle { angle_deg: 15.0 });
    assert_eq!(calls[4], ControlCommand::StopTrial);
    assert_eq!(calls[5], ControlCommand::StopAll);
    server.shutdown();
}

#[test]
fn wrong_or_missing_token_is_refused_and_the_handler_not_called() {
    let handler = Arc::new(RecordingHandler::new());
    let server = server_with(Arc::clone(&handler));
    let mut c = connect(&server);
    for (id, request) in [
        r#"{"id":10,"token":"nope","cmd":"stop_trial"}"#,
        r#"{"id":11,"cmd":"start_trial","name":"x"}"#,
        r#"{"id":12,"token":"","cmd":"set_base_angle","angle_deg":5}"#,
        r#"{"id":13,"token":42,"cmd":"auth"}"#,
    ]
    .iter()
    .enumerate()
    {
        c.send_line(request);
        let reply = c.next_reply();
        assert_eq!(reply.id, Some(10 + id as u64));
        assert!(!reply.ok);
        assert_eq!(reply.error, Some(ErrorCode::BadToken));
    }
    assert!(handler.calls().is_empty());
    // The connection is still usable, and the right token is answered.
    c.send_line(&format!(
        r#"{{"id":15,"token":"{TOKEN}","cmd":"stop_trial"}}"#
    ));
    assert!(c.next_reply().ok);
    assert_eq!(handler.calls(), vec![ControlCommand::StopTrial]);
    // A token with the right prefix is still wrong.
    let mut other = connect(&server);
    other.send_line(&format!(
        r#"{{"id":14,"token":"{}","cmd":"stop_trial"}}"#,
        &TOKEN[..TOKEN.len() - 1]
    ));
    assert_eq!(other.next_reply().error, Some(ErrorCode::BadToken));
    assert_eq!(handler.calls().len(), 1);
    server.shutdown();
}

/// Bytes of filler in each line of the queue-jumping test: lines stay under the protocol's
/// [`antenna_data::stream::MAX_LINE_BYTES`].
const FILLER_BYTES: usize = 48 * 1024;

/// A sample message numbered `seq`, made about [`FILLER_BYTES`] long by one segment's error.
fn bulky_samples(seq: u64, filler: &str) -> StreamMessage {
    let mut message = samples(seq);
    if let StreamMessage::Samples { segments, .. } = &mut message {
        segments[0].error = Some(filler.to_owned());
    }
    message
}

/// The most payload a loopback TCP connection can hold in its buffers (the sender's send
/// buffer plus the receiver's receive buffer), from the kernel's limits: the larger of the
/// autotuning maximum and the explicit-setting maximum (doubled, as the kernel doubles a set
/// size), per direction. 64 MiB when they cannot be read.
fn socket_buffer_limit_bytes() -> usize {
    let read = |path: &str, field: usize| -> Option<usize> {
        std::fs::read_to_string(path)
            .ok()?
            .split_whitespace()
            .nth(field)?
            .parse()
            .ok()
    };
    let limits = (
        read("/proc/sys/net/ipv4/tcp_wmem", 2),
        read("/proc/sys/net/core/wmem_max", 0),
        read("/proc/sys/net/ipv4/tcp_rmem", 2),
        read("/proc/sys/net/core/rmem_max", 0),
    );
    match limits {
        (Some(tcp_w), Some(core_w), Some(tcp_r), Some(core_r)) => {
            tcp_w.max(2 * core_w) + tcp_r.max(2 * core_r)
        }
        _ => 64 << 20,
    }
}

#[test]
fn stop_all_needs_no_token_and_jumps_the_stream_queue() {
    let handler = Arc::new(RecordingHandler::new());
    let socket_bytes = socket_buffer_limit_bytes();
    // Enough lines that the queue holds half as many bytes again as the socket's buffers.
    let queue_capacity = (socket_bytes * 3 / 2).div_ceil(FILLER_BYTES) + 16;
    let server = StreamServer::bind_with(
        "127.0.0.1:0",
        ControlToken::new(TOKEN).unwrap(),
        Arc::clone(&handler) as Arc<dyn ControlHandler>,
        ServerOptions {
            queue_capacity,
            // The client stops reading on purpose: however loaded the machine, it is not
            // disconnected for lagging before it reads again.
            write_timeout: Duration::from_secs(120),
            ..ServerOptions::default()
        },
    )
    .unwrap();
    let mut c = connect(&server);
    for request in [
        r#"{"id":1,"cmd":"stop_all"}"#,
        r#"{"id":2,"token":"wrong","cmd":"stop_all"}"#,
    ] {
        c.send_line(request);
        let reply = c.next_reply();
        assert!(reply.ok, "{reply:?}");
    }
    assert_eq!(
        handler.calls(),
        vec![ControlCommand::StopAll, ControlCommand::StopAll]
    );
    // The client stops reading. Its lines are made so large that the queue alone holds
    // more bytes than the socket's buffers can (the kernel's limits, read below): once the
    // queue is full, the writer can move only part of it into the socket, so the lines at
    // its tail (the last one queued among them) stay queued until the client reads again,
    // however fast or slow this machine is.
    wait_for_clients(&server, 1);
    let filler = "x".repeat(FILLER_BYTES);
    let mut last_queued = None;
    for seq in 0..1_000_000 {
        if server.publish(&bulky_samples(seq, &filler)) == 0 {
            break;
        }
        last_queued = Some(seq);
    }
    let last_queued = last_queued.expect("the queue took no line");
    // The reply goes out ahead of the stream lines still queued: the last line queued before
    // the request was sent arrives after the reply, and the lines keep their order.
    c.send_line(r#"{"id":3,"cmd":"stop_all"}"#);
    let mut before_reply = 0u64;
    let mut previous_seq = None;
    loop {
        match c.next_message() {
            StreamMessage::Reply(reply) => {
                assert_eq!(reply.id, Some(3));
                break;
            }
            StreamMessage::Samples { seq, .. } => {
                assert_ne!(
                    seq, last_queued,
                    "the last line queued before the request came before the reply"
                );
                assert!(previous_seq < Some(seq), "out of order: {seq}");
                previous_seq = Some(seq);
                before_reply += 1;
            }
            _ => {}
        }
    }
    let mut after_reply = 0u64;
    loop {
        if let StreamMessage::Samples { seq, .. } = c.next_message() {
            assert!(previous_seq < Some(seq), "out of order: {seq}");
            previous_seq = Some(seq);
            after_reply += 1;
            if seq == last_queued {
                break;
            }
        }
    }
    assert_eq!(
        before_reply + after_reply,
        last_queued + 1,
        "every queued line arrives"
    );
    eprintln!("{before_reply} stream lines before the reply, {after_reply} after it");
    server.shutdown();
}

#[test]
fn malformed_commands_get_clear_errors_and_never_reach_the_handler() {
    let handler = Arc::new(RecordingHandler::new());
    let server = server_with(Arc::clone(&handler));
    let mut c = connect(&server);
    let cases: [(&str, ErrorCode, &str); 9] = [
        (
            r#"{"id":1,"token":"T","cmd":"move_stage"}"#,
            ErrorCode::BadRequest,
            "exactly one",
        ),
        (
            r#"{"id":2,"token":"T","cmd":"move_stage","position_m":1,"relative_m":1}"#,
            ErrorCode::BadRequest,
            "exactly one",
        ),
        (
            r#"{"id":3,"token":"T","cmd":"move_stage","positon_m":1}"#,
            ErrorCode::BadRequest,
            "positon_m",
        ),
        (
            r#"{"id":4,"token":"T","cmd":"move_stage","relative_m":0.1,"speed_m_per_s":-1}"#,
            ErrorCode::BadRequest,
            "speed_m_per_s",
        ),
        (
            r#"{"id":5,"token":"T","cmd":"set_base_angle","angle_deg":"ten"}"#,
            ErrorCode::BadRequest,
            "set_base_angle",
        ),
        (
            r#"{"id":6,"token":"T","cmd":"start_trial"}"#,
            ErrorCode::BadRequest,
            "name",
        ),
        (
            r#"{"id":7,"token":"T","cmd":"start_trial","name":"  "}"#,
            ErrorCode::BadRequest,
            "name",
        ),
        (
            r#"{"id":8,"token":"T","cmd":"self_destruct"}"#,
            ErrorCode::UnknownCommand,
            "self_destruct",
        ),
        (r#"{"id":9,"token":"T"}"#, ErrorCode::UnknownCommand, "cmd"),
    ];
    for (request, code, mentions) in cases {
        c.send_line(&request.replace("\"T\"", &format!("\"{TOKEN}\"")));
        let reply = c.next_reply();
        assert!(!reply.ok);
        assert_eq!(reply.error, Some(code), "{request}: {reply:?}");
        assert!(
            reply.message.contains(mentions),
            "{request}: {}",
            reply.message
        );
        assert!(reply.id.is_some());
    }
    c.send_line(r#"{"id":-1,"token":"x","cmd":"stop_all"}"#);
    assert_eq!(c.next_reply().error, Some(ErrorCode::BadRequest));
    assert!(handler.calls().is_empty());
    server.shutdown();
}

#[test]
fn handler_refusal_is_reported_as_rejected() {
    let handler = Arc::new(RecordingHandler::refusing("beyond the soft limit"));
    let server = server_with(Arc::clone(&handler));
    let mut c = connect(&server);
    c.send_line(&format!(
        r#"{{"id":1,"token":"{TOKEN}","cmd":"move_stage","position_m":9}}"#
    ));
    let reply = c.next_reply();
    assert_eq!(reply.error, Some(ErrorCode::Rejected));
    assert_eq!(reply.message, "beyond the soft limit");
    assert_eq!(handler.calls().len(), 1);
    server.shutdown();
}

/// A deterministic byte source (xorshift64), so a failure can be replayed.
fn garbage(len: usize, mut state: u64) -> Vec<u8> {
    (0..len)
        .map(|_| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 24) as u8
        })
        .collect()
}

#[test]
fn garbage_gets_errors_and_the_connection_and_server_keep_working() {
    let handler = Arc::new(RecordingHandler::new());
    let server = server_with(Arc::clone(&handler));
    let mut watcher = connect(&server);
    let mut c = connect(&server);
    wait_for_clients(&server, 2);
    // Random bytes cut into short lines (none over the limit), plus classic non-requests.
    for (i, chunk) in garbage(20_000, 0x9E37_79B9_7F4A_7C15)
        .chunks(200)
        .enumerate()
    {
        let mut line: Vec<u8> = chunk.iter().copied().filter(|&b| b != b'\n').collect();
        line.push(b'\n');
        c.send(&line);
        if i.is_multiple_of(10) {
            c.send(b"not json\n[1,2,3]\n\"str\"\n{\"id\": 5\n\xff\xfe{}\n");
        }
    }
    c.send_line(&format!(
        r#"{{"id":99,"token":"{TOKEN}","cmd":"stop_all"}}"#
    ));
    let mut errors = 0;
    loop {
        let reply = c.next_reply();
        if reply.id == Some(99) {
            assert!(reply.ok, "{reply:?}");
            break;
        }
        assert!(!reply.ok);
        errors += 1;
    }
    assert!(
        errors >= 100,
        "every garbage line gets an error reply ({errors})"
    );
    assert_eq!(handler.calls(), vec![ControlCommand::StopAll]);
    server.publish(&samples(1));
    assert_eq!(watcher.next_message(), samples(1));
    server.shutdown();
}

#[test]
fn over_long_line_gets_an_error_then_the_connection_closes_and_others_are_served() {
    let handler = Arc::new(RecordingHandler::new());
    let server = server_with(Arc::clone(&handler));
    let mut watcher = connect(&server);
    let mut c = connect(&server);
    wait_for_clients(&server, 2);
    let flood = vec![b'{'; 4 * antenna_data::stream::MAX_LINE_BYTES];
    // The server may close before it has read all of it; a failed write is fine then.
    let _ = std::io::Write::write_all(&mut c.writer, &flood);
    let reply = c.next_reply();
    assert_eq!(reply.error, Some(ErrorCode::LineTooLong));
    c.expect_closed();
    wait_for_clients(&server, 1);
    server.publish(&samples(2));
    assert_eq!(watcher.next_message(), samples(2));
    let mut fresh = connect(&server);
    fresh.send_line(&format!(
        r#"{{"id":1,"token":"{TOKEN}","cmd":"stop_trial"}}"#
    ));
    assert!(fresh.next_reply().ok);
    assert_eq!(handler.calls(), vec![ControlCommand::StopTrial]);
    server.shutdown();
}

#[test]
fn short_token_cannot_be_configured_and_busy_port_is_a_clear_error() {
    assert!(ControlToken::new("").is_err());
    assert!(ControlToken::new("a").is_err());
    let first = server_with(Arc::new(RecordingHandler::new()));
    let err = StreamServer::bind(
        first.local_addr(),
        ControlToken::new(TOKEN).unwrap(),
        Arc::new(RecordingHandler::new()),
    )
    .unwrap_err();
    assert!(err.to_string().contains("cannot listen on"), "{err}");
    first.shutdown();
}
