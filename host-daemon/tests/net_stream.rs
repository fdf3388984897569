//! The stream side: every client gets every message in order; slow clients are lagged (drops
//! counted exactly), stalled ones disconnected, and neither delays `publish` or other clients.
#![allow(clippy::unwrap_used)]

mod net_support;

use std::net::TcpStream;
use std::sync::Arc;
use std::sync::mpsc;
use std::thread;
use std::time::{Duration, Instant};

use antenna_data::stream::{EstimateMessage, PROTOCOL_VERSION, StreamMessage};
use host_daemon::net::{ControlToken, RecordingHandler, ServerOptions, StreamServer};
use net_support::{Client, TOKEN, follow_exactly, samples, wait_for_clients};

fn server(options: ServerOptions) -> StreamServer {
    StreamServer::bind_with(
        "127.0.0.1:0",
        ControlToken::new(TOKEN).unwrap(),
        Arc::new(RecordingHandler::new()),
        options,
    )
    .unwrap()
}

/// Publishes `seq, seq+1, ...` every 5 ms until `done` says the readers are finished.
fn publish_tail_until(server: &StreamServer, mut seq: u64, done: impl Fn() -> bool) {
    // Only a hang ever takes this long; the readers normally finish in a second or two.
    let deadline = Instant::now() + Duration::from_secs(300);
    while !done() {
        assert!(Instant::now() < deadline, "readers never reached the tail");
        server.publish(&samples(seq));
        seq += 1;
        thread::sleep(Duration::from_millis(5));
    }
}

#[test]
fn hello_then_every_message_in_order_for_several_clients() {
    let server = server(ServerOptions {
        queue_capacity: 10_000,
        segment_addresses: vec![0x21, 0x22, 0x23],
        ..ServerOptions::default()
    });
    let mut clients: Vec<Client> = (0..4)
        .map(|_| Client::connect(server.local_addr()))
        .collect();
    wait_for_clients(&server, 4);
    for client in &mut clients {
        match client.next_message() {
            StreamMessage::Hello {
                protocol_version,
                segment_count,
                segment_addresses,
                ..
            } => {
                assert_eq!(protocol_version, PROTOCOL_VERSION);
                assert_eq!(segment_count, 3);
                assert_eq!(segment_addresses, vec![0x21, 0x22, 0x23]);
            }
            other => panic!("expected hello, got {other:?}"),
        }
    }
    const N: u64 = 2000;
    for seq in 0..N {
        assert_eq!(server.publish(&samples(seq)), 4);
    }
    for client in &mut clients {
        for seq in 0..N {
            assert_eq!(client.next_message(), samples(seq));
        }
    }
    server.shutdown();
}

#[test]
fn stalled_client_never_delays_publish_and_is_disconnected() {
    let server = server(ServerOptions {
        queue_capacity: 256,
        write_timeout: Duration::from_secs(2),
        ..ServerOptions::default()
    });
    // Connects and never reads: its socket buffers fill, then its writer times out.
    let stalled = TcpStream::connect(server.local_addr()).unwrap();
    let mut healthy = Client::connect(server.local_addr());
    wait_for_clients(&server, 2);

    const N: u64 = 100_000;
    let reader = thread::spawn(move || {
        let counts = follow_exactly(&mut healthy, N);
        (healthy, counts)
    });
    // `publish` never waits for a socket: with the stalled client's socket and queue full,
    // it returns having dropped that client's copy (queued for the healthy one only). How
    // long a publish takes is a benchmark figure, not asserted here.
    let mut dropped_for_the_stalled = 0u64;
    let mut slowest = Duration::ZERO;
    for seq in 0..N {
        let start = Instant::now();
        let queued = server.publish(&samples(seq));
        slowest = slowest.max(start.elapsed());
        if queued < 2 {
            dropped_for_the_stalled += 1;
        }
    }
    eprintln!("slowest of {N} publishes beside a stalled client: {slowest:?}");
    assert!(
        dropped_for_the_stalled > 0,
        "publish never dropped the stalled client's copy"
    );
    publish_tail_until(&server, N, || reader.is_finished());
    let (mut healthy, (received, dropped)) = reader.join().unwrap();
    assert!(received > 0);
    assert!(
        received + dropped > N,
        "the healthy client saw every message or its drop count"
    );

    // As the daemon keeps publishing, the stalled client (its queue full for longer than the
    // write timeout) is disconnected, and the server keeps serving.
    publish_tail_until(&server, 2 * N, || server.client_count() == 1);
    // It was the stalled one: its stream ends (after what its buffers held) ...
    Client::from_stream(stalled).expect_closed();
    // ... while the healthy one still gets what is published.
    server.publish(&samples(3 * N));
    let mut seen_last = false;
    for _ in 0..1_000_000 {
        if let StreamMessage::Samples { seq, .. } = healthy.next_message()
            && seq == 3 * N
        {
            seen_last = true;
            break;
        }
    }
    assert!(seen_last);
    server.shutdown();
}

