//! The Pololu Maestro servo controller, compact protocol, one channel.
//!
//! Bytes on the wire, exactly (targets and positions in quarter-microseconds):
//!
//! | call | sent | answer |
//! |---|---|---|
//! | set target `t` on channel `c` | `0x84, c, t & 0x7F, (t >> 7) & 0x7F` | none |
//! | get position of channel `c` | `0x90, c` | two bytes, low first |

use crate::hardware::servo::{PulseCalibration, Servo};
use std::io::{self, Read, Write};
use std::time::{Duration, Instant};

/// Channels on the largest Maestro (Mini Maestro 24).
pub const MAESTRO_CHANNELS: u8 = 24;
/// Largest target the compact protocol can carry (14 bits), quarter-microseconds.
pub const MAX_TARGET_QUARTER_US: u16 = 0x3FFF;

/// What went wrong with the Maestro.
#[derive(Debug, thiserror::Error)]
pub enum MaestroError {
    /// No such channel on a Maestro.
    #[error("channel {0} is not below {MAESTRO_CHANNELS}")]
    InvalidChannel(u8),
    /// The pulse limits are not finite, positive, ordered and within 14-bit targets.
    #[error("pulse limits {min_us} us to {max_us} us are not usable")]
    InvalidLimits {
        /// Lower limit, microseconds.
        min_us: f64,
        /// Upper limit, microseconds.
        max_us: f64,
    },
    /// The angle maps to a pulse width outside the configured limits (or is not finite);
    /// nothing was sent.
    #[error("{angle_rad} rad needs {pulse_us} us, outside {min_us}..={max_us} us")]
    AngleOutOfRange {
        /// The angle asked for, radians.
        angle_rad: f64,
        /// The pulse width it maps to, microseconds.
        pulse_us: f64,
        /// Lower limit, microseconds.
        min_us: f64,
        /// Upper limit, microseconds.
        max_us: f64,
    },
    /// A raw target beyond 14 bits; nothing was sent.
    #[error("target {0} quarter-us does not fit in 14 bits")]
    TargetOutOfRange(u16),
    /// The Maestro did not answer a position request in time.
    #[error("no position from the Maestro within {0:?}")]
    Timeout(Duration),
    /// The serial device failed or vanished.
    #[error("the Maestro's serial device is gone: {0}")]
    Disconnected(#[source] io::Error),
}

/// Which channel drives the servo, how pulse maps to angle and the pulse limits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MaestroConfig {
    channel: u8,
    calibration: PulseCalibration,
    min_pulse_us: f64,
    max_pulse_us: f64,
}

impl MaestroConfig {
    /// Channel `channel` with `calibration` and the Maestro's factory limits, 992 us to
    /// 2000 us (beyond its limits the Maestro silently clamps; this driver refuses instead).
    pub fn new(channel: u8, calibration: PulseCalibration) -> Result<Self, MaestroError> {
        if channel >= MAESTRO_CHANNELS {
            return Err(MaestroError::InvalidChannel(channel));
        }
        Ok(Self {
            channel,
            calibration,
            min_pulse_us: 992.0,
            max_pulse_us: 2000.0,
        })
    }

    /// The same with pulse limits `min_us..=max_us` (set the Maestro's own to match).
    pub fn with_pulse_limits_us(mut self, min_us: f64, max_us: f64) -> Result<Self, MaestroError> {
        let top = f64::from(MAX_TARGET_QUARTER_US) / 4.0;
        if !(min_us.is_finite() && max_us.is_finite() && 0.0 < min_us && min_us < max_us)
            || max_us > top
        {
            return Err(MaestroError::InvalidLimits { min_us, max_us });
        }
        self.min_pulse_us = min_us;
        self.max_pulse_us = max_us;
        Ok(self)
    }

    /// The channel.
    pub fn channel(&self) -> u8 {
        self.channel
    }

    /// The calibration.
    pub fn calibration(&self) -> &PulseCalibration {
        &self.calibration
    }
}

