//! A virtual I2C bus whose segments run the firmware's own logic.

use antenna_protocol::{Calibration, DEFAULT_ADDRESS, SampleWord, StatusFlags, TouchBits};
use embedded_hal::i2c::{ErrorKind, ErrorType, I2c, NoAcknowledgeSource, Operation};
use firmware_segment::{BusEvent, Debouncer, TargetMachine, adc_fault, oversample};

use crate::hall_sensor::HallSensor;

/// An error on the simulated bus, as a real bus would report it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum SimBusError {
    /// No segment answers at the address.
    #[error("no segment acknowledged address {0:#04x}")]
    AddressNack(u8),
    /// The segment did not acknowledge a data byte (an over-long or refused write).
    #[error("segment {0:#04x} did not acknowledge a data byte")]
    DataNack(u8),
}

impl embedded_hal::i2c::Error for SimBusError {
    fn kind(&self) -> ErrorKind {
        match self {
            SimBusError::AddressNack(_) => ErrorKind::NoAcknowledge(NoAcknowledgeSource::Address),
            SimBusError::DataNack(_) => ErrorKind::NoAcknowledge(NoAcknowledgeSource::Data),
        }
    }
}

/// A fault injected into one simulated segment, for testing how the host copes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SegmentFault {
    /// The segment behaves.
    #[default]
    None,
    /// The segment does not acknowledge its address (a NACK storm while it lasts).
    Nack,
    /// Reads come back with the last byte (the PEC of a 3-byte read) bit-flipped, as a
    /// corrupted transfer would.
    CorruptPec,
    /// The segment's main loop has stopped: its I2C target still answers with the last word,
    /// but no new sample is published, so its sample counter stops moving.
    StuckCounter,
    /// The angle sensor's output sits on a rail (the Hall sensor's diagnostic clamp or a
    /// broken wire): every conversion reads 0, so the firmware sets its ADC-fault status bit.
    SensorRail,
    /// A transfer addressed to the segment never returns: the calling thread blocks for
    /// good, as on a bus a segment holds low behind a driver without a timeout (the stuck
    /// ioctl the daemon's watchdog is for).
    Hang,
}

/// One simulated segment: a physical joint angle and touch switches, sampled by the
/// firmware's oversampling and debouncing and served by its I2C target state machine. Its
/// Hall sensor is ideal unless given one as it is ([`SimSegment::with_hall_sensor`]).
#[derive(Debug, Clone)]
pub struct SimSegment {
    machine: TargetMachine,
    debouncer: Debouncer,
    calibration: Calibration,
    hall: HallSensor,
    angle_rad: f64,
    touch_raw: u8,
    fault: SegmentFault,
}

impl SimSegment {
    /// A segment already assigned to `address`, whose magnet reads `calibration`.
    pub fn new(address: u8, calibration: Calibration) -> Self {
        Self {
            machine: TargetMachine::new(address, true),
            debouncer: Debouncer::new(),
            calibration,
            hall: HallSensor::ideal(),
            angle_rad: 0.0,
            touch_raw: 0,
            fault: SegmentFault::None,
        }
    }

    /// A segment fresh from programming: no address stored, so it answers at
    /// [`DEFAULT_ADDRESS`] with its address-not-set status bit until one is assigned.
    pub fn unassigned(calibration: Calibration) -> Self {
        Self {
            machine: TargetMachine::new(DEFAULT_ADDRESS, false),
            ..Self::new(DEFAULT_ADDRESS, calibration)
        }
    }

    /// The segment with `hall` as its Hall sensor and ADC: calibration errors and seeded
    /// noise on each conversion ([`crate::hall_sensor`]).
    pub fn with_hall_sensor(mut self, hall: HallSensor) -> Self {
        self.hall = hall;
        self
    }

    /// The Hall sensor and ADC.
    pub fn hall_sensor(&self) -> &HallSensor {
        &self.hall
    }

    /// Injects `fault` (or clears it with [`SegmentFault::None`]).
    pub fn set_fault(&mut self, fault: SegmentFault) {
        self.fault = fault;
    }

    /// The fault in force.
    pub fn fault(&self) -> SegmentFault {
        self.fault
    }

    /// Sets the joint angle the Hall sensor sees.
    pub fn set_angle_rad(&mut self, angle_rad: f64) {
        self.angle_rad = angle_rad;
    }

