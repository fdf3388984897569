//! `Segment::sample` end to end: scripted ADC conversions and mock touch pins in, the
//! published word, status and counter out.
#![allow(clippy::unwrap_used)]

mod common;

use antenna_protocol::{DEFAULT_ADDRESS, SampleWord, StatusFlags};
use common::{
    ASSIGNED_ADDRESS, FakeAdc, FakeBus, FakeError, FakeStore, FakeTouch, MID_SCALE, pins_done,
    touch_pins,
};
use embedded_hal::digital::ErrorKind;
use embedded_hal_mock::eh1::MockError;
use embedded_hal_mock::eh1::digital::{Mock as PinMock, State, Transaction};
use firmware_segment::{
    OVERSAMPLE_COUNT, Parts, Segment, SegmentError, TOUCH_STUCK_SAMPLES, TouchPins,
};

fn parts<T>(adc: FakeAdc, touch: T, store: FakeStore) -> Parts<FakeAdc, T, FakeBus, FakeStore> {
    Parts {
        adc,
        touch,
        i2c: FakeBus::default(),
        store,
    }
}

#[test]
fn a_sample_oversamples_checks_rails_debounces_and_publishes() {
    let mut adc = FakeAdc::new();
    // 16 conversions 100..=115 with junk above bit 9: sum 1720, >> 2 = 430.
    let mut conversions = [0u16; OVERSAMPLE_COUNT];
    for (i, c) in conversions.iter_mut().enumerate() {
        *c = 0xFC00 | (100 + i as u16);
    }
    adc.push_sample(conversions);
    adc.push_sample(conversions);
    // The third sample has one conversion on the upper rail.
    conversions[5] = 1023;
    adc.push_sample(conversions);
    let raw_touch = [0b0110, 0b0110, 0b0110];
    let mut segment =
        Segment::new(parts(adc, touch_pins(&raw_touch), FakeStore::default())).unwrap();
    assert_eq!(segment.address(), DEFAULT_ADDRESS);

    let first = segment.sample().unwrap();
    assert_eq!(first.word, SampleWord::pack_truncate(430, 0));
    assert_eq!(
        first.status,
        StatusFlags::from_bits(StatusFlags::ADDRESS_NOT_SET)
    );
    segment.sample().unwrap();
    let third = segment.sample().unwrap();
    // 1720 - 105 + 1023 = 2638, >> 2 = 659; the touch bits are stable after three reads.
    assert_eq!(third.word, SampleWord::pack_truncate(659, 0b0110));
    assert_eq!(
        third.status,
        StatusFlags::from_bits(StatusFlags::ADC_FAULT | StatusFlags::ADDRESS_NOT_SET)
    );
    assert_eq!(segment.target().word(), third.word);
    assert_eq!(segment.target().status(), third.status);
    assert_eq!(segment.target().counter(), 3);

    let parts = segment.destroy();
    assert!(parts.adc.conversions.is_empty());
    pins_done(parts.touch);
}

#[test]
fn a_segment_with_a_stored_address_has_status_bit_two_clear() {
    let mut adc = FakeAdc::new();
    adc.push_constant(MID_SCALE, 1);
    let store = FakeStore {
        stored: Some(ASSIGNED_ADDRESS),
        ..FakeStore::default()
    };
    let mut segment = Segment::new(parts(adc, touch_pins(&[0]), store)).unwrap();
    assert_eq!(segment.address(), ASSIGNED_ADDRESS);
    let sample = segment.sample().unwrap();
    assert_eq!(sample.word, SampleWord::pack_truncate(2048, 0));
    assert_eq!(sample.status, StatusFlags::default());
    let parts = segment.destroy();
    assert_eq!(parts.i2c.address, Some(ASSIGNED_ADDRESS));
    pins_done(parts.touch);
}

#[test]
fn an_unassignable_stored_address_falls_back_to_the_default() {
    for stored in [0x00, 0x78, 0xFF] {
        let store = FakeStore {
            stored: Some(stored),
            ..FakeStore::default()
        };
        let segment = Segment::new(parts(FakeAdc::new(), FakeTouch::default(), store)).unwrap();
        assert_eq!(segment.address(), DEFAULT_ADDRESS);
        assert!(!segment.target().address_set());
    }
}

#[test]
fn a_bounce_is_rejected_and_three_agreeing_reads_are_accepted() {
    // Bit 0 bounces (1, 0, 1, 1, 0, 1) and never settles; bit 2 settles at the third 1.
    let raw = [0b0001, 0b0100, 0b0101, 0b0101, 0b0100, 0b0001];
    let expected_touch = [0, 0, 0, 0b0100, 0b0100, 0b0100];
    let mut adc = FakeAdc::new();
    adc.push_constant(MID_SCALE, raw.len());
    let mut segment = Segment::new(parts(adc, touch_pins(&raw), FakeStore::default())).unwrap();
    for (i, expected) in expected_touch.iter().enumerate() {
        let sample = segment.sample().unwrap();
        assert_eq!(sample.word.touch().bits(), *expected, "sample {i}");
    }
    pins_done(segment.destroy().touch);
}