#[test]
fn slow_client_gets_exact_lag_counts_and_stays_connected() {
    let server = server(ServerOptions {
        queue_capacity: 8,
        write_timeout: Duration::from_secs(60),
        ..ServerOptions::default()
    });
    let mut slow = Client::connect(server.local_addr());
    wait_for_clients(&server, 1);
    // Far more than the socket buffers and the queue hold while the client is not reading:
    // about 0.85 kB a message, and loopback buffers autotune up to 4 MB to send plus 32 MB to
    // receive (`tcp_wmem`, `tcp_rmem`), so 50,000 messages could all fit; 200,000 cannot.
    const N: u64 = 200_000;
    for seq in 0..N {
        server.publish(&samples(seq));
    }
    // The reader hands the client back: dropping it would close the connection, which the
    // server may then reap before the count below.
    let reader = thread::spawn(move || {
        let counts = follow_exactly(&mut slow, N);
        (slow, counts)
    });
    publish_tail_until(&server, N, || reader.is_finished());
    let (_slow, (received, dropped)) = reader.join().unwrap();
    assert!(dropped > 0, "the slow client should have been lagged");
    assert!(received > 0);
    assert_eq!(
        server.client_count(),
        1,
        "a slow client is lagged, not disconnected"
    );
    server.shutdown();
}

/// An estimate line of poll `seq` (the daemon sends one after every tenth poll's samples).
fn estimate(seq: u64) -> StreamMessage {
    StreamMessage::Estimate(EstimateMessage {
        seq,
        t_ns: seq * 1_000_000,
        estimated_ns: seq * 1_000_000 + 20_000,
        estimator: "contact-line".to_owned(),
        distance_m: Some(0.14),
        angle_rad: Some(-0.1),
        preview_m: Some(0.3),
        reason: None,
        true_distance_m: None,
        true_angle_rad: None,
    })
}

#[test]
fn with_other_lines_dropped_too_samples_dropped_is_the_exact_seq_gap() {
    let server = server(ServerOptions {
        queue_capacity: 8,
        write_timeout: Duration::from_secs(60),
        ..ServerOptions::default()
    });
    let mut slow = Client::connect(server.local_addr());
    wait_for_clients(&server, 1);
    const N: u64 = 150_000;
    let publish = |seq: u64| {
        server.publish(&samples(seq));
        if seq.is_multiple_of(10) {
            server.publish(&estimate(seq));
        }
    };
    for seq in 0..N {
        publish(seq);
    }
    let reader = thread::spawn(move || {
        let (mut next, mut pending, mut lagged_estimates) = (0u64, 0u64, 0u64);
        let (mut received, mut estimates) = (0u64, 0u64);
        loop {
            match slow.next_message() {
                StreamMessage::Hello { .. } => {}
                StreamMessage::Lagged {
                    dropped,
                    samples_dropped,
                } => {
                    assert!(samples_dropped <= dropped);
                    pending += samples_dropped;
                    lagged_estimates += dropped - samples_dropped;
                }
                StreamMessage::Samples { seq, .. } => {
                    assert_eq!(
                        seq,
                        next + pending,
                        "gap not accounted for by samples_dropped"
                    );
                    (next, pending) = (seq + 1, 0);
                    received += 1;
                    if seq >= N {
                        return (slow, received, estimates, lagged_estimates);
                    }
                }
                StreamMessage::Estimate(e) => {
                    assert!(e.seq.is_multiple_of(10));
                    estimates += 1;
                }
                other => panic!("unexpected {other:?}"),
            }
        }
    });
    let mut seq = N;
    let deadline = Instant::now() + Duration::from_secs(300);
    while !reader.is_finished() {
        assert!(
            Instant::now() < deadline,
            "the reader never reached the tail"
        );
        publish(seq);
        seq += 1;
        thread::sleep(Duration::from_millis(5));
    }
    let (_slow, received, estimates, lagged_estimates) = reader.join().unwrap();
    assert!(received > 0 && estimates > 0);
    assert!(lagged_estimates > 0, "estimates were dropped too");
    server.shutdown();
}

