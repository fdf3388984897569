//! The I2C target state machine at byte level: reads, registers, address assignment, and every
//! row of the README's bad-input table (the answer, and that no state changes).
#![allow(clippy::unwrap_used)]

mod common;

use antenna_protocol::{
    AddressAssignment, DEFAULT_ADDRESS, FIRMWARE_VERSION, SampleWord, StatusFlags, pec,
};
use common::{ASSIGNED_ADDRESS, read, write};
use firmware_segment::{BusEvent, IDLE_BYTE, Phase, TargetMachine};

/// A machine at the default address with one sample published: word 0x8009 (angle 2048,
/// touch 0b1001), ADC fault set, counter 1.
fn published() -> TargetMachine {
    let mut target = TargetMachine::new(DEFAULT_ADDRESS, false);
    target.publish(
        SampleWord::pack_truncate(2048, 0b1001),
        StatusFlags::from_bits(StatusFlags::ADC_FAULT | StatusFlags::ADDRESS_NOT_SET),
    );
    target
}

fn pec_over(address: u8, data: &[u8]) -> u8 {
    let mut bytes = vec![pec::read_address_byte(address)];
    bytes.extend_from_slice(data);
    pec::compute(&bytes)
}

#[test]
fn plain_two_byte_read_returns_the_word() {
    let mut target = published();
    assert_eq!(read(&mut target, 2), vec![0x80, 0x09]);
    assert_eq!(target.phase(), Phase::Idle);
}

#[test]
fn three_byte_read_returns_the_word_and_its_pec() {
    let mut target = published();
    let bytes = read(&mut target, 3);
    let word = SampleWord::from_read_with_pec(DEFAULT_ADDRESS, [bytes[0], bytes[1], bytes[2]]);
    assert_eq!(word, Ok(SampleWord::pack_truncate(2048, 0b1001)));
}

#[test]
fn register_reads_return_version_status_and_counter_with_pec() {
    let mut target = published();
    for _ in 0..4 {
        target.publish(SampleWord::from_raw(0x1234), StatusFlags::from_bits(0));
    }
    let version = [FIRMWARE_VERSION.0, FIRMWARE_VERSION.1];
    let expected: [(u8, Vec<u8>); 4] = [
        (0x00, vec![0x12, 0x34]),
        (0x01, version.to_vec()),
        // Bit 2 comes from address_set at the read, not from the published status.
        (0x02, vec![StatusFlags::ADDRESS_NOT_SET]),
        (0x03, vec![5]),
    ];
    for (register, data) in expected {
        let answer = write(&mut target, &[register]);
        assert_eq!(answer.acked, vec![true]);
        assert_eq!(target.pointer(), register);
        let mut with_pec = data.clone();
        with_pec.push(pec_over(DEFAULT_ADDRESS, &data));
        assert_eq!(
            read(&mut target, data.len() + 1),
            with_pec,
            "register {register}"
        );
    }
}

#[test]
fn status_read_clears_bit_two_once_the_address_is_set() {
    let mut target = TargetMachine::new(ASSIGNED_ADDRESS, true);
    target.publish(SampleWord::from_raw(0), StatusFlags::from_bits(0b111));
    write(&mut target, &[0x02]);
    let bytes = read(&mut target, 2);
    assert_eq!(bytes, vec![0b011, pec_over(ASSIGNED_ADDRESS, &[0b011])]);
}

#[test]
fn the_pointer_returns_to_the_word_after_a_read() {
    let mut target = published();
    write(&mut target, &[0x03]);
    assert_eq!(read(&mut target, 1), vec![1]);
    assert_eq!(target.pointer(), 0x00);
    assert_eq!(read(&mut target, 2), vec![0x80, 0x09]);
    // Also when the read ends with STOP instead of ReadDone.
    write(&mut target, &[0x01]);
    target.step(BusEvent::StartRead);
    target.step(BusEvent::Stop);
    assert_eq!(target.pointer(), 0x00);
}

#[test]
fn the_read_latches_at_its_start() {
    let mut target = published();
    let first = target.step(BusEvent::StartRead).tx;
    target.publish(SampleWord::from_raw(0xFFFF), StatusFlags::default());
    let second = target.step(BusEvent::ByteAcked).tx;
    assert_eq!([first, second], [0x80, 0x09]);
}

#[test]
fn the_counter_wraps() {
    let mut target = TargetMachine::new(DEFAULT_ADDRESS, false);
    for _ in 0..255 {
        target.publish(SampleWord::default(), StatusFlags::default());
    }
    assert_eq!(target.counter(), 255);
    target.publish(SampleWord::default(), StatusFlags::default());
    assert_eq!(target.counter(), 0);
}

#[test]
fn a_good_assignment_moves_the_segment() {
    let mut target = published();
    let message = AddressAssignment::new(ASSIGNED_ADDRESS).unwrap().to_bytes();
    let answer = write(&mut target, &message);
    assert_eq!(answer.acked, vec![true, true, true]);
    assert!(answer.stop.address_changed);
    assert_eq!(target.address(), ASSIGNED_ADDRESS);
    assert!(target.address_set());
    // The next read's PEC is over the new address.
    let bytes = read(&mut target, 3);
    assert!(
        SampleWord::from_read_with_pec(ASSIGNED_ADDRESS, [bytes[0], bytes[1], bytes[2]]).is_ok()
    );
}

/// Runs `bytes` as a write and checks nothing at all changed.
fn assert_write_changes_nothing(bytes: &[u8]) -> common::WriteAnswer {
    let mut target = published();
    let before = target;
    let answer = write(&mut target, bytes);
    assert!(!answer.stop.address_changed, "{bytes:02x?}");
    assert!(answer.stop.ack_next);
    assert_eq!(answer.stop.tx, IDLE_BYTE);
    assert_eq!(target, before, "{bytes:02x?}");
    answer
}