#[test]
fn touch_stuck_sets_after_a_minute_of_contact() {
    let mut adc = FakeAdc::new();
    adc.push_constant(MID_SCALE, usize::from(TOUCH_STUCK_SAMPLES) + 2);
    let touch = FakeTouch { raw: 0b1000 };
    let mut segment = Segment::new(parts(adc, touch, FakeStore::default())).unwrap();
    // Two reads to settle; the third makes the bit stable and it counts from 1.
    for _ in 0..usize::from(TOUCH_STUCK_SAMPLES) + 1 {
        let sample = segment.sample().unwrap();
        assert!(!sample.status.touch_stuck());
    }
    assert_eq!(segment.debouncer().held()[3], TOUCH_STUCK_SAMPLES - 1);
    let sample = segment.sample().unwrap();
    assert!(sample.status.touch_stuck());
    assert_eq!(segment.target().status(), sample.status);
    assert_eq!(segment.debouncer().held()[3], TOUCH_STUCK_SAMPLES);
}

#[test]
fn touch_stuck_clears_when_the_switch_releases() {
    let mut adc = FakeAdc::new();
    let samples = usize::from(TOUCH_STUCK_SAMPLES) + 10;
    adc.push_constant(MID_SCALE, samples + 3);
    let raw: Vec<u8> = std::iter::repeat_n(0b0001, samples)
        .chain([0, 0, 0])
        .collect();
    let mut segment = Segment::new(parts(adc, touch_pins(&raw), FakeStore::default())).unwrap();
    let mut stuck = Vec::new();
    for _ in 0..raw.len() {
        stuck.push(segment.sample().unwrap().status.touch_stuck());
    }
    assert!(!stuck[usize::from(TOUCH_STUCK_SAMPLES)]);
    assert!(stuck[usize::from(TOUCH_STUCK_SAMPLES) + 1]);
    assert!(stuck[samples - 1]);
    // The first two zero reads do not release the debounced bit; the third does.
    assert_eq!(&stuck[samples..], &[true, true, false]);
    pins_done(segment.destroy().touch);
}

#[test]
fn the_counter_wraps_after_256_samples() {
    let mut adc = FakeAdc::new();
    adc.push_constant(MID_SCALE, 257);
    let mut segment = Segment::new(parts(adc, FakeTouch::default(), FakeStore::default())).unwrap();
    for _ in 0..255 {
        segment.sample().unwrap();
    }
    assert_eq!(segment.target().counter(), 255);
    segment.sample().unwrap();
    assert_eq!(segment.target().counter(), 0);
    segment.sample().unwrap();
    assert_eq!(segment.target().counter(), 1);
}

#[test]
fn a_failed_conversion_publishes_nothing() {
    let mut adc = FakeAdc::new();
    adc.push_constant(MID_SCALE, 1);
    adc.conversions.extend([MID_SCALE; 7]); // runs out mid-sample
    let mut segment = Segment::new(parts(adc, touch_pins(&[0]), FakeStore::default())).unwrap();
    segment.sample().unwrap();
    let before = *segment.target();
    assert_eq!(segment.sample(), Err(SegmentError::Adc(FakeError)));
    assert_eq!(*segment.target(), before);
    pins_done(segment.destroy().touch);
}

#[test]
fn a_failed_pin_read_is_reported_and_publishes_nothing() {
    let mut adc = FakeAdc::new();
    adc.push_constant(MID_SCALE, 1);
    let good = |state| PinMock::new(&[Transaction::get(state)]);
    let failing = PinMock::new(&[
        Transaction::get(State::High).with_error(MockError::Io(std::io::ErrorKind::Other))
    ]);
    // Pin 2 fails: pin 3 is never read.
    let pins = TouchPins::new([
        good(State::High),
        good(State::Low),
        failing,
        PinMock::new(&[]),
    ]);
    let mut segment = Segment::new(parts(adc, pins, FakeStore::default())).unwrap();
    assert_eq!(segment.sample(), Err(SegmentError::Touch(ErrorKind::Other)));
    assert_eq!(segment.target().counter(), 0);
    pins_done(segment.destroy().touch);
}

#[test]
fn a_failed_address_load_hands_the_peripherals_back() {
    let store = FakeStore {
        fail_load: true,
        ..FakeStore::default()
    };
    let pins: TouchPins<PinMock> = touch_pins(&[]);
    let failure = Segment::new(parts(FakeAdc::new(), pins, store)).unwrap_err();
    assert_eq!(failure.error, SegmentError::Store(FakeError));
    assert!(failure.parts.store.fail_load);
    pins_done(failure.parts.touch);
}
