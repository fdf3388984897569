//! The Velmex VXM stepping motor controller over a serial port (9600 baud, 8N1, ASCII), motor 1.
//!
//! Bytes on the wire, exactly:
//!
//! | call | sent | answer |
//! |---|---|---|
//! | [`Vxm::online`] | `F` | none |
//! | [`Vxm::clear`] | `C` | none |
//! | [`Vxm::zero`] | `N` | none |
//! | [`Vxm::start_relative_steps`]`(400)` | `C,S1M2000,I1M400,R` | `^` when the move ends |
//! | [`Vxm::start_absolute_steps`]`(-400)` | `C,S1M2000,IA1M-400,R` | `^` when the move ends |
//! | [`Vxm::start_homing`]`(Negative)` | `C,S1M2000,I1M-0,IA1M-0,R` | `^` when at the switch, zeroed |
//! | [`Vxm::status`] | `V` | `R` ready, `B` busy, `J` jog, `b` jog busy |
//! | [`Vxm::position_steps`] | `X` | a signed number and CR, e.g. `+0000400\r` |
//! | [`Vxm::kill`] | `K` | none |
//! | [`Vxm::decelerate`] | `D` | none |
//!
//! [`Vxm::set_speed_steps_per_s`] sends nothing: the speed (`S1M2000` above) is part of every
//! move's program, so a move never runs at a speed left over from someone else's program.
//! A relative move of zero steps sends nothing (the VXM reads `I1M0` as "run to the positive
//! limit switch").
//!
//! # Power cycles
//!
//! A VXM that lost power comes back off line with echo on and its position register at
//! zero, wherever the carriage is. The driver takes an echo as the sign: a `V` or `X` whose
//! answer starts with the command's own letter is [`VxmError::PowerCycled`] (the daemon
//! queries `X` at the stage's sampling rate, so a power blip shows at the next sample), and
//! [`Vxm::reconnect`] asks `V` before putting the VXM back on line and says whether it
//! echoed. Either way the position is lost: home again.
//!
//! # Stopping while a query waits
//!
//! [`VxmKill`] is a second handle on the same serial port ([`SerialPort::try_clone`]) that
//! only ever writes `K`, from any thread: a `stop_all` does not wait behind a query that is
//! waiting for its answer on the driver's handle.

use crate::hardware::stage::{HomingDirection, Stage};
use serialport::{DataBits, FlowControl, Parity, SerialPort, StopBits};
use std::io::{self, Read, Write};
use std::sync::{Arc, Mutex, PoisonError};
use std::time::{Duration, Instant};

/// The VXM's factory baud rate.
pub const VXM_BAUD: u32 = 9600;
/// Slowest speed the VXM accepts, steps per second.
pub const MIN_SPEED_STEPS_PER_S: u32 = 1;
/// Fastest speed the VXM accepts, steps per second.
pub const MAX_SPEED_STEPS_PER_S: u32 = 6000;
/// Largest distance or position in one index command, steps.
pub const MAX_INDEX_STEPS: i32 = 16_777_215;
/// Longest position answer accepted before it counts as garbage.
const MAX_ANSWER_BYTES: usize = 16;