/// A Maestro driving one servo channel, over a port it owns ([`Maestro::destroy`] gives it
/// back). The port must time out its reads, as every `serialport` port does.
#[derive(Debug)]
pub struct Maestro<P> {
    port: P,
    config: MaestroConfig,
    reply_timeout: Duration,
}

impl<P: Read + Write> Maestro<P> {
    /// A driver on `port`; answers awaited for 200 ms.
    pub fn new(port: P, config: MaestroConfig) -> Self {
        Self {
            port,
            config,
            reply_timeout: Duration::from_millis(200),
        }
    }

    /// Sets how long a position request waits for its answer.
    pub fn with_reply_timeout(mut self, reply_timeout: Duration) -> Self {
        self.reply_timeout = reply_timeout;
        self
    }

    /// The configuration.
    pub fn config(&self) -> &MaestroConfig {
        &self.config
    }

    /// Sends a raw target, quarter-microseconds (0 switches the pulses off).
    pub fn set_target_quarter_us(&mut self, target: u16) -> Result<(), MaestroError> {
        if target > MAX_TARGET_QUARTER_US {
            return Err(MaestroError::TargetOutOfRange(target));
        }
        let bytes = [
            0x84,
            self.config.channel,
            (target & 0x7F) as u8,
            ((target >> 7) & 0x7F) as u8,
        ];
        self.port
            .write_all(&bytes)
            .and_then(|()| self.port.flush())
            .map_err(MaestroError::Disconnected)
    }

    /// Reads the channel's position, quarter-microseconds.
    pub fn position_quarter_us(&mut self) -> Result<u16, MaestroError> {
        self.port
            .write_all(&[0x90, self.config.channel])
            .and_then(|()| self.port.flush())
            .map_err(MaestroError::Disconnected)?;
        let deadline = Instant::now() + self.reply_timeout;
        let mut answer = [0u8; 2];
        let mut filled = 0;
        while filled < 2 {
            match self.port.read(&mut answer[filled..]) {
                Ok(0) => {
                    return Err(MaestroError::Disconnected(io::Error::new(
                        io::ErrorKind::UnexpectedEof,
                        "end of file",
                    )));
                }
                Ok(n) => filled += n,
                Err(error)
                    if matches!(
                        error.kind(),
                        io::ErrorKind::TimedOut
                            | io::ErrorKind::WouldBlock
                            | io::ErrorKind::Interrupted
                    ) => {}
                Err(error) => return Err(MaestroError::Disconnected(error)),
            }
            if filled < 2 && Instant::now() >= deadline {
                return Err(MaestroError::Timeout(self.reply_timeout));
            }
        }
        Ok(u16::from_le_bytes(answer))
    }

    /// Drives `port` instead, giving back the old one (after the device vanished and came
    /// back).
    pub fn reconnect(&mut self, port: P) -> P {
        core::mem::replace(&mut self.port, port)
    }

    /// Gives the port back.
    pub fn destroy(self) -> P {
        self.port
    }

    /// The target for `angle_rad`, if within the pulse limits.
    pub fn target_for_angle(&self, angle_rad: f64) -> Result<u16, MaestroError> {
        let pulse_us = self.config.calibration.pulse_us(angle_rad);
        let (min_us, max_us) = (self.config.min_pulse_us, self.config.max_pulse_us);
        if !(pulse_us.is_finite() && (min_us..=max_us).contains(&pulse_us)) {
            return Err(MaestroError::AngleOutOfRange {
                angle_rad,
                pulse_us,
                min_us,
                max_us,
            });
        }
        // Within the limits, which fit in 14 bits.
        Ok((pulse_us * 4.0).round() as u16)
    }
}

impl<P: Read + Write> Servo for Maestro<P> {
    type Error = MaestroError;

    fn set_angle_rad(&mut self, angle_rad: f64) -> Result<(), MaestroError> {
        let target = self.target_for_angle(angle_rad)?;
        self.set_target_quarter_us(target)
    }

    fn angle_rad(&mut self) -> Result<f64, MaestroError> {
        let position = self.position_quarter_us()?;
        Ok(self.config.calibration.angle_rad(f64::from(position) / 4.0))
    }
}
