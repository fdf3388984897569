//! The control token never leaves the daemon: a real antennad (in-process, the simulated rig)
//! configured with `token = "..."` in its file runs a trial that a client starts and stops
//! with the token, after guessing wrong and asking for the token to be kept in the trial's
//! notes; the trial is exported with `antenna export` to MAT and CSV. Every byte written is
//! searched for the token: every file under the data directory, the exports, the stream the
//! client received, the daemon's log and the export's output. An older recording whose
//! configuration still holds a token line exports without it too.
#![allow(clippy::unwrap_used)]

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

use antenna_data::record::{TrialReader, TrialRecorder, synthetic_metadata, synthetic_segments};
use host_daemon::service::config::Config;
use host_daemon::service::daemon::{Daemon, DaemonOptions};

const TOKEN: &str = "SECRET-TOKEN-123-abcdef";

fn contains(haystack: &[u8], needle: &str) -> bool {
    haystack
        .windows(needle.len())
        .any(|w| w == needle.as_bytes())
}

/// Every file under `dir`, recursively.
fn files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            out.extend(files(&path));
        } else {
            out.push(path);
        }
    }
    out
}

fn export(trial: &Path, mat: &Path, csv: &Path) -> Vec<u8> {
    let out = Command::new(env!("CARGO_BIN_EXE_antenna"))
        .arg("export")
        .arg(trial)
        .arg("--mat")
        .arg(mat)
        .arg("--csv")
        .arg(csv)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    [out.stdout, out.stderr].concat()
}

/// Sends one request line and reads the stream until its reply; returns every byte read.
fn request(reader: &mut BufReader<TcpStream>, writer: &mut TcpStream, line: &str) -> Vec<u8> {
    writer.write_all(format!("{line}\n").as_bytes()).unwrap();
    let mut bytes = Vec::new();
    loop {
        let mut line = String::new();
        assert!(reader.read_line(&mut line).unwrap() > 0, "closed");
        bytes.extend_from_slice(line.as_bytes());
        if line.starts_with(r#"{"type":"reply""#) {
            return bytes;
        }
    }
}

