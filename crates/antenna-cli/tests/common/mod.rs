//! Helpers shared by the `antenna` command's integration tests: run the binary, find the
//! examples, write scratch files.
#![allow(dead_code, clippy::unwrap_used)]

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

/// The `antenna` binary under test.
pub fn antenna() -> Command {
    Command::new(env!("CARGO_BIN_EXE_antenna"))
}

/// Runs `antenna args...`.
pub fn run(args: &[&str]) -> Output {
    antenna().args(args).output().unwrap()
}

/// Runs `antenna args...` with `stdin` on its standard input.
pub fn run_with_stdin(args: &[&str], stdin: &str) -> Output {
    let mut child = antenna()
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    child
        .stdin
        .take()
        .unwrap()
        .write_all(stdin.as_bytes())
        .unwrap();
    child.wait_with_output().unwrap()
}

pub fn stdout(o: &Output) -> String {
    String::from_utf8(o.stdout.clone()).unwrap()
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8(o.stderr.clone()).unwrap()
}

/// The repository's `examples/` directory.
pub fn examples_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

/// Every `examples/*.toml`, sorted.
pub fn example_scenes() -> Vec<PathBuf> {
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(examples_dir())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    scenes.sort();
    scenes
}

pub fn example(name: &str) -> String {
    examples_dir().join(name).display().to_string()
}

/// Writes `text` to a scratch file named `name` (unique per test binary) and returns its path.
pub fn scratch(name: &str, text: &str) -> String {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("antenna-cli-tests");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    // Tests run in parallel and several write the same file: write aside, then rename, so a
    // reader never sees a half-written file.
    static NEXT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let aside = dir.join(format!("{name}.{}.{n}.tmp", std::process::id()));
    std::fs::write(&aside, text).unwrap();
    std::fs::rename(&aside, &path).unwrap();
    path.display().to_string()
}

/// A short version of the thesis's 4.2.1 sweep (`examples/sweep_line_wall.toml`): 20 steps.
/// Line numbers matter to the error tests: `[[walls]]` is line 11, `[sweep]` line 17,
/// `[start]` line 22.
pub const WALL_SCENE: &str = r#"[antenna]
links = 9
link_length_m = 0.04
base_angle_deg = 30.0

[antenna.stiffness]
profile = "linear"
min_n_m_per_rad = 0.004
max_n_m_per_rad = 0.082

[[walls]]
shape = "line"
point_m = [0.0, 0.2]
angle_deg = -8.0
solid = "left"

[sweep]
velocity_m_per_s = [0.0167, 0.0]
duration_s = 0.2
step_s = 0.01

[start]
placement = "tip-on-wall"
ahead_m = 0.0
shape = "C"
"#;
