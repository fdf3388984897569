//! The C shim (`firmware-segment/c-shim/src/segment.c`, compiled for the host by `build.rs`)
//! against the Rust crates, bit for bit: pack over every angle and touch value, PEC over every
//! byte pair, oversampling and the rail check on random conversions, the debouncer on random
//! raw sequences (with a run long enough to trip the stuck counter), and the I2C target on
//! thousands of random event sequences, comparing the answer and the whole state after every
//! step.
#![allow(clippy::unwrap_used)]

use antenna_protocol::{SampleWord, StatusFlags, pec};
use antenna_tests as _;
use firmware_segment::{
    BusEvent, Debouncer, Phase, StepResult, TOUCH_STUCK_SAMPLES, TargetMachine, TargetState,
    adc_fault, oversample,
};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

/// `seg_debounce_t`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default)]
struct SegDebounce {
    h1: u8,
    h2: u8,
    stable: u8,
    held: [u16; 4],
}

/// `seg_target_t`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
struct SegTarget {
    address: u8,
    address_set: u8,
    pointer: u8,
    phase: u8,
    wr_reg: u8,
    wr_len: u8,
    wr_payload: [u8; 2],
    wr_bad: u8,
    rd_buf: [u8; 3],
    rd_len: u8,
    rd_index: u8,
    word: u16,
    status: u8,
    counter: u8,
}

const SEG_STEP_ACK_NEXT: u8 = 0x01;
const SEG_STEP_ADDRESS_CHANGED: u8 = 0x02;

unsafe extern "C" {
    fn seg_pack(angle12: u16, touch: u8) -> u16;
    fn seg_pec_update(crc: u8, byte: u8) -> u8;
    fn seg_oversample(samples16: *const u16) -> u16;
    fn seg_adc_fault(samples16: *const u16) -> u8;
    fn seg_debounce_init(d: *mut SegDebounce);
    fn seg_debounce_step(d: *mut SegDebounce, raw: u8) -> u8;
    fn seg_touch_stuck(d: *const SegDebounce) -> u8;
    fn seg_target_init(t: *mut SegTarget, address: u8, address_set: u8);
    fn seg_target_publish(t: *mut SegTarget, word: u16, status: u8);
    fn seg_target_step(t: *mut SegTarget, i2stat: u8, rx: u8, tx: *mut u8) -> u8;
}

/// The C debouncer, safely.
struct CDebouncer(SegDebounce);

impl CDebouncer {
    fn new() -> Self {
        let mut d = SegDebounce::default();
        // SAFETY: `d` is a valid, exclusively borrowed seg_debounce_t.
        unsafe { seg_debounce_init(&mut d) };
        Self(d)
    }

    fn step(&mut self, raw: u8) -> u8 {
        // SAFETY: as above.
        unsafe { seg_debounce_step(&mut self.0, raw) }
    }

    fn touch_stuck(&self) -> bool {
        // SAFETY: as above.
        unsafe { seg_touch_stuck(&self.0) != 0 }
    }
}

/// The C target, safely.
struct CTarget(SegTarget);

impl CTarget {
    fn new(address: u8, address_set: bool) -> Self {
        let mut t = SegTarget {
            // Garbage, to show init sets every field.
            rd_buf: [0xAA; 3],
            word: 0x5555,
            ..SegTarget::default()
        };
        // SAFETY: `t` is a valid, exclusively borrowed seg_target_t.
        unsafe { seg_target_init(&mut t, address, u8::from(address_set)) };
        Self(t)
    }

    fn publish(&mut self, word: u16, status: u8) {
        // SAFETY: as above.
        unsafe { seg_target_publish(&mut self.0, word, status) }
    }

    fn step(&mut self, i2stat: u8, rx: u8) -> StepResult {
        let mut tx = 0u8;
        // SAFETY: as above; `tx` is a valid u8 out-pointer.
        let flags = unsafe { seg_target_step(&mut self.0, i2stat, rx, &mut tx) };
        assert_eq!(flags & !(SEG_STEP_ACK_NEXT | SEG_STEP_ADDRESS_CHANGED), 0);
        StepResult {
            tx,
            ack_next: flags & SEG_STEP_ACK_NEXT != 0,
            address_changed: flags & SEG_STEP_ADDRESS_CHANGED != 0,
        }
    }
}