#[test]
fn read_only_client_that_closes_its_sending_side_keeps_receiving() {
    let server = server(ServerOptions::default());
    let mut client = Client::connect(server.local_addr());
    wait_for_clients(&server, 1);
    client.writer.shutdown(std::net::Shutdown::Write).unwrap();
    assert!(matches!(client.next_message(), StreamMessage::Hello { .. }));
    thread::sleep(Duration::from_millis(50));
    server.publish(&samples(7));
    assert_eq!(client.next_message(), samples(7));
    server.shutdown();
}

#[test]
fn shutdown_joins_its_threads_and_closes_every_connection() {
    let server = server(ServerOptions {
        queue_capacity: 64,
        write_timeout: Duration::from_secs(600),
        ..ServerOptions::default()
    });
    let addr = server.local_addr();
    let mut reading = Client::connect(addr);
    let stalled = TcpStream::connect(addr).unwrap();
    wait_for_clients(&server, 2);
    // Fill the stalled client's socket so its writer is blocked in a write.
    for seq in 0..20_000 {
        server.publish(&samples(seq));
    }
    let (done_tx, done_rx) = mpsc::channel();
    let stopper = thread::spawn(move || {
        server.shutdown();
        done_tx.send(()).unwrap();
    });
    // Shutdown must not wait for the 600 s write timeout of the blocked writer.
    done_rx
        .recv_timeout(Duration::from_secs(20))
        .expect("shutdown did not return");
    stopper.join().unwrap();
    reading.expect_closed();
    assert!(TcpStream::connect(addr).is_err(), "the listener is closed");
    drop(stalled);
}

/// At the limit a new client takes the place of the oldest one that never proved the token
/// (told why); an operator's connection is never dropped, so then the new one is refused.
#[test]
fn at_the_limit_the_oldest_reader_makes_room_and_operators_stay() {
    use antenna_data::stream::ErrorCode;
    let server = server(ServerOptions {
        max_clients: 1,
        ..ServerOptions::default()
    });
    let mut first = Client::connect(server.local_addr());
    assert!(matches!(first.next_message(), StreamMessage::Hello { .. }));
    wait_for_clients(&server, 1);
    let mut second = Client::connect(server.local_addr());
    assert!(matches!(second.next_message(), StreamMessage::Hello { .. }));
    assert_eq!(first.next_reply().error, Some(ErrorCode::Evicted));
    first.expect_closed();
    wait_for_clients(&server, 1);
    second.send_line(&format!(r#"{{"id":1,"token":"{TOKEN}","cmd":"auth"}}"#));
    assert!(second.next_reply().ok);
    assert_eq!(server.operator_count(), 1);
    let mut third = Client::connect(server.local_addr());
    assert_eq!(third.next_reply().error, Some(ErrorCode::TooManyClients));
    third.expect_closed();
    server.publish(&samples(1));
    assert_eq!(second.next_message(), samples(1));
    server.shutdown();
}