    /// Sets the raw state of the four touch switches (bit 0 most proximal).
    pub fn set_touch(&mut self, touch: TouchBits) {
        self.touch_raw = touch.bits();
    }

    /// The address the segment answers at.
    pub fn address(&self) -> u8 {
        self.machine.address()
    }

    /// One sampling period of the firmware's main loop: 16 conversions of the angle by the
    /// Hall sensor (ideal: they oversample to the angle's count), the touch port read and
    /// debounced, and the sample published.
    pub fn sample(&mut self) {
        if self.fault == SegmentFault::StuckCounter {
            return;
        }
        let conversions = if self.fault == SegmentFault::SensorRail {
            [0; 16]
        } else {
            self.hall.conversions(self.calibration, self.angle_rad)
        };
        let touch = self.debouncer.step(self.touch_raw);
        let word = SampleWord::pack_truncate(oversample(&conversions), touch.bits());
        let status = StatusFlags::default()
            .with(StatusFlags::ADC_FAULT, adc_fault(&conversions))
            .with(StatusFlags::TOUCH_STUCK, self.debouncer.touch_stuck());
        self.machine.publish(word, status);
    }

    fn step(&mut self, event: BusEvent) -> firmware_segment::StepResult {
        self.machine.step(event)
    }
}

/// A virtual I2C bus of [`SimSegment`]s, implementing embedded-hal's [`I2c`] as a controller
/// sees it: every transaction is turned into the bus events the segments' state machines
/// receive (address, data bytes, repeated start, stop).
#[derive(Debug, Clone, Default)]
pub struct SimBus {
    segments: Vec<SimSegment>,
}

impl SimBus {
    /// A bus with these segments on it.
    pub fn new(segments: Vec<SimSegment>) -> Self {
        Self { segments }
    }

    /// The segments, in the order given.
    pub fn segments(&self) -> &[SimSegment] {
        &self.segments
    }

    /// Segment `index` for changing its physical state, or `None` past the end.
    pub fn segment_mut(&mut self, index: usize) -> Option<&mut SimSegment> {
        self.segments.get_mut(index)
    }

    /// One sampling period on every segment.
    pub fn sample_all(&mut self) {
        self.segments.iter_mut().for_each(SimSegment::sample);
    }
}

impl ErrorType for SimBus {
    type Error = SimBusError;
}

