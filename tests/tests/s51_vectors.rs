//! The C shim (`firmware-segment/c-shim/src/segment.c`) compiled by SDCC for the 8051 and run
//! on the s51 simulator, compared output for output with the Rust crates (`antenna-protocol`
//! and `firmware-segment`) over more than ten thousand vectors; and the P89LPC938 build's size
//! against the part's memories.
//!
//! Needs `sdcc` and `s51` (Debian: `apt-get install sdcc sdcc-ucsim`); the tests fail, not skip,
//! without them. The harness (`c-shim/s51/vectors_main.c`) reads a binary vector file through
//! the simulator's I/O port and prints one hex line per record; its header comment documents
//! the record format, which [`Record::encode`] writes.
#![allow(clippy::unwrap_used)]

use antenna_protocol::{SampleWord, StatusFlags, pec};
use firmware_segment::{
    BusEvent, Debouncer, TOUCH_STUCK_SAMPLES, TargetMachine, adc_fault, oversample,
};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use rayon::prelude::*;
use std::fmt::Write as _;
use std::io::{BufRead, BufReader, Write as _};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

const SETUP_HINT: &str = "install the 8051 toolchain: apt-get install sdcc sdcc-ucsim";
const BEGIN_MARKER: &str = "<<SEG-BEGIN>>";
const END_MARKER: &str = "<<SEG-END>>";
/// One s51 run must finish well within this (the whole set takes about 15 s on two cores).
const S51_TIMEOUT: Duration = Duration::from_secs(180);
const MIN_VECTORS: usize = 10_000;

/// One record of the vector file (see `c-shim/s51/vectors_main.c`).
#[derive(Debug, Clone, Copy)]
enum Record {
    Pack { angle: u16, touch: u8 },
    Pec { crc: u8, byte: u8 },
    Oversample([u16; 16]),
    DebounceReset,
    DebounceStep(u8),
    DebounceRun { raw: u8, count: u16 },
    TargetInit { address: u8, address_set: u8 },
    TargetPublish { word: u16, status: u8 },
    TargetStep { i2stat: u8, rx: u8 },
}

impl Record {
    fn encode(&self, out: &mut Vec<u8>) {
        match *self {
            Record::Pack { angle, touch } => {
                out.push(0x01);
                out.extend_from_slice(&angle.to_be_bytes());
                out.push(touch);
            }
            Record::Pec { crc, byte } => out.extend_from_slice(&[0x02, crc, byte]),
            Record::Oversample(samples) => {
                out.push(0x03);
                for sample in samples {
                    out.extend_from_slice(&sample.to_be_bytes());
                }
            }
            Record::DebounceReset => out.push(0x04),
            Record::DebounceStep(raw) => out.extend_from_slice(&[0x05, raw]),
            Record::DebounceRun { raw, count } => {
                assert!(count >= 1);
                out.extend_from_slice(&[0x06, raw]);
                out.extend_from_slice(&count.to_be_bytes());
            }
            Record::TargetInit {
                address,
                address_set,
            } => out.extend_from_slice(&[0x07, address, address_set]),
            Record::TargetPublish { word, status } => {
                out.push(0x08);
                out.extend_from_slice(&word.to_be_bytes());
                out.push(status);
            }
            Record::TargetStep { i2stat, rx } => out.extend_from_slice(&[0x09, i2stat, rx]),
        }
    }

    /// Whether the harness prints result bytes for it (the others print an empty line).
    fn has_output(&self) -> bool {
        !matches!(
            self,
            Record::DebounceReset | Record::TargetInit { .. } | Record::TargetPublish { .. }
        )
    }

    /// Rough s51 cost, for spreading the groups over simulator processes.
    fn cost(&self) -> u64 {
        match *self {
            Record::Pack { .. } | Record::Pec { .. } | Record::DebounceReset => 1,
            Record::Oversample(_) => 8,
            Record::DebounceStep(_) | Record::TargetInit { .. } | Record::TargetPublish { .. } => 3,
            Record::DebounceRun { count, .. } => 3 * u64::from(count),
            Record::TargetStep { .. } => 12,
        }
    }
}

/// The Rust side: what the harness must print for each record.
struct Reference {
    debouncer: Debouncer,
    target: TargetMachine,
}

impl Reference {
    /// The state the harness starts in.
    fn new() -> Self {
        Self {
            debouncer: Debouncer::new(),
            target: TargetMachine::new(antenna_protocol::DEFAULT_ADDRESS, false),
        }
    }