/// What went wrong talking to a VXM.
#[derive(Debug, thiserror::Error)]
pub enum VxmError {
    /// The VXM did not answer (or did not finish the move) in time.
    #[error("no {expected} from the VXM within {waited:?}")]
    Timeout {
        /// What was awaited: `"^"`, a status or a position.
        expected: &'static str,
        /// How long the driver waited.
        waited: Duration,
    },
    /// The VXM answered something that is not a valid answer to the command.
    #[error("the VXM answered {answer:?} to {command:?}")]
    Garbage {
        /// The command sent.
        command: &'static str,
        /// The bytes received, lossily as text.
        answer: String,
    },
    /// The serial device failed or vanished (unplugged, closed); reconnect with
    /// [`Vxm::reconnect`].
    #[error("the VXM's serial device is gone: {0}")]
    Disconnected(#[source] io::Error),
    /// The speed is outside what the VXM accepts; nothing was sent.
    #[error("speed {0} steps/s is outside 1..=6000")]
    SpeedOutOfRange(u32),
    /// The distance or position is beyond what one index command can express; nothing was
    /// sent.
    #[error("{0} steps is beyond the VXM's ±16777215")]
    StepsOutOfRange(i32),
    /// The VXM echoed the command: it is off line with echo on, as after power-up, and its
    /// position register was zeroed wherever the carriage is. Home it again.
    #[error(
        "the VXM echoed {command:?}: it is off line, as after a power cycle; its position is lost"
    )]
    PowerCycled {
        /// The command it echoed.
        command: &'static str,
    },
}

/// The VXM's answer to `V`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VxmStatus {
    /// Ready: no program running.
    Ready,
    /// Busy: a program (a move) is running.
    Busy,
    /// Jog mode.
    Jog,
    /// Jog mode, the motor moving.
    JogBusy,
}

/// Opens `path` as a VXM port: 9600 baud, 8 data bits, no parity, 1 stop bit, no flow
/// control, reads giving up after `timeout` (keep it short: the driver's own deadlines are
/// built from these reads).
pub fn open_port(path: &str, timeout: Duration) -> serialport::Result<Box<dyn SerialPort>> {
    serialport::new(path, VXM_BAUD)
        .data_bits(DataBits::Eight)
        .parity(Parity::None)
        .stop_bits(StopBits::One)
        .flow_control(FlowControl::None)
        .timeout(timeout)
        .open()
}

/// A VXM driving motor 1, over a port it owns ([`Vxm::destroy`] gives it back).
///
/// The port must time out its reads (every [`SerialPort`] does; a read that returns
/// [`io::ErrorKind::TimedOut`] or [`io::ErrorKind::WouldBlock`] is retried until the driver's
/// deadline). End of file or any other I/O error means the device is gone.
#[derive(Debug)]
pub struct Vxm<P> {
    port: P,
    speed_steps_per_s: u32,
    reply_timeout: Duration,
    /// A `^` arrived (perhaps while reading another answer) and has not been waited for.
    finished_seen: bool,
}

impl<P: Read + Write> Vxm<P> {
    /// A driver on `port`, speed 2000 steps/s, answers awaited for 500 ms.
    pub fn new(port: P) -> Self {
        Self {
            port,
            speed_steps_per_s: 2000,
            reply_timeout: Duration::from_millis(500),
            finished_seen: false,
        }
    }

    /// Sets how long [`Vxm::status`] and [`Vxm::position_steps`] wait for an answer.
    pub fn with_reply_timeout(mut self, reply_timeout: Duration) -> Self {
        self.reply_timeout = reply_timeout;
        self
    }

    /// The speed of the following moves, steps per second.
    pub fn speed_steps_per_s(&self) -> u32 {
        self.speed_steps_per_s
    }

    /// Puts the VXM on line (`F`).
    pub fn online(&mut self) -> Result<(), VxmError> {
        self.send(b"F")
    }

    /// Clears the program memory (`C`).
    pub fn clear(&mut self) -> Result<(), VxmError> {
        self.send(b"C")
    }

    /// Zeroes the position register (`N`).
    pub fn zero(&mut self) -> Result<(), VxmError> {
        self.send(b"N")
    }

    /// Sets the speed of the following moves (sent with each move).
    pub fn set_speed_steps_per_s(&mut self, speed_steps_per_s: u32) -> Result<(), VxmError> {
        if !(MIN_SPEED_STEPS_PER_S..=MAX_SPEED_STEPS_PER_S).contains(&speed_steps_per_s) {
            return Err(VxmError::SpeedOutOfRange(speed_steps_per_s));
        }
        self.speed_steps_per_s = speed_steps_per_s;
        Ok(())
    }