/// The Rust state in the C struct's layout.
fn mirror(s: TargetState) -> SegTarget {
    SegTarget {
        address: s.address,
        address_set: u8::from(s.address_set),
        pointer: s.pointer,
        phase: match s.phase {
            Phase::Idle => 0,
            Phase::Writing => 1,
            Phase::Reading => 2,
        },
        wr_reg: s.write_register,
        wr_len: s.write_len,
        wr_payload: s.write_payload,
        wr_bad: u8::from(s.write_bad),
        rd_buf: s.read_buf,
        rd_len: s.read_len,
        rd_index: s.read_index,
        word: s.word,
        status: s.status,
        counter: s.counter,
    }
}

#[test]
fn pack_matches_for_every_angle_and_touch_value_and_out_of_range_inputs() {
    for angle in 0..=0x0FFFu16 {
        for touch in 0..16u8 {
            // SAFETY: a pure function.
            let c = unsafe { seg_pack(angle, touch) };
            assert_eq!(c, SampleWord::pack_truncate(angle, touch).raw());
        }
    }
    let mut rng = StdRng::seed_from_u64(1);
    let edges = [0x1000u16, 0x1FFF, 0x8000, 0xF000, 0xFFFF];
    for i in 0..20_000 {
        let angle = if i < edges.len() {
            edges[i]
        } else {
            rng.random()
        };
        let touch: u8 = rng.random();
        // SAFETY: a pure function.
        let c = unsafe { seg_pack(angle, touch) };
        assert_eq!(
            c,
            SampleWord::pack_truncate(angle, touch).raw(),
            "{angle:#x} {touch:#x}"
        );
    }
}

#[test]
fn pec_matches_over_every_byte_pair() {
    for a in 0..=255u8 {
        // SAFETY: a pure function.
        let after_a = unsafe { seg_pec_update(0, a) };
        assert_eq!(after_a, pec::compute(&[a]));
        for b in 0..=255u8 {
            // SAFETY: a pure function.
            let c = unsafe { seg_pec_update(after_a, b) };
            assert_eq!(c, pec::compute(&[a, b]), "{a:#04x} {b:#04x}");
        }
    }
}

fn random_conversions(rng: &mut StdRng) -> [u16; 16] {
    let mut samples = [0u16; 16];
    let mode = rng.random_range(0..4);
    for s in &mut samples {
        *s = match mode {
            // In range, rarely a rail.
            0 => rng.random_range(0..=1023),
            // Near the rails.
            1 => [0, 1, 2, 1021, 1022, 1023][rng.random_range(0..6)],
            // Anything: values above 10 bits.
            2 => rng.random(),
            // Mid-scale with junk in the upper bits.
            _ => rng.random_range(1..1023u16) | (rng.random::<u16>() & 0xFC00),
        };
    }
    samples
}

#[test]
fn oversampling_and_the_rail_check_match_on_random_conversions() {
    let mut rng = StdRng::seed_from_u64(2);
    let mut faults = 0;
    for _ in 0..200_000 {
        let samples = random_conversions(&mut rng);
        // SAFETY: `samples` holds the 16 values the functions read.
        let (c_angle, c_fault) = unsafe {
            (
                seg_oversample(samples.as_ptr()),
                seg_adc_fault(samples.as_ptr()),
            )
        };
        assert_eq!(c_angle, oversample(&samples), "{samples:?}");
        assert_eq!(c_fault != 0, adc_fault(&samples), "{samples:?}");
        faults += usize::from(c_fault);
    }
    // Both outcomes were exercised.
    assert!(faults > 1000 && faults < 199_000, "{faults}");
    for rail in [[0u16; 16], [1023; 16], [0xFFFF; 16], [0x0400; 16], [1; 16]] {
        // SAFETY: as above.
        unsafe {
            assert_eq!(seg_oversample(rail.as_ptr()), oversample(&rail));
            assert_eq!(seg_adc_fault(rail.as_ptr()) != 0, adc_fault(&rail));
        }
    }
}