    fn expected(&mut self, record: &Record) -> Vec<u8> {
        match *record {
            Record::Pack { angle, touch } => SampleWord::pack_truncate(angle, touch)
                .raw()
                .to_be_bytes()
                .to_vec(),
            Record::Pec { crc, byte } => vec![pec::update(crc, byte)],
            Record::Oversample(samples) => {
                let [hi, lo] = oversample(&samples).to_be_bytes();
                vec![hi, lo, u8::from(adc_fault(&samples))]
            }
            Record::DebounceReset => {
                self.debouncer = Debouncer::new();
                Vec::new()
            }
            Record::DebounceStep(raw) => {
                let stable = self.debouncer.step(raw).bits();
                vec![stable, u8::from(self.debouncer.touch_stuck())]
            }
            Record::DebounceRun { raw, count } => {
                let mut stable = 0;
                for _ in 0..count {
                    stable = self.debouncer.step(raw).bits();
                }
                vec![stable, u8::from(self.debouncer.touch_stuck())]
            }
            Record::TargetInit {
                address,
                address_set,
            } => {
                self.target = TargetMachine::new(address, address_set != 0);
                Vec::new()
            }
            Record::TargetPublish { word, status } => {
                self.target
                    .publish(SampleWord::from_raw(word), StatusFlags::from_bits(status));
                Vec::new()
            }
            Record::TargetStep { i2stat, rx } => {
                let result = self.target.step(BusEvent::from_i2stat(i2stat, rx));
                let s = self.target.state();
                let flags = u8::from(result.ack_next) | (u8::from(result.address_changed) << 1);
                let [word_hi, word_lo] = s.word.to_be_bytes();
                vec![
                    result.tx,
                    flags,
                    s.address,
                    u8::from(s.address_set),
                    s.pointer,
                    s.phase as u8,
                    s.write_register,
                    s.write_len,
                    s.write_payload[0],
                    s.write_payload[1],
                    u8::from(s.write_bad),
                    s.read_buf[0],
                    s.read_buf[1],
                    s.read_buf[2],
                    s.read_len,
                    s.read_index,
                    word_hi,
                    word_lo,
                    s.status,
                    s.counter,
                ]
            }
        }
    }
}

/// A run of records that only depends on the state it sets up itself, so groups can go to
/// different simulator processes.
type Group = Vec<Record>;

fn pack_groups(rng: &mut StdRng) -> Vec<Group> {
    let mut group = Vec::new();
    // Every in-range angle, with a varying (sometimes out-of-range) touch value.
    for angle in 0..=4095u16 {
        group.push(Record::Pack {
            angle,
            touch: rng.random(),
        });
    }
    // Every touch value, at the edges of the angle range.
    for touch in 0..=255u8 {
        for angle in [0u16, 4095, 4096, 0xFFFF] {
            group.push(Record::Pack { angle, touch });
        }
    }
    // Out-of-range angles: the high bits are dropped.
    for _ in 0..1000 {
        group.push(Record::Pack {
            angle: rng.random_range(4096..=u16::MAX),
            touch: rng.random(),
        });
    }
    vec![group]
}

fn pec_groups(rng: &mut StdRng) -> Vec<Group> {
    let mut group = Vec::new();
    for byte in 0..=255u8 {
        group.push(Record::Pec { crc: 0, byte });
        group.push(Record::Pec { crc: byte, byte: 0 });
        group.push(Record::Pec { crc: 0xFF, byte });
    }
    for _ in 0..3500 {
        group.push(Record::Pec {
            crc: rng.random(),
            byte: rng.random(),
        });
    }
    vec![group]
}

fn oversample_groups(rng: &mut StdRng) -> Vec<Group> {
    let mut group = Vec::new();
    let in_range = |rng: &mut StdRng| rng.random_range(1..=1022u16);
    // Clean sets: no fault, sums up to 16 * 1022.
    for _ in 0..400 {
        group.push(Record::Oversample(core::array::from_fn(|_| in_range(rng))));
    }
    // Constant sets, every level near the rails and a spread between.
    for level in (0..=1023u16).step_by(31).chain([0, 1, 2, 1021, 1022, 1023]) {
        group.push(Record::Oversample([level; 16]));
    }
    // One rail (or a value that masks to a rail) at one position.
    for &rail in &[0u16, 1023, 0x0400, 0x07FF, 0xFC00, 0xFFFF, 0x8000, 0x83FF] {
        for position in 0..16 {
            let mut samples: [u16; 16] = core::array::from_fn(|_| in_range(rng));
            samples[position] = rail;
            group.push(Record::Oversample(samples));
        }
    }
    // Values wider than 10 bits: only the low 10 bits count.
    for _ in 0..400 {
        group.push(Record::Oversample(core::array::from_fn(|_| rng.random())));
    }
    // Near-rail values that are not rails: 1 and 1022, with high garbage bits.
    for _ in 0..200 {
        group.push(Record::Oversample(core::array::from_fn(|_| {
            let low = if rng.random_bool(0.5) { 1 } else { 1022 };
            low | (rng.random_range(0..64u16) << 10)
        })));
    }
    vec![group]
}