    /// Starts homing (`C,S1M<speed>,I1M-0,IA1M-0,R` toward the negative limit switch,
    /// `I1M0` toward the positive one): the motor runs until the switch trips, then the
    /// absolute zero is set there; `^` follows. A kill before the switch leaves the
    /// position register as it was.
    pub fn start_homing(&mut self, toward: HomingDirection) -> Result<(), VxmError> {
        self.finished_seen = false;
        let index = match toward {
            HomingDirection::Negative => "I1M-0",
            HomingDirection::Positive => "I1M0",
        };
        let program = format!("C,S1M{},{index},IA1M-0,R", self.speed_steps_per_s);
        self.send(program.as_bytes())
    }

    /// Starts a move of `steps` (`C,S1M<speed>,I1M<steps>,R`); zero steps sends nothing.
    pub fn start_relative_steps(&mut self, steps: i32) -> Result<(), VxmError> {
        check_steps(steps)?;
        if steps == 0 {
            self.finished_seen = true;
            return Ok(());
        }
        self.finished_seen = false;
        let program = format!("C,S1M{},I1M{steps},R", self.speed_steps_per_s);
        self.send(program.as_bytes())
    }

    /// Starts a move to `position_steps` (`C,S1M<speed>,IA1M<position>,R`).
    pub fn start_absolute_steps(&mut self, position_steps: i32) -> Result<(), VxmError> {
        check_steps(position_steps)?;
        self.finished_seen = false;
        let program = format!("C,S1M{},IA1M{position_steps},R", self.speed_steps_per_s);
        self.send(program.as_bytes())
    }

    /// Waits for the `^` that ends a program, at most `timeout`. Returns at once if it has
    /// already arrived.
    pub fn wait_done(&mut self, timeout: Duration) -> Result<(), VxmError> {
        if self.finished_seen {
            self.finished_seen = false;
            return Ok(());
        }
        let deadline = Instant::now() + timeout;
        match self.read_byte(deadline, "^")? {
            b'^' => Ok(()),
            other => Err(VxmError::Garbage {
                command: "R",
                answer: String::from_utf8_lossy(&[other]).into_owned(),
            }),
        }
    }

    /// Asks for the status (`V`); an echoed `V` is [`VxmError::PowerCycled`].
    pub fn status(&mut self) -> Result<VxmStatus, VxmError> {
        self.send(b"V")?;
        let deadline = Instant::now() + self.reply_timeout;
        loop {
            match self.read_byte(deadline, "status")? {
                b'R' => return Ok(VxmStatus::Ready),
                b'B' => return Ok(VxmStatus::Busy),
                b'J' => return Ok(VxmStatus::Jog),
                b'b' => return Ok(VxmStatus::JogBusy),
                b'^' => self.finished_seen = true,
                b'V' => return Err(self.power_cycled("V")),
                other => {
                    return Err(VxmError::Garbage {
                        command: "V",
                        answer: String::from_utf8_lossy(&[other]).into_owned(),
                    });
                }
            }
        }
    }

    /// Asks for the position (`X`), steps; an echoed `X` is [`VxmError::PowerCycled`].
    pub fn position_steps(&mut self) -> Result<i32, VxmError> {
        self.send(b"X")?;
        let deadline = Instant::now() + self.reply_timeout;
        let mut answer = Vec::new();
        loop {
            match self.read_byte(deadline, "position")? {
                b'^' if answer.is_empty() => self.finished_seen = true,
                b'X' if answer.is_empty() => return Err(self.power_cycled("X")),
                b'\r' => break,
                byte => {
                    answer.push(byte);
                    if answer.len() > MAX_ANSWER_BYTES {
                        break;
                    }
                }
            }
        }
        parse_position(&answer).ok_or_else(|| VxmError::Garbage {
            command: "X",
            answer: String::from_utf8_lossy(&answer).into_owned(),
        })
    }