fn assert_debouncers_equal(rust: &Debouncer, c: &CDebouncer, step: usize) {
    assert_eq!(rust.history(), (c.0.h1, c.0.h2), "step {step}");
    assert_eq!(rust.stable().bits(), c.0.stable, "step {step}");
    assert_eq!(rust.held(), c.0.held, "step {step}");
    assert_eq!(rust.touch_stuck(), c.touch_stuck(), "step {step}");
}

#[test]
fn debouncing_matches_on_random_raw_sequences() {
    let mut rng = StdRng::seed_from_u64(3);
    for _ in 0..200 {
        let mut rust = Debouncer::new();
        let mut c = CDebouncer::new();
        let mut raw: u8 = rng.random();
        for step in 0..2_000 {
            // Mostly hold the previous value with a few bits flipping (chatter), sometimes
            // anything (with bits above bit 3).
            raw = if rng.random_bool(0.1) {
                rng.random()
            } else {
                raw ^ if rng.random_bool(0.3) {
                    1 << rng.random_range(0..4)
                } else {
                    0
                }
            };
            assert_eq!(rust.step(raw).bits(), c.step(raw), "step {step}");
            assert_debouncers_equal(&rust, &c, step);
        }
    }
}

#[test]
fn debouncing_matches_through_the_stuck_threshold_and_saturation() {
    let mut rng = StdRng::seed_from_u64(4);
    let mut rust = Debouncer::new();
    let mut c = CDebouncer::new();
    let mut stuck_seen = false;
    // Bit 1 held for longer than u16::MAX samples while the other bits chatter, then released.
    let run = usize::from(u16::MAX) + 1_000;
    for step in 0..run + 10 {
        let chatter: u8 = rng.random::<u8>() & 0b1101;
        let raw = if step < run {
            chatter | 0b0010
        } else {
            chatter
        };
        assert_eq!(rust.step(raw).bits(), c.step(raw), "step {step}");
        assert_debouncers_equal(&rust, &c, step);
        // Bit 1 is stable from the third read (step 2) on, counting from 1.
        if step == usize::from(TOUCH_STUCK_SAMPLES) {
            assert!(!c.touch_stuck());
        }
        if step == usize::from(TOUCH_STUCK_SAMPLES) + 1 {
            assert!(c.touch_stuck());
        }
        stuck_seen |= c.touch_stuck();
    }
    assert!(stuck_seen);
    assert!(!c.touch_stuck());
    assert_eq!(c.0.held[1], 0);
}

/// One step of both machines; panics on any difference.
fn step_both(
    rust: &mut TargetMachine,
    c: &mut CTarget,
    i2stat: u8,
    rx: u8,
    context: &str,
) -> StepResult {
    let expected = rust.step(BusEvent::from_i2stat(i2stat, rx));
    let got = c.step(i2stat, rx);
    assert_eq!(
        got, expected,
        "{context}: i2stat {i2stat:#04x} rx {rx:#04x}"
    );
    assert_eq!(
        c.0,
        mirror(rust.state()),
        "{context}: i2stat {i2stat:#04x} rx {rx:#04x}"
    );
    expected
}

const WRITE_CODES: [u8; 4] = [0x60, 0x68, 0x70, 0x78];
const ACKED_CODES: [u8; 2] = [0x80, 0x90];
const NACKED_CODES: [u8; 2] = [0x88, 0x98];
const READ_CODES: [u8; 2] = [0xA8, 0xB0];
const DONE_CODES: [u8; 2] = [0xC0, 0xC8];

fn pick(rng: &mut StdRng, codes: &[u8]) -> u8 {
    codes[rng.random_range(0..codes.len())]
}

/// A register number: mostly the known ones, sometimes anything.
fn random_register(rng: &mut StdRng) -> u8 {
    if rng.random_bool(0.8) {
        [0x00, 0x01, 0x02, 0x03, 0x10][rng.random_range(0..5)]
    } else {
        rng.random()
    }
}