fn debounce_groups(rng: &mut StdRng) -> Vec<Group> {
    let mut groups = Vec::new();
    // Chattering sequences: each bit flips with its own probability.
    for sequence in 0..50 {
        let mut group = vec![Record::DebounceReset];
        let flip = [0.05, 0.2, 0.5, 0.9][sequence % 4];
        let mut raw: u8 = rng.random::<u8>() & 0x0F;
        for _ in 0..60 {
            for bit in 0..4 {
                if rng.random_bool(flip) {
                    raw ^= 1 << bit;
                }
            }
            // Bits above bit 3 are noise the debouncer must ignore.
            let noise = if rng.random_bool(0.3) {
                rng.random::<u8>() & 0xF0
            } else {
                0
            };
            group.push(Record::DebounceStep(raw | noise));
        }
        groups.push(group);
    }
    // Short holds: a contact for a while, then release, then a run of a few hundred samples.
    let mut group = vec![Record::DebounceReset];
    for _ in 0..40 {
        let raw = rng.random::<u8>() & 0x0F;
        group.push(Record::DebounceRun {
            raw,
            count: rng.random_range(1..400),
        });
        for _ in 0..4 {
            group.push(Record::DebounceStep(rng.random()));
        }
    }
    groups.push(group);
    groups
}

/// The stuck detector: crossing TOUCH_STUCK_SAMPLES, saturating at u16::MAX, and release.
fn stuck_group() -> Group {
    let stuck = TOUCH_STUCK_SAMPLES;
    let mut group = vec![Record::DebounceReset];
    // Bit 0 debounces to 1 at the third read; its count reaches `stuck` after stuck + 2 reads.
    group.push(Record::DebounceRun {
        raw: 0x01,
        count: stuck - 8,
    });
    for _ in 0..16 {
        group.push(Record::DebounceStep(0x01));
    }
    // Bit 1 joins (its own count starts), bit 0 keeps counting up to saturation.
    group.push(Record::DebounceRun {
        raw: 0x03,
        count: u16::MAX - stuck - 10,
    });
    for _ in 0..16 {
        group.push(Record::DebounceStep(0x03));
    }
    // Release bit 0: stuck stays clear only once no held count is at the limit.
    for _ in 0..4 {
        group.push(Record::DebounceStep(0x02));
    }
    for _ in 0..4 {
        group.push(Record::DebounceStep(0x00));
    }
    group
}

const WRITE_CODES: [u8; 4] = [0x60, 0x68, 0x70, 0x78];
const ACK_CODES: [u8; 2] = [0x80, 0x90];
const NACK_CODES: [u8; 2] = [0x88, 0x98];
const READ_CODES: [u8; 2] = [0xA8, 0xB0];
const DONE_CODES: [u8; 2] = [0xC0, 0xC8];

fn pick(rng: &mut StdRng, codes: &[u8]) -> u8 {
    codes[rng.random_range(0..codes.len())]
}

