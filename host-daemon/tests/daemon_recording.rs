//! Recording with a real antennad, in-process on the simulated rig: the default trial's file
//! is zstd-compressed at least ten times smaller than its messages; a disk that fills up
//! refuses new trials and ends a running one cleanly, the reason the file's last word, while
//! polling and streaming go on.
#![allow(clippy::unwrap_used)]

mod net_support;

use std::io;
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use antenna_data::record::TrialReader;
use antenna_data::stream::StreamMessage;
use host_daemon::net::ControlToken;
use host_daemon::service::config::Config;
use host_daemon::service::daemon::{Daemon, DaemonOptions};
use host_daemon::service::free_space::FreeSpace;
use net_support::{Client, TOKEN};

fn temp_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("antennad-rec-{name}-{}", std::process::id()));
    std::fs::remove_dir_all(&dir).ok();
    dir
}

/// The default trial (its stage moves, the sim at 1 kHz) for 2 s: the file holds every poll
/// in zstd chunks at least ten times smaller than the chunks' messages.
#[test]
fn the_default_trial_is_recorded_ten_times_smaller() {
    let dir = temp_dir("size");
    let config = Config {
        data_dir: dir.clone(),
        ..Config::default()
    };
    let options = DaemonOptions {
        first_trial: Some(None),
        first_trial_duration: Some(Duration::from_secs(2)),
        exit_after_trial: true,
        serve: false,
        ..DaemonOptions::default()
    };
    let summary = Daemon::start(config, options).unwrap().wait().unwrap();
    let path = summary.trials[0].path.clone().unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let index = mcap::Summary::read(&bytes).unwrap().unwrap();
    let uncompressed: u64 = index
        .chunk_indexes
        .iter()
        .map(|c| c.uncompressed_size)
        .sum();
    assert!(index.chunk_indexes.iter().all(|c| c.compression == "zstd"));
    let file = bytes.len() as u64;
    assert!(
        10 * file <= uncompressed,
        "{file} B on disk for {uncompressed} B of messages"
    );
    let trial = TrialReader::read(&path).unwrap();
    assert!(trial.truncated.is_none());
    assert_eq!(
        trial.segments.len() as u64,
        summary.trials[0].recorded.segments
    );
    // The trial ended for a reason, recorded as the file's last word.
    let last = trial.log.last().unwrap();
    assert_eq!(last.text, "trial ended: its duration passed");
    std::fs::remove_dir_all(&dir).ok();
}

/// A disk whose free space the test sets.
#[derive(Debug)]
struct FakeDisk(AtomicU64);

impl FreeSpace for FakeDisk {
    fn free_bytes(&self, _dir: &Path) -> io::Result<u64> {
        Ok(self.0.load(Ordering::SeqCst))
    }
}

#[test]
fn a_full_disk_refuses_a_trial_and_ends_a_running_one_while_polling_goes_on() {
    let dir = temp_dir("full");
    let mut config = Config {
        data_dir: dir.clone(),
        ..Config::default()
    };
    config.server.listen = "127.0.0.1:0".to_owned();
    config.server.token = Some(ControlToken::new(TOKEN).unwrap());
    config.bus.poll_hz = 200.0;
    config.trials[0].duration_s = 60.0;
    config.recording.min_free_mb = 50.0;
    let disk = Arc::new(FakeDisk(AtomicU64::new(10_000_000)));
    let options = DaemonOptions {
        free_space: Arc::clone(&disk) as Arc<dyn FreeSpace>,
        ..DaemonOptions::default()
    };
    let daemon = Daemon::start(config, options).unwrap();
    let mut client = Client::connect(daemon.local_addr().unwrap());
    let start = format!(r#"{{"id":1,"token":"{TOKEN}","cmd":"start_trial","name":"wall-sweep"}}"#);
    // 10 MB free, 50 MB needed: refused before a file is made.
    client.send_line(&start);
    let reply = client.next_reply();
    assert!(
        !reply.ok && reply.message.contains("nearly full"),
        "{reply:?}"
    );
    assert!(!dir.join("wall-sweep.mcap").exists());
    // Room again: the trial runs...
    disk.0.store(1_000_000_000, Ordering::SeqCst);
    client.send_line(&start);
    assert!(client.next_reply().ok);
    // 100 polls of the trial streamed (and so recorded), however long that takes here.
    let mut polled = 0;
    while polled < 100 {
        if let StreamMessage::Samples { .. } = client.next_message() {
            polled += 1;
        }
    }
    // ...until the disk fills up: it ends within the second, with the reason recorded.
    disk.0.store(1_000_000, Ordering::SeqCst);
    // Only a hang takes this long, however loaded the machine.
    let deadline = Instant::now() + Duration::from_secs(60);
    while daemon.trial().is_some() {
        assert!(Instant::now() < deadline, "the trial did not end");
        std::thread::sleep(Duration::from_millis(20));
    }
    // Polling and streaming go on.
    let mut samples = 0;
    while samples < 50 {
        if let StreamMessage::Samples { .. } = client.next_message() {
            samples += 1;
        }
    }
    let summary = daemon.shutdown().unwrap();
    assert_eq!(summary.trials.len(), 1);
    assert_eq!(summary.trials[0].ended, "the disk is nearly full");
    let trial = TrialReader::read(dir.join("wall-sweep.mcap")).unwrap();
    assert!(trial.truncated.is_none(), "the file was closed cleanly");
    let texts: Vec<&str> = trial.log.iter().map(|l| l.text.as_str()).collect();
    assert!(
        texts.iter().any(|t| t.contains("nearly full: 1.0 MB free")),
        "{texts:?}"
    );
    assert_eq!(texts.last(), Some(&"trial ended: the disk is nearly full"));
    assert!(trial.segments.len() > 50);
    std::fs::remove_dir_all(&dir).ok();
}