/// A plausible controller transaction as (I2STAT, rx) pairs, following the target's AA bit
/// for ACK/NACK of written bytes as the hardware does; the machine is stepped as it goes.
fn plausible_transaction(
    rng: &mut StdRng,
    rust: &mut TargetMachine,
    c: &mut CTarget,
    context: &str,
) {
    let kind = rng.random_range(0..6);
    if kind < 3 {
        // A write: register, assignment (right or wrong complement, good or bad address),
        // or random bytes; sometimes truncated or over-long.
        let mut bytes: Vec<u8> = match kind {
            0 => vec![random_register(rng)],
            1 => {
                let address: u8 = if rng.random_bool(0.7) {
                    rng.random_range(0x08..=0x77)
                } else {
                    rng.random()
                };
                let complement = if rng.random_bool(0.7) {
                    !address
                } else {
                    rng.random()
                };
                vec![0x10, address, complement]
            }
            _ => (0..rng.random_range(0..6)).map(|_| rng.random()).collect(),
        };
        if rng.random_bool(0.1) {
            bytes.push(rng.random());
        }
        if rng.random_bool(0.1) && !bytes.is_empty() {
            bytes.pop();
        }
        let mut ack = step_both(rust, c, pick(rng, &WRITE_CODES), rng.random(), context).ack_next;
        for byte in bytes {
            let code = if ack {
                pick(rng, &ACKED_CODES)
            } else {
                pick(rng, &NACKED_CODES)
            };
            ack = step_both(rust, c, code, byte, context).ack_next;
        }
        // STOP, a repeated START (also 0xA0), or rarely a bus error.
        let end = if rng.random_bool(0.95) { 0xA0 } else { 0x00 };
        step_both(rust, c, end, rng.random(), context);
    } else {
        // A read of 1..=5 bytes, ended by ReadDone or STOP.
        let n = rng.random_range(1..=5);
        step_both(rust, c, pick(rng, &READ_CODES), rng.random(), context);
        for _ in 1..n {
            step_both(rust, c, 0xB8, rng.random(), context);
        }
        let end = if rng.random_bool(0.85) {
            pick(rng, &DONE_CODES)
        } else {
            0xA0
        };
        step_both(rust, c, end, rng.random(), context);
    }
}

/// Any code: the target-mode ones weighted up, plus anything else.
fn random_code(rng: &mut StdRng) -> u8 {
    const TARGET_CODES: [u8; 15] = [
        0x60, 0x68, 0x70, 0x78, 0x80, 0x90, 0x88, 0x98, 0xA0, 0xA8, 0xB0, 0xB8, 0xC0, 0xC8, 0x00,
    ];
    if rng.random_bool(0.85) {
        pick(rng, &TARGET_CODES)
    } else {
        rng.random()
    }
}

#[test]
fn the_target_matches_on_random_event_sequences() {
    let mut rng = StdRng::seed_from_u64(5);
    let mut address_changes = 0;
    for sequence in 0..20_000 {
        let address: u8 = if rng.random_bool(0.5) {
            0x77
        } else {
            rng.random()
        };
        let address_set = rng.random_bool(0.5);
        let mut rust = TargetMachine::new(address, address_set);
        let mut c = CTarget::new(address, address_set);
        assert_eq!(
            c.0,
            mirror(rust.state()),
            "init {address:#04x} {address_set}"
        );
        let pure_random = sequence % 4 == 3;
        for event in 0..60 {
            let context = format!("sequence {sequence} event {event}");
            if rng.random_bool(0.15) {
                let word: u16 = rng.random();
                let status: u8 = rng.random();
                rust.publish(SampleWord::from_raw(word), StatusFlags::from_bits(status));
                c.publish(word, status);
                assert_eq!(c.0, mirror(rust.state()), "{context}: publish");
            } else if pure_random {
                let code = random_code(&mut rng);
                let result = step_both(&mut rust, &mut c, code, rng.random(), &context);
                address_changes += usize::from(result.address_changed);
            } else {
                let before = rust.address();
                plausible_transaction(&mut rng, &mut rust, &mut c, &context);
                address_changes += usize::from(rust.address() != before);
            }
        }
    }
    // The sequences reached the assignment path.
    assert!(address_changes > 1_000, "{address_changes}");
}