/// Bus transactions, well-formed and not, against the target state machine.
fn target_groups(rng: &mut StdRng) -> Vec<Group> {
    let mut groups = Vec::new();
    for sequence in 0..24 {
        let mut group = Vec::new();
        let (address, address_set) = match sequence % 3 {
            0 => (antenna_protocol::DEFAULT_ADDRESS, 0),
            1 => (rng.random_range(0x08..=0x77), 1),
            _ => (rng.random(), rng.random()),
        };
        group.push(Record::TargetInit {
            address,
            address_set,
        });
        let step =
            |group: &mut Group, i2stat: u8, rx: u8| group.push(Record::TargetStep { i2stat, rx });
        for _ in 0..30 {
            match rng.random_range(0..10) {
                0 => group.push(Record::TargetPublish {
                    word: rng.random(),
                    status: rng.random(),
                }),
                // A read of 0..5 bytes, ended by the controller one way or another.
                1 | 2 => {
                    step(&mut group, pick(rng, &READ_CODES), rng.random());
                    for _ in 0..rng.random_range(0..5) {
                        step(&mut group, 0xB8, rng.random());
                    }
                    let end = match rng.random_range(0..6) {
                        0 => 0xA0,
                        1 => 0x00,
                        _ => pick(rng, &DONE_CODES),
                    };
                    step(&mut group, end, rng.random());
                }
                // Set the pointer (or try to: unknown registers, extra bytes).
                3 | 4 => {
                    step(&mut group, pick(rng, &WRITE_CODES), 0);
                    let register = match rng.random_range(0..8) {
                        0..=3 => rng.random_range(0..4),
                        4 => 0x10,
                        _ => rng.random(),
                    };
                    step(&mut group, pick(rng, &ACK_CODES), register);
                    for _ in 0..rng.random_range(0..3) {
                        let codes = if rng.random_bool(0.5) {
                            &ACK_CODES
                        } else {
                            &NACK_CODES
                        };
                        step(&mut group, pick(rng, codes), rng.random());
                    }
                    step(
                        &mut group,
                        if rng.random_bool(0.9) { 0xA0 } else { 0x00 },
                        0,
                    );
                }
                // Address assignment: valid, wrong complement, unassignable, short, long.
                5 | 6 => {
                    let new_address = match rng.random_range(0..6) {
                        0 => 0x07,
                        1 => 0x08,
                        2 => 0x77,
                        3 => 0x78,
                        _ => rng.random_range(0x08..=0x77),
                    };
                    let complement = if rng.random_bool(0.7) {
                        !new_address
                    } else {
                        rng.random()
                    };
                    step(&mut group, pick(rng, &WRITE_CODES), 0);
                    step(&mut group, pick(rng, &ACK_CODES), 0x10);
                    let payload = [new_address, complement, rng.random()];
                    let len = match rng.random_range(0..8) {
                        0 => 0,
                        1 => 1,
                        2 => 3,
                        _ => 2,
                    };
                    for &byte in &payload[..len] {
                        let nack = rng.random_bool(0.05);
                        step(
                            &mut group,
                            pick(rng, if nack { &NACK_CODES } else { &ACK_CODES }),
                            byte,
                        );
                    }
                    step(
                        &mut group,
                        if rng.random_bool(0.9) { 0xA0 } else { 0x00 },
                        0,
                    );
                }
                // Stray events: any code, any byte.
                _ => {
                    for _ in 0..rng.random_range(1..4) {
                        step(&mut group, rng.random(), rng.random());
                    }
                }
            }
        }
        groups.push(group);
    }
    // Every I2STAT code in every phase.
    let mut group = vec![Record::TargetInit {
        address: 0x21,
        address_set: 1,
    }];
    group.push(Record::TargetPublish {
        word: 0xBEEF,
        status: 0x03,
    });
    for code in 0..=255u8 {
        group.push(Record::TargetStep {
            i2stat: code,
            rx: !code,
        });
        group.push(Record::TargetStep {
            i2stat: 0x60,
            rx: 0,
        });
        group.push(Record::TargetStep {
            i2stat: code,
            rx: 0x10,
        });
        group.push(Record::TargetStep {
            i2stat: 0xA8,
            rx: 0,
        });
        group.push(Record::TargetStep {
            i2stat: code,
            rx: code,
        });
        group.push(Record::TargetStep {
            i2stat: 0xC0,
            rx: 0,
        });
    }
    groups.push(group);
    groups
}

fn all_groups() -> Vec<Group> {
    let mut rng = StdRng::seed_from_u64(0x5E61_8051);
    let mut groups = vec![stuck_group()];
    groups.extend(pack_groups(&mut rng));
    groups.extend(pec_groups(&mut rng));
    groups.extend(oversample_groups(&mut rng));
    groups.extend(debounce_groups(&mut rng));
    groups.extend(target_groups(&mut rng));
    groups
}

/// One simulator process's share: records with their index in the whole set.
#[derive(Default)]
struct Shard {
    records: Vec<(usize, Record)>,
    cost: u64,
}