#[test]
fn the_token_is_nowhere_in_a_trial_its_export_the_stream_or_the_log() {
    let dir = std::env::temp_dir().join(format!("antenna-secrets-{}", std::process::id()));
    std::fs::remove_dir_all(&dir).ok();
    let data = dir.join("data");
    let text = format!(
        "data_dir = {data:?}\n[server]\nlisten = \"127.0.0.1:0\"\ntoken = \"{TOKEN}\"\n\
         [bus]\npoll_hz = 200.0\n[[trials]]\nname = \"secret-trial\"\nduration_s = 30.0\n\
         [trials.metadata]\noperator = \"someone\"\n",
        data = data.display().to_string()
    );
    let config = Config::from_toml_str(&text, "secret.toml").unwrap();
    let daemon = Daemon::start(config, DaemonOptions::default()).unwrap();
    let stream = TcpStream::connect(daemon.local_addr().unwrap()).unwrap();
    stream
        .set_read_timeout(Some(Duration::from_secs(10)))
        .unwrap();
    let mut writer = stream.try_clone().unwrap();
    let mut reader = BufReader::new(stream);
    let mut received = Vec::new();
    received.extend(request(
        &mut reader,
        &mut writer,
        r#"{"id":1,"token":"SECRET-TOKEN-123-abcdeX","cmd":"stop_trial"}"#,
    ));
    received.extend(request(
        &mut reader,
        &mut writer,
        &format!(
            r#"{{"id":2,"token":"{TOKEN}","cmd":"start_trial","name":"secret-trial","metadata":{{"note":"the token is {TOKEN}","{TOKEN}":"as a key"}}}}"#
        ),
    ));
    assert!(
        contains(&received, r#""id":2,"ok":true"#),
        "{}",
        String::from_utf8_lossy(&received)
    );
    std::thread::sleep(Duration::from_millis(700));
    received.extend(request(
        &mut reader,
        &mut writer,
        &format!(r#"{{"id":3,"token":"{TOKEN}","cmd":"stop_trial"}}"#),
    ));
    // Some more of the stream, status lines included.
    let mut more = vec![0u8; 1 << 16];
    let n = reader.read(&mut more).unwrap();
    received.extend_from_slice(&more[..n]);
    let log = daemon.log_lines().join("\n");
    let summary = daemon.shutdown().unwrap();
    assert_eq!(summary.trials.len(), 1);
    let trial_path = summary.trials[0].path.clone().unwrap();

    // The recording kept the configuration (readable back) and the notes, scrubbed.
    let trial = TrialReader::read(&trial_path).unwrap();
    let metadata = trial.metadata.clone().unwrap();
    let recorded = Config::from_toml_str(&metadata.config, "recorded").unwrap();
    assert_eq!(recorded.trials[0].name, "secret-trial");
    assert!(recorded.server.token.is_none());
    assert_eq!(metadata.notes["note"], "the token is <redacted>");
    assert!(trial.segments.len() > 50);

    let exports = dir.join("exports");
    std::fs::create_dir_all(&exports).unwrap();
    let export_output = export(&trial_path, &exports.join("t.mat"), &exports.join("t.csv"));

    let mut searched = 0;
    for file in files(&dir) {
        let bytes = std::fs::read(&file).unwrap();
        assert!(
            !contains(&bytes, TOKEN),
            "the token is in {}",
            file.display()
        );
        searched += 1;
    }
    assert!(searched >= 3, "{searched} files");
    assert!(!contains(&received, TOKEN), "the token is in the stream");
    assert!(
        !contains(log.as_bytes(), TOKEN),
        "the token is in the log:\n{log}"
    );
    assert!(
        log.contains("authentication failed from 127.0.0.1:"),
        "{log}"
    );
    assert!(!contains(&export_output, TOKEN));
    // The MCAP's own metadata record and every message, decompressed, too.
    let bytes = std::fs::read(&trial_path).unwrap();
    for message in mcap::MessageStream::new(&bytes).unwrap() {
        assert!(!contains(&message.unwrap().data, TOKEN));
    }
    let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
    for index in &summary.metadata_indexes {
        let record = mcap::read::metadata(&bytes, index).unwrap();
        for (key, value) in &record.metadata {
            assert!(!key.contains(TOKEN) && !value.contains(TOKEN), "{key}");
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A recording made before antennad left the token out: the export blanks its token line.
#[test]
fn an_old_recording_exports_without_its_token_line() {
    let dir = std::env::temp_dir().join(format!("antenna-old-secret-{}", std::process::id()));
    std::fs::remove_dir_all(&dir).ok();
    std::fs::create_dir_all(&dir).unwrap();
    let mut metadata = synthetic_metadata("old");
    metadata.config = format!("[server]\nlisten = \"127.0.0.1:7878\"\ntoken = \"{TOKEN}\"\n");
    let trial = dir.join("old.mcap");
    let mut recorder = TrialRecorder::create(&trial, &metadata).unwrap();
    for i in 0..20 {
        recorder.record_segments(&synthetic_segments(i, 3)).unwrap();
    }
    recorder.finish().unwrap();
    let (mat, csv) = (dir.join("old.mat"), dir.join("old.csv"));
    export(&trial, &mat, &csv);
    for file in [&mat, &csv] {
        let bytes = std::fs::read(file).unwrap();
        assert!(!contains(&bytes, TOKEN), "{}", file.display());
    }
    let csv = std::fs::read_to_string(&csv).unwrap();
    assert!(csv.contains("# config: token = \"<redacted>\""), "{csv}");
    assert!(
        csv.contains("# config: listen = \"127.0.0.1:7878\""),
        "{csv}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