impl I2c for SimBus {
    /// Every segment at `address` takes part, as on a real shared bus: each receives the
    /// bytes and answers with its own ACK, the controller sees an ACK when any of them gives
    /// one, and the bytes read are the wired AND of what each sends (open-drain: a 0 wins).
    /// Two segments at one address thus read back garbage whose PEC fails unless their bytes
    /// happen to agree.
    fn transaction(
        &mut self,
        address: u8,
        operations: &mut [Operation<'_>],
    ) -> Result<(), Self::Error> {
        let mut targets: Vec<&mut SimSegment> = self
            .segments
            .iter_mut()
            .filter(|segment| segment.address() == address && segment.fault != SegmentFault::Nack)
            .collect();
        if targets.is_empty() {
            return Err(SimBusError::AddressNack(address));
        }
        let corrupt = targets
            .iter()
            .any(|segment| segment.fault == SegmentFault::CorruptPec);
        if targets
            .iter()
            .any(|segment| segment.fault == SegmentFault::Hang)
        {
            // Nothing can lift the fault from here: the thread that would is this one.
            loop {
                std::thread::park();
            }
        }
        let mut index = 0;
        while index < operations.len() {
            // Adjacent operations of one kind are one transfer (no repeated start between).
            let is_write = matches!(operations[index], Operation::Write(_));
            let mut end = index;
            while end < operations.len()
                && matches!(operations[end], Operation::Write(_)) == is_write
            {
                end += 1;
            }
            if is_write {
                // Each segment's own AA bit: whether it acknowledges the next byte.
                let mut acks: Vec<bool> = targets
                    .iter_mut()
                    .map(|segment| segment.step(BusEvent::StartWrite).ack_next)
                    .collect();
                for operation in &operations[index..end] {
                    if let Operation::Write(bytes) = operation {
                        for &byte in bytes.iter() {
                            let acked = acks.iter().any(|&ack| ack);
                            for (segment, ack) in targets.iter_mut().zip(acks.iter_mut()) {
                                *ack = if *ack {
                                    segment.step(BusEvent::DataAcked(byte)).ack_next
                                } else {
                                    segment.step(BusEvent::DataNacked(byte));
                                    false
                                };
                            }
                            if !acked {
                                for segment in targets.iter_mut() {
                                    segment.step(BusEvent::Stop);
                                }
                                return Err(SimBusError::DataNack(address));
                            }
                        }
                    }
                }
                // A stop, or the repeated start before the next transfer: the same event.
                for segment in targets.iter_mut() {
                    segment.step(BusEvent::Stop);
                }
            } else {
                let mut first = true;
                for operation in &mut operations[index..end] {
                    if let Operation::Read(buffer) = operation {
                        for byte in buffer.iter_mut() {
                            let event = if first {
                                BusEvent::StartRead
                            } else {
                                BusEvent::ByteAcked
                            };
                            first = false;
                            *byte = targets
                                .iter_mut()
                                .fold(0xFF, |wired, segment| wired & segment.step(event).tx);
                        }
                        if corrupt && let Some(last) = buffer.last_mut() {
                            *last ^= 0x5a;
                        }
                    }
                }
                for segment in targets.iter_mut() {
                    if first {
                        // A zero-length read still addresses the segment.
                        segment.step(BusEvent::StartRead);
                    }
                    segment.step(BusEvent::ReadDone);
                }
            }
            index = end;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use antenna_protocol::{AddressAssignment, Direction, Register};

    fn bus() -> SimBus {
        SimBus::new(vec![
            SimSegment::new(0x21, Calibration::new(2048, Direction::CounterClockwise)),
            SimSegment::new(0x22, Calibration::new(100, Direction::Clockwise)),
        ])
    }

    #[test]
    fn a_pec_read_returns_the_published_word() {
        let mut bus = bus();
        bus.segment_mut(0).unwrap().set_angle_rad(-0.3);
        bus.segment_mut(1).unwrap().set_angle_rad(0.7);
        bus.sample_all();
        for (address, calibration, angle) in [
            (
                0x21,
                Calibration::new(2048, Direction::CounterClockwise),
                -0.3,
            ),
            (0x22, Calibration::new(100, Direction::Clockwise), 0.7),
        ] {
            let mut bytes = [0u8; 3];
            bus.read(address, &mut bytes).unwrap();
            let word = SampleWord::from_read_with_pec(address, bytes).unwrap();
            assert_eq!(word.angle_counts(), calibration.counts_for_angle(angle));
        }
    }

    #[test]
    fn touch_is_debounced_over_three_samples() {
        let mut bus = bus();
        bus.segment_mut(0)
            .unwrap()
            .set_touch(TouchBits::from_bits(0b1000).unwrap());
        let mut seen = Vec::new();
        for _ in 0..3 {
            bus.sample_all();
            let mut bytes = [0u8; 2];
            bus.read(0x21, &mut bytes).unwrap();
            seen.push(SampleWord::from_be_bytes(bytes).touch().bits());
        }
        assert_eq!(seen, vec![0, 0, 0b1000]);
    }

    #[test]
    fn missing_address_is_a_nack_and_register_reads_work() {
        let mut bus = bus();
        assert_eq!(
            bus.read(0x30, &mut [0u8; 2]),
            Err(SimBusError::AddressNack(0x30))
        );
        bus.sample_all();
        bus.sample_all();
        let mut counter = [0u8; 2];
        bus.write_read(0x21, &[Register::Counter.number()], &mut counter)
            .unwrap();
        assert_eq!(counter[0], 2);
        // Over-long write to a read-only register: the extra byte is refused.
        assert_eq!(
            bus.write(0x21, &[Register::Counter.number(), 0x55]),
            Err(SimBusError::DataNack(0x21))
        );
    }

    #[test]
    fn injected_faults_nack_corrupt_and_freeze_the_counter() {
        let mut bus = bus();
        bus.sample_all();
        bus.segment_mut(0).unwrap().set_fault(SegmentFault::Nack);
        assert_eq!(
            bus.read(0x21, &mut [0u8; 3]),
            Err(SimBusError::AddressNack(0x21))
        );
        bus.segment_mut(0)
            .unwrap()
            .set_fault(SegmentFault::CorruptPec);
        let mut bytes = [0u8; 3];
        bus.read(0x21, &mut bytes).unwrap();
        assert!(SampleWord::from_read_with_pec(0x21, bytes).is_err());
        bus.segment_mut(0)
            .unwrap()
            .set_fault(SegmentFault::StuckCounter);
        let counter = |bus: &mut SimBus| {
            let mut c = [0u8; 1];
            bus.write_read(0x21, &[Register::Counter.number()], &mut c)
                .unwrap();
            c[0]
        };
        let before = counter(&mut bus);
        bus.sample_all();
        assert_eq!(counter(&mut bus), before);
        bus.segment_mut(0).unwrap().set_fault(SegmentFault::None);
        bus.sample_all();
        assert_eq!(counter(&mut bus), before.wrapping_add(1));
    }

    #[test]
    fn address_assignment_moves_the_segment() {
        let mut bus = bus();
        let message = AddressAssignment::new(0x40).unwrap().to_bytes();
        bus.write(0x21, &message).unwrap();
        assert_eq!(bus.segments()[0].address(), 0x40);
        assert!(bus.read(0x40, &mut [0u8; 2]).is_ok());
        assert_eq!(
            bus.read(0x21, &mut [0u8; 2]),
            Err(SimBusError::AddressNack(0x21))
        );
    }

    #[test]
    fn an_unassigned_segment_answers_at_the_default_address_until_assigned() {
        let mut bus = SimBus::new(vec![SimSegment::unassigned(Calibration::default())]);
        bus.sample_all();
        let status = |bus: &mut SimBus, address: u8| {
            let mut byte = [0u8; 1];
            bus.write_read(address, &[Register::Status.number()], &mut byte)
                .unwrap();
            StatusFlags::from_bits(byte[0])
        };
        assert!(status(&mut bus, DEFAULT_ADDRESS).address_not_set());
        bus.write(
            DEFAULT_ADDRESS,
            &AddressAssignment::new(0x30).unwrap().to_bytes(),
        )
        .unwrap();
        assert!(!status(&mut bus, 0x30).address_not_set());
    }

    #[test]
    fn two_segments_at_one_address_both_ack_and_their_bytes_are_wired_and() {
        let mut bus = SimBus::new(vec![
            SimSegment::new(0x21, Calibration::new(0x0F0, Direction::CounterClockwise)),
            SimSegment::new(0x21, Calibration::new(0x00F, Direction::CounterClockwise)),
        ]);
        bus.sample_all();
        let mut bytes = [0u8; 3];
        bus.read(0x21, &mut bytes).unwrap();
        // 0x0F0 << 4 = 0x0F00 and 0x00F << 4 = 0x00F0: the AND is 0x0000.
        assert_eq!([bytes[0], bytes[1]], [0x00, 0x00]);
        assert!(SampleWord::from_read_with_pec(0x21, bytes).is_err());
        // An assignment reaches both: they move together.
        bus.write(0x21, &AddressAssignment::new(0x40).unwrap().to_bytes())
            .unwrap();
        assert!(bus.segments().iter().all(|s| s.address() == 0x40));
        // With one of them silent, the other answers alone, with a good PEC.
        bus.segment_mut(1).unwrap().set_fault(SegmentFault::Nack);
        let mut bytes = [0u8; 3];
        bus.read(0x40, &mut bytes).unwrap();
        assert_eq!(
            SampleWord::from_read_with_pec(0x40, bytes).map(|w| w.angle_counts()),
            Ok(0x0F0)
        );
    }

    #[test]
    fn a_sensor_on_a_rail_sets_the_adc_fault_bit() {
        let mut bus = bus();
        bus.segment_mut(1)
            .unwrap()
            .set_fault(SegmentFault::SensorRail);
        bus.sample_all();
        let mut byte = [0u8; 1];
        bus.write_read(0x22, &[Register::Status.number()], &mut byte)
            .unwrap();
        assert!(StatusFlags::from_bits(byte[0]).adc_fault());
        bus.write_read(0x21, &[Register::Status.number()], &mut byte)
            .unwrap();
        assert!(!StatusFlags::from_bits(byte[0]).adc_fault());
    }
}