fn shard(groups: Vec<Group>, shards: usize) -> Vec<Shard> {
    let mut indexed = Vec::new();
    let mut index = 0;
    for group in groups {
        let cost: u64 = group.iter().map(Record::cost).sum();
        let records: Vec<(usize, Record)> = group
            .into_iter()
            .map(|record| {
                index += 1;
                (index - 1, record)
            })
            .collect();
        indexed.push((cost, records));
    }
    // Largest first, each to the least loaded shard.
    indexed.sort_by_key(|(cost, _)| std::cmp::Reverse(*cost));
    let mut out: Vec<Shard> = (0..shards).map(|_| Shard::default()).collect();
    for (cost, records) in indexed {
        let lightest = out.iter_mut().min_by_key(|shard| shard.cost).unwrap();
        lightest.cost += cost;
        lightest.records.extend(records);
    }
    out.retain(|shard| !shard.records.is_empty());
    out
}

/// A shard's records, the lines s51 printed for them, and how long s51 took.
type ShardResult = (Vec<(usize, Record)>, Vec<String>, Duration);

fn c_shim_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../firmware-segment/c-shim")
}

fn require_tool(tool: &str, version_arg: &str) {
    match Command::new(tool).arg(version_arg).output() {
        Ok(_) => {}
        Err(error) => panic!("`{tool}` is not runnable ({error}): {SETUP_HINT}"),
    }
}

/// Runs build-sdcc.sh for `target` into `build_dir`; returns its stdout.
fn build(target: &str, build_dir: &Path) -> String {
    require_tool("sdcc", "--version");
    let script = c_shim_dir().join("build-sdcc.sh");
    let output = Command::new("bash")
        .arg(&script)
        .arg(target)
        .env("BUILD_DIR", build_dir)
        .output()
        .unwrap_or_else(|error| panic!("running {}: {error}", script.display()));
    let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
    assert!(
        output.status.success(),
        "{} {target} failed ({}):\n{stdout}\n{}",
        script.display(),
        output.status,
        String::from_utf8_lossy(&output.stderr)
    );
    stdout
}

/// Runs the harness on one vector file; returns the lines between the markers.
fn run_s51(ihx: &Path, vectors: &Path) -> Vec<String> {
    // s51 quits when its command console reads end of input, even with the program still
    // running: keep stdin open until the end marker has come out, then close it.
    let mut child = Command::new("s51")
        .args(["-t", "8052", "-q", "-I"])
        .arg(format!("if=xram[0xffff],in={}", vectors.display()))
        .arg("-G")
        .arg(ihx)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap_or_else(|error| panic!("`s51` is not runnable ({error}): {SETUP_HINT}"));
    let stdout = child.stdout.take().unwrap();
    let (sender, receiver) = mpsc::channel();
    std::thread::spawn(move || {
        let mut lines = Vec::new();
        for line in BufReader::new(stdout).lines() {
            let Ok(line) = line else { break };
            let line = line.trim_end().to_owned();
            let done = line == END_MARKER || line == "?";
            lines.push(line);
            if done {
                break;
            }
        }
        let _ = sender.send(lines);
    });
    let lines = receiver.recv_timeout(S51_TIMEOUT);
    if lines.is_err() {
        let _ = child.kill();
    }
    let mut stdin = child.stdin.take();
    if let Some(stdin) = stdin.as_mut() {
        let _ = stdin.flush();
    }
    drop(stdin);
    let _ = child.wait();
    let lines = lines.unwrap_or_else(|_| panic!("s51 did not finish within {S51_TIMEOUT:?}"));
    let begin = lines
        .iter()
        .position(|line| line == BEGIN_MARKER)
        .unwrap_or_else(|| panic!("no {BEGIN_MARKER} in the s51 output:\n{}", lines.join("\n")));
    let body = &lines[begin + 1..];
    match body.last().map(String::as_str) {
        Some(END_MARKER) => body[..body.len() - 1].to_vec(),
        // Fewer lines than records: reported by the comparison.
        _ => body.to_vec(),
    }
}

fn parse_hex(line: &str) -> Option<Vec<u8>> {
    if !line.len().is_multiple_of(2) {
        return None;
    }
    (0..line.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(line.get(i..i + 2)?, 16).ok())
        .collect()
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().fold(String::new(), |mut s, b| {
        let _ = write!(s, "{b:02x}");
        s
    })
}

