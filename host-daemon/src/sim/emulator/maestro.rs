//! A Pololu Maestro as its serial port sees it (compact protocol: set target, get position).

use super::{Device, Runner};
use crate::hardware::maestro::MAESTRO_CHANNELS;
use serialport::SerialPort;
use std::sync::MutexGuard;

/// How the emulated Maestro misbehaves.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MaestroFault {
    /// It behaves.
    #[default]
    None,
    /// Position requests are never answered.
    Silent,
}

#[derive(Debug)]
struct MaestroModel {
    received: Vec<u8>,
    pending: Vec<u8>,
    positions: [u16; MAESTRO_CHANNELS as usize],
    fault: MaestroFault,
    protocol_errors: usize,
}

impl Device for MaestroModel {
    fn feed(&mut self, bytes: &[u8], out: &mut Vec<u8>) {
        self.received.extend_from_slice(bytes);
        self.pending.extend_from_slice(bytes);
        loop {
            let consumed = match self.pending.as_slice() {
                [0x84, rest @ ..] if rest.len() >= 3 => {
                    let (channel, low, high) = (rest[0], rest[1], rest[2]);
                    if channel >= MAESTRO_CHANNELS || (low | high) & 0x80 != 0 {
                        self.protocol_errors += 1;
                    } else {
                        self.positions[usize::from(channel)] =
                            u16::from(low) | (u16::from(high) << 7);
                    }
                    4
                }
                [0x90, channel, ..] => {
                    match self.positions.get(usize::from(*channel)) {
                        Some(position) if self.fault == MaestroFault::None => {
                            out.extend_from_slice(&position.to_le_bytes());
                        }
                        Some(_) => {}
                        None => self.protocol_errors += 1,
                    }
                    2
                }
                [0x84, ..] | [0x90] | [] => break,
                [_, ..] => {
                    self.protocol_errors += 1;
                    1
                }
            };
            self.pending.drain(..consumed);
        }
    }

    fn tick(&mut self, _out: &mut Vec<u8>) {}
}

/// An emulated Maestro on its own thread, answering at the far end of `port`. A target is
/// reached at once (no speed or acceleration limits configured); a malformed command counts
/// as a protocol error, as the Maestro's error register would.
#[derive(Debug)]
pub struct MaestroEmulator {
    runner: Runner<MaestroModel>,
}

impl MaestroEmulator {
    /// Starts an emulated Maestro with every channel off (position 0).
    pub fn spawn<P: SerialPort + 'static>(port: P) -> Self {
        let model = MaestroModel {
            received: Vec::new(),
            pending: Vec::new(),
            positions: [0; MAESTRO_CHANNELS as usize],
            fault: MaestroFault::None,
            protocol_errors: 0,
        };
        Self {
            runner: Runner::spawn(port, model),
        }
    }

    fn model(&self) -> MutexGuard<'_, MaestroModel> {
        self.runner.model()
    }

    /// Makes the emulator misbehave from now on.
    pub fn set_fault(&self, fault: MaestroFault) {
        self.model().fault = fault;
    }

    /// Every byte received so far.
    pub fn received(&self) -> Vec<u8> {
        self.model().received.clone()
    }

    /// A channel's position, quarter-microseconds (`None` past the last channel).
    pub fn position_quarter_us(&self, channel: u8) -> Option<u16> {
        self.model().positions.get(usize::from(channel)).copied()
    }

    /// Malformed commands received.
    pub fn protocol_errors(&self) -> usize {
        self.model().protocol_errors
    }

    /// The device vanishes: the thread stops and its end of the port is closed.
    pub fn close(mut self) {
        self.runner.close();
    }
}
