//! A poll's readings as the recording's samples ([`antenna_data::record::SegmentSample`]) and
//! the stream's ([`antenna_data::stream::SegmentSample`]): each angle from its segment's
//! calibration, each failure named.

use antenna_data::{record, stream};
use antenna_protocol::Calibration;

use crate::{PollError, SegmentReading};

/// The recorded sample of one poll reading, its angle from `calibration`; `stale` as the
/// acquisition judged it.
pub fn record_sample(
    reading: &SegmentReading,
    calibration: Calibration,
    stale: bool,
) -> record::SegmentSample {
    let mut sample = record::SegmentSample {
        address: reading.address,
        angle_counts: None,
        angle_rad: None,
        touch: None,
        ok: false,
        nack: false,
        pec_error: false,
        bus_error: false,
        stale,
    };
    match &reading.result {
        Ok(word) => {
            sample.ok = true;
            sample.angle_counts = Some(word.angle_counts());
            sample.angle_rad = Some(calibration.angle_rad(word.angle_counts()));
            sample.touch = Some(word.touch().bits());
        }
        Err(PollError::Nack { .. }) => sample.nack = true,
        Err(PollError::Corrupted { .. }) => sample.pec_error = true,
        Err(PollError::Bus { .. }) => sample.bus_error = true,
    }
    sample
}

/// The streamed sample of one poll reading, its angle from `calibration`.
pub fn stream_sample(
    reading: &SegmentReading,
    calibration: Calibration,
    stale: bool,
) -> stream::SegmentSample {
    match reading.result {
        Ok(word) => stream::SegmentSample {
            address: reading.address,
            angle_rad: Some(calibration.angle_rad(word.angle_counts())),
            contact: Some(word.touch().any()),
            touch_bits: Some(word.touch().bits()),
            counter: None,
            error: None,
            stale,
        },
        Err(e) => stream::SegmentSample {
            address: reading.address,
            angle_rad: None,
            contact: None,
            touch_bits: None,
            counter: None,
            error: Some(
                match e {
                    PollError::Nack { .. } => "nack",
                    PollError::Corrupted { .. } => "pec",
                    PollError::Bus { .. } => "bus",
                }
                .to_owned(),
            ),
            stale,
        },
    }
}