    /// Stops the motor at once (`K`); no `^` follows.
    pub fn kill(&mut self) -> Result<(), VxmError> {
        self.finished_seen = false;
        self.send(b"K")
    }

    /// Stops the motor with its deceleration ramp (`D`); no `^` follows.
    pub fn decelerate(&mut self) -> Result<(), VxmError> {
        self.finished_seen = false;
        self.send(b"D")
    }

    /// After the device vanished and came back: drives `port` instead (giving back the old
    /// one), asks `V` and puts the VXM on line again. Also says whether the VXM echoed the
    /// `V`, the sign of a power cycle (see the module documentation): the position register
    /// survives a lost USB link but not a power cycle, so then home again.
    ///
    /// If the VXM does not answer, the driver keeps its old port and `port` is dropped
    /// (closed): a serial port holds an exclusive lock on its device while open, so a port
    /// kept after a failed attempt would make every later attempt to open the device fail.
    pub fn reconnect(&mut self, port: P) -> Result<(P, bool), VxmError> {
        let old = core::mem::replace(&mut self.port, port);
        self.finished_seen = false;
        match self.handshake() {
            Ok(power_cycled) => Ok((old, power_cycled)),
            Err(e) => {
                drop(core::mem::replace(&mut self.port, old));
                Err(e)
            }
        }
    }

    /// `V` (whose echo is the sign of a power cycle), then on line.
    fn handshake(&mut self) -> Result<bool, VxmError> {
        let power_cycled = match self.status() {
            Ok(_) => false,
            Err(VxmError::PowerCycled { .. }) => true,
            Err(e) => return Err(e),
        };
        self.online()?;
        Ok(power_cycled)
    }

    /// The port handle (e.g. to clone it for a [`VxmKill`]).
    pub fn port(&self) -> &P {
        &self.port
    }

    /// After an echo: reads what else the VXM sends (the rest of the echoed answer) for a
    /// short while, so the next query starts clean.
    fn power_cycled(&mut self, command: &'static str) -> VxmError {
        let deadline = Instant::now() + Duration::from_millis(50).min(self.reply_timeout);
        while self.read_byte(deadline, "the rest of an echo").is_ok() {}
        self.finished_seen = false;
        VxmError::PowerCycled { command }
    }

    /// Gives the port back.
    pub fn destroy(self) -> P {
        self.port
    }

    fn send(&mut self, bytes: &[u8]) -> Result<(), VxmError> {
        self.port
            .write_all(bytes)
            .and_then(|()| self.port.flush())
            .map_err(VxmError::Disconnected)
    }

    fn read_byte(&mut self, deadline: Instant, expected: &'static str) -> Result<u8, VxmError> {
        let start = Instant::now();
        let mut byte = [0u8; 1];
        loop {
            match self.port.read(&mut byte) {
                Ok(1) => return Ok(byte[0]),
                Ok(_) => {
                    return Err(VxmError::Disconnected(io::Error::new(
                        io::ErrorKind::UnexpectedEof,
                        "end of file",
                    )));
                }
                Err(error)
                    if matches!(
                        error.kind(),
                        io::ErrorKind::TimedOut | io::ErrorKind::WouldBlock
                    ) => {}
                Err(error) if error.kind() == io::ErrorKind::Interrupted => {}
                Err(error) => return Err(VxmError::Disconnected(error)),
            }
            if Instant::now() >= deadline {
                return Err(VxmError::Timeout {
                    expected,
                    waited: start.elapsed(),
                });
            }
        }
    }
}

/// A second handle on the VXM's serial port that only ever sends `K` (kill), usable from
/// any thread while the driver's own handle waits for an answer. Clones share the handle;
/// [`VxmKill::arm`] swaps in a new one after a reconnect.
#[derive(Clone, Default)]
pub struct VxmKill {
    port: Arc<Mutex<Option<Box<dyn SerialPort>>>>,
}