#[test]
fn segment_c_on_s51_matches_the_rust_crates() {
    require_tool("s51", "-v");
    let work = Path::new(env!("CARGO_TARGET_TMPDIR")).join("s51-vectors");
    let _ = std::fs::remove_dir_all(&work);
    std::fs::create_dir_all(&work).unwrap();
    build("s51", &work.join("build"));
    let ihx = work.join("build/s51/vectors.ihx");

    let parallel = std::thread::available_parallelism()
        .map_or(2, |n| n.get())
        .clamp(2, 4);
    let shards = shard(all_groups(), parallel);

    let started = Instant::now();
    // One s51 process per shard, all at once: a pool of as many threads as shards.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(shards.len())
        .build()
        .unwrap();
    let results: Vec<ShardResult> = pool.install(|| {
        shards
            .into_par_iter()
            .enumerate()
            .map(|(n, shard)| {
                let path = work.join(format!("vec{n}.bin"));
                let mut bytes = Vec::new();
                for (_, record) in &shard.records {
                    record.encode(&mut bytes);
                }
                bytes.push(0x00); // END
                std::fs::write(&path, &bytes).unwrap();
                let started = Instant::now();
                let lines = run_s51(&ihx, &path);
                (shard.records, lines, started.elapsed())
            })
            .collect()
    });
    let elapsed = started.elapsed();

    let mut compared = 0usize;
    let mut sent = 0usize;
    let mut mismatches = Vec::new();
    for (records, lines, _) in &results {
        let mut reference = Reference::new();
        sent += records.len();
        for (position, (index, record)) in records.iter().enumerate() {
            let expected = reference.expected(record);
            let Some(line) = lines.get(position) else {
                mismatches.push((*index, format!(
                    "vector {index} {record:?}: expected {}, got nothing (s51 printed {} of {} lines)",
                    hex(&expected),
                    lines.len(),
                    records.len()
                )));
                break;
            };
            match parse_hex(line) {
                Some(got) if got == expected => {
                    if record.has_output() {
                        compared += 1;
                    }
                }
                _ => mismatches.push((
                    *index,
                    format!(
                        "vector {index} {record:?}: expected {}, got {line:?}",
                        hex(&expected)
                    ),
                )),
            }
        }
        if lines.len() > records.len() {
            mismatches.push((
                usize::MAX,
                format!(
                    "s51 printed {} lines for {} records; extra: {:?}",
                    lines.len(),
                    records.len(),
                    &lines[records.len()..lines.len().min(records.len() + 5)]
                ),
            ));
        }
    }
    let per_process: Vec<String> = results
        .iter()
        .map(|(records, _, took)| format!("{} records {:.1} s", records.len(), took.as_secs_f64()))
        .collect();
    println!(
        "s51: {compared} vectors with results compared ({sent} records) in {:.1} s, {} s51 processes in parallel: {}",
        elapsed.as_secs_f64(),
        results.len(),
        per_process.join(", ")
    );
    mismatches.sort_by_key(|(index, _)| *index);
    assert!(
        mismatches.is_empty(),
        "{} mismatches between segment.c on s51 and the Rust crates; first ones:\n{}",
        mismatches.len(),
        mismatches
            .iter()
            .take(25)
            .map(|(_, message)| message.as_str())
            .collect::<Vec<_>>()
            .join("\n")
    );
    assert!(
        compared >= MIN_VECTORS,
        "only {compared} vectors compared, want at least {MIN_VECTORS}"
    );
}

/// Parses "<label>: <n> bytes of <max>" from build-sdcc.sh's report.
fn reported(report: &str, label: &str) -> (u64, u64) {
    let line = report
        .lines()
        .find(|line| line.starts_with(label))
        .unwrap_or_else(|| panic!("no `{label}` line in:\n{report}"));
    let numbers: Vec<u64> = line
        .split(|c: char| !c.is_ascii_digit())
        .filter(|s| !s.is_empty())
        .filter_map(|s| s.parse().ok())
        .collect();
    (numbers[0], numbers[1])
}

#[test]
fn lpc938_build_fits_the_part() {
    let work = Path::new(env!("CARGO_TARGET_TMPDIR")).join("lpc938-size");
    let _ = std::fs::remove_dir_all(&work);
    let report = build("lpc938", &work);
    println!("{report}");
    let (code, flash) = reported(&report, "code");
    let (iram, iram_max) = reported(&report, "internal RAM");
    let (xram, xram_max) = reported(&report, "external RAM");
    assert_eq!((flash, iram_max, xram_max), (8192, 256, 512));
    assert!(code > 0 && code <= 8192, "code {code} B");
    assert!(iram <= 256, "internal RAM {iram} B");
    assert!(xram <= 512, "xdata {xram} B");
    assert!(work.join("lpc938/segment-lpc938.ihx").is_file());
}