#[test]
fn an_assignment_with_a_wrong_complement_is_acked_and_changes_nothing() {
    for complement in [0x00, 0xFF, !ASSIGNED_ADDRESS ^ 0x01, ASSIGNED_ADDRESS] {
        let answer = assert_write_changes_nothing(&[0x10, ASSIGNED_ADDRESS, complement]);
        assert_eq!(answer.acked, vec![true, true, true]);
    }
}

#[test]
fn an_unassignable_address_is_acked_and_changes_nothing() {
    for address in [0x00, 0x07, 0x78, 0x7F, 0x80, 0xFF] {
        let answer = assert_write_changes_nothing(&[0x10, address, !address]);
        assert_eq!(answer.acked, vec![true, true, true], "{address:#04x}");
    }
}

#[test]
fn an_incomplete_assignment_changes_nothing() {
    assert_write_changes_nothing(&[0x10]);
    assert_write_changes_nothing(&[0x10, ASSIGNED_ADDRESS]);
    assert_write_changes_nothing(&[]);
}

#[test]
fn an_over_long_assignment_has_its_extra_byte_nacked_and_changes_nothing() {
    let answer = assert_write_changes_nothing(&[0x10, ASSIGNED_ADDRESS, !ASSIGNED_ADDRESS, 0x00]);
    assert_eq!(answer.acked, vec![true, true, true, false]);
    // Even if the hardware had ACKed the fourth byte.
    let mut target = published();
    let before = target;
    target.step(BusEvent::StartWrite);
    for byte in [0x10, ASSIGNED_ADDRESS, !ASSIGNED_ADDRESS, 0x00] {
        target.step(BusEvent::DataAcked(byte));
    }
    assert!(!target.step(BusEvent::Stop).address_changed);
    assert_eq!(target, before);
}

// The README's bad-input table, row by row.

#[test]
fn bad_input_unknown_register_acks_that_byte_nacks_later_ones_and_changes_nothing() {
    for register in [0x04, 0x0F, 0x11, 0x55, 0xFF] {
        let answer = assert_write_changes_nothing(&[register, 0x01, 0x02]);
        assert_eq!(answer.acked, vec![true, false, false], "{register:#04x}");
        let answer = assert_write_changes_nothing(&[register]);
        assert_eq!(answer.acked, vec![true]);
    }
    // The next read returns what it would have: after a pointer write, still that register.
    let mut target = published();
    write(&mut target, &[0x03]);
    let before = target;
    write(&mut target, &[0x42]);
    assert_eq!(target, before);
    assert_eq!(read(&mut target, 1), vec![1]);
}

#[test]
fn bad_input_over_long_write_nacks_the_extra_bytes_and_changes_nothing() {
    for register in [0x00, 0x01, 0x02, 0x03] {
        let answer = assert_write_changes_nothing(&[register, 0x10]);
        assert_eq!(answer.acked, vec![true, false], "{register:#04x}");
        let answer = assert_write_changes_nothing(&[register, 0x00, 0x00]);
        assert_eq!(answer.acked, vec![true, false, false]);
    }
    // A pointer already set survives an over-long write.
    let mut target = published();
    write(&mut target, &[0x01]);
    let before = target;
    write(&mut target, &[0x02, 0x00]);
    assert_eq!(target, before);
    assert_eq!(target.pointer(), 0x01);
}

#[test]
fn bad_input_read_past_the_end_returns_0xff_and_changes_nothing() {
    let mut target = published();
    let before = target;
    let bytes = read(&mut target, 6);
    assert_eq!(&bytes[3..], &[IDLE_BYTE; 3]);
    assert_eq!(target, before);
    // The bytes before the end are the normal read's.
    let mut twin = published();
    assert_eq!(&bytes[..3], read(&mut twin, 3).as_slice());
    // A counter read past the end.
    let mut target = published();
    write(&mut target, &[0x03]);
    target.step(BusEvent::StartRead);
    target.step(BusEvent::ByteAcked);
    let during = target;
    let past = target.step(BusEvent::ByteAcked);
    assert_eq!(past.tx, IDLE_BYTE);
    assert!(past.ack_next);
    assert_eq!(target, during);
}

#[test]
fn bad_input_wrong_complement_is_acked_and_changes_nothing() {
    let answer = assert_write_changes_nothing(&[0x10, 0x30, 0x30]);
    assert_eq!(answer.acked, vec![true, true, true]);
}

#[test]
fn a_bus_error_drops_the_write_and_keeps_the_pointer() {
    let mut target = published();
    write(&mut target, &[0x02]);
    let before = target;
    target.step(BusEvent::StartWrite);
    for byte in [0x10, ASSIGNED_ADDRESS, !ASSIGNED_ADDRESS] {
        target.step(BusEvent::DataAcked(byte));
    }
    let result = target.step(BusEvent::BusError);
    assert!(result.ack_next && !result.address_changed);
    assert_eq!(target, before);
}

#[test]
fn events_out_of_place_change_nothing() {
    let mut target = published();
    let before = target;
    for event in [
        BusEvent::DataAcked(0x10),
        BusEvent::DataNacked(0x10),
        BusEvent::ByteAcked,
        BusEvent::Other,
        BusEvent::from_i2stat(0xF8, 0),
        BusEvent::Stop,
    ] {
        let result = target.step(event);
        assert_eq!(
            (result.tx, result.ack_next, result.address_changed),
            (IDLE_BYTE, true, false)
        );
        assert_eq!(target, before, "{event:?}");
    }
}