impl std::fmt::Debug for VxmKill {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("VxmKill")
            .field("armed", &self.is_armed())
            .finish()
    }
}

impl VxmKill {
    /// Unarmed: [`VxmKill::kill`] sends nothing until [`VxmKill::arm`].
    pub fn new() -> Self {
        Self::default()
    }

    /// Kills through a clone of `port` from now on (a failed clone leaves it unarmed and
    /// is returned).
    pub fn arm(&self, port: &dyn SerialPort) -> serialport::Result<()> {
        let clone = port.try_clone();
        let mut slot = self.port.lock().unwrap_or_else(PoisonError::into_inner);
        match clone {
            Ok(clone) => {
                *slot = Some(clone);
                Ok(())
            }
            Err(e) => {
                *slot = None;
                Err(e)
            }
        }
    }

    /// Sends nothing from now on (the device vanished).
    pub fn disarm(&self) {
        *self.port.lock().unwrap_or_else(PoisonError::into_inner) = None;
    }

    /// Whether a port is there to kill through.
    pub fn is_armed(&self) -> bool {
        self.port
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .is_some()
    }

    /// Sends `K` at once: `Ok(true)` if sent, `Ok(false)` if unarmed.
    pub fn kill(&self) -> Result<bool, VxmError> {
        let mut slot = self.port.lock().unwrap_or_else(PoisonError::into_inner);
        match slot.as_mut() {
            Some(port) => port
                .write_all(b"K")
                .and_then(|()| port.flush())
                .map(|()| true)
                .map_err(VxmError::Disconnected),
            None => Ok(false),
        }
    }
}

fn check_steps(steps: i32) -> Result<(), VxmError> {
    if steps.unsigned_abs() > MAX_INDEX_STEPS.unsigned_abs() {
        Err(VxmError::StepsOutOfRange(steps))
    } else {
        Ok(())
    }
}

/// `[+-]digits`, surrounding spaces allowed.
fn parse_position(answer: &[u8]) -> Option<i32> {
    let text = core::str::from_utf8(answer).ok()?.trim();
    let digits = text.strip_prefix(['+', '-']).unwrap_or(text);
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    text.parse().ok()
}

impl<P: Read + Write> Stage for Vxm<P> {
    type Error = VxmError;

    fn online(&mut self) -> Result<(), VxmError> {
        Vxm::online(self)
    }
    fn start_homing(&mut self, toward: HomingDirection) -> Result<(), VxmError> {
        Vxm::start_homing(self, toward)
    }
    fn is_moving(&mut self) -> Result<bool, VxmError> {
        Vxm::status(self).map(|status| matches!(status, VxmStatus::Busy | VxmStatus::JogBusy))
    }
    fn set_speed_steps_per_s(&mut self, speed_steps_per_s: u32) -> Result<(), VxmError> {
        Vxm::set_speed_steps_per_s(self, speed_steps_per_s)
    }
    fn start_relative_steps(&mut self, steps: i32) -> Result<(), VxmError> {
        Vxm::start_relative_steps(self, steps)
    }
    fn start_absolute_steps(&mut self, position_steps: i32) -> Result<(), VxmError> {
        Vxm::start_absolute_steps(self, position_steps)
    }
    fn wait_done(&mut self, timeout: Duration) -> Result<(), VxmError> {
        Vxm::wait_done(self, timeout)
    }
    fn position_steps(&mut self) -> Result<i32, VxmError> {
        Vxm::position_steps(self)
    }
    fn kill(&mut self) -> Result<(), VxmError> {
        Vxm::kill(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn positions_parse_signed_and_padded() {
        assert_eq!(parse_position(b"+0000400"), Some(400));
        assert_eq!(parse_position(b"-12"), Some(-12));
        assert_eq!(parse_position(b" 7 "), Some(7));
        assert_eq!(parse_position(b"+"), None);
        assert_eq!(parse_position(b"+-3"), None);
        assert_eq!(parse_position(b"?!"), None);
    }
}
