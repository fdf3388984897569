//! `Segment::serve`: transaction-level controller scripts through the fake target peripheral,
//! translated into the state machine's bus events.
#![allow(clippy::unwrap_used)]

mod common;

use antenna_protocol::{
    AddressAssignment, DEFAULT_ADDRESS, FIRMWARE_VERSION, SampleWord, StatusFlags, pec,
};
use common::{
    ASSIGNED_ADDRESS, FakeAdc, FakeBus, FakeError, FakeStore, FakeTouch, MID_SCALE, Scripted,
};
use firmware_segment::{Parts, Segment, SegmentError, Served, TargetRequest};

type TestSegment = Segment<FakeAdc, FakeTouch, FakeBus, FakeStore>;

/// A segment with one sample published (angle 2048, no touch) and the bus scripted.
fn segment(script: Vec<Scripted>, store: FakeStore) -> TestSegment {
    let mut adc = FakeAdc::new();
    adc.push_constant(MID_SCALE, 1);
    let mut segment = Segment::new(Parts {
        adc,
        touch: FakeTouch::default(),
        i2c: FakeBus::new(script),
        store,
    })
    .unwrap();
    segment.sample().unwrap();
    segment
}

fn serve_all(segment: &mut TestSegment) -> Vec<Served> {
    let mut served = Vec::new();
    loop {
        match segment.serve().unwrap() {
            Served::Nothing => return served,
            other => served.push(other),
        }
    }
}

#[test]
fn nothing_pending_serves_nothing() {
    let mut segment = segment(vec![], FakeStore::default());
    assert_eq!(segment.serve(), Ok(Served::Nothing));
}

#[test]
fn plain_and_pec_reads_return_the_word() {
    let mut segment = segment(
        vec![Scripted::Read(2), Scripted::Read(3), Scripted::Read(5)],
        FakeStore::default(),
    );
    assert_eq!(
        serve_all(&mut segment),
        vec![
            Served::Read { sent: 2 },
            Served::Read { sent: 3 },
            Served::Read { sent: 5 }
        ]
    );
    let reads = segment.destroy().i2c.reads;
    assert_eq!(reads[0], vec![0x80, 0x00]);
    let word =
        SampleWord::from_read_with_pec(DEFAULT_ADDRESS, [reads[1][0], reads[1][1], reads[1][2]]);
    assert_eq!(word, Ok(SampleWord::pack_truncate(2048, 0)));
    assert_eq!(&reads[2][3..], &[0xFF, 0xFF]);
}

#[test]
fn register_reads_and_the_pointer_reset() {
    let mut segment = segment(
        vec![
            Scripted::Write(vec![0x01]),
            Scripted::Read(3),
            Scripted::Write(vec![0x02]),
            Scripted::Read(2),
            Scripted::Write(vec![0x03]),
            Scripted::Read(2),
            Scripted::Read(2),
        ],
        FakeStore::default(),
    );
    serve_all(&mut segment);
    let reads = segment.destroy().i2c.reads;
    let with_pec = |data: &[u8]| {
        let mut message = vec![pec::read_address_byte(DEFAULT_ADDRESS)];
        message.extend_from_slice(data);
        let mut out = data.to_vec();
        out.push(pec::compute(&message));
        out
    };
    assert_eq!(
        reads[0],
        with_pec(&[FIRMWARE_VERSION.0, FIRMWARE_VERSION.1])
    );
    assert_eq!(reads[1], with_pec(&[StatusFlags::ADDRESS_NOT_SET]));
    assert_eq!(reads[2], with_pec(&[1]));
    // The pointer went back to the word after the counter read.
    assert_eq!(reads[3], vec![0x80, 0x00]);
}

#[test]
fn an_assignment_is_persisted_and_programmed() {
    let message = AddressAssignment::new(ASSIGNED_ADDRESS).unwrap().to_bytes();
    let mut segment = segment(
        vec![Scripted::Write(message.to_vec()), Scripted::Read(3)],
        FakeStore::default(),
    );
    assert_eq!(
        serve_all(&mut segment),
        vec![
            Served::AddressChanged {
                address: ASSIGNED_ADDRESS
            },
            Served::Read { sent: 3 }
        ]
    );
    assert_eq!(segment.address(), ASSIGNED_ADDRESS);
    let parts = segment.destroy();
    assert_eq!(parts.store.stored, Some(ASSIGNED_ADDRESS));
    assert_eq!(parts.i2c.address, Some(ASSIGNED_ADDRESS));
    let r = &parts.i2c.reads[0];
    assert!(SampleWord::from_read_with_pec(ASSIGNED_ADDRESS, [r[0], r[1], r[2]]).is_ok());
}

#[test]
fn an_assignment_that_cannot_be_persisted_keeps_the_old_address() {
    let message = AddressAssignment::new(ASSIGNED_ADDRESS).unwrap().to_bytes();
    let store = FakeStore {
        fail_store: true,
        ..FakeStore::default()
    };
    let mut segment = segment(vec![Scripted::Write(message.to_vec())], store);
    let before = *segment.target();
    assert_eq!(segment.serve(), Err(SegmentError::Store(FakeError)));
    assert_eq!(*segment.target(), before);
    assert_eq!(segment.destroy().i2c.address, Some(DEFAULT_ADDRESS));
}

#[test]
fn bad_writes_change_nothing() {
    let bad = [
        vec![0x42],                                         // unknown register
        vec![0x42, 0x01, 0x02, 0x03],                       // unknown register, over-long
        vec![0x00, 0x01],                                   // over-long to a read-only register
        vec![0x10, ASSIGNED_ADDRESS, ASSIGNED_ADDRESS],     // wrong complement
        vec![0x10, 0x78, !0x78],                            // unassignable
        vec![0x10, ASSIGNED_ADDRESS],                       // incomplete
        vec![0x10, ASSIGNED_ADDRESS, !ASSIGNED_ADDRESS, 0], // over-long assignment
        vec![],                                             // empty write
    ];
    for bytes in bad {
        let mut segment = segment(vec![Scripted::Write(bytes.clone())], FakeStore::default());
        let before = *segment.target();
        assert_eq!(
            segment.serve(),
            Ok(Served::Write {
                received: bytes.len()
            })
        );
        assert_eq!(*segment.target(), before, "{bytes:02x?}");
        assert_eq!(segment.destroy().store.stored, None);
    }
}

#[test]
fn a_peripheral_failure_drops_the_transfer() {
    let mut segment = segment(
        vec![
            Scripted::Write(vec![0x03]),
            Scripted::Fail(TargetRequest::Write),
            Scripted::Fail(TargetRequest::Read),
        ],
        FakeStore::default(),
    );
    segment.serve().unwrap();
    let before = *segment.target();
    assert_eq!(segment.serve(), Err(SegmentError::I2c(FakeError)));
    assert_eq!(*segment.target(), before);
    // A failed read drops the read; the pointer stays.
    assert_eq!(segment.serve(), Err(SegmentError::I2c(FakeError)));
    assert_eq!(*segment.target(), before);
    assert_eq!(segment.target().pointer(), 0x03);
}
