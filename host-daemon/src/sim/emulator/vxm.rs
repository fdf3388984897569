//! A Velmex VXM (motor 1) as its serial port sees it.

use super::{Device, Runner};
use serialport::SerialPort;
use std::sync::MutexGuard;
use std::time::Instant;

/// How far below its start an emulated VXM's negative limit switch is, steps.
pub const DEFAULT_LIMIT_BELOW_STEPS: u32 = 400;

/// How the emulated VXM misbehaves.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum VxmFault {
    /// It behaves.
    #[default]
    None,
    /// Moves complete but no `^` is ever sent.
    NeverFinish,
    /// `V` and `X` are answered with noise.
    Garbage,
    /// `V` and `X` are not answered (the controller hangs on a query) until
    /// [`VxmEmulator::answer_stalled`]; every other command, `K` too, still works.
    Stall,
}

/// One command of a program.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ProgramStep {
    Speed(i64),
    Relative(i64),
    Absolute(i64),
    /// `I1M-0` (`false`) or `I1M0` (`true`): run to that limit switch.
    ToLimit(bool),
    /// `IA1M-0`: the current position becomes absolute zero.
    SetZero,
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct Motion {
    from_steps: f64,
    to_steps: f64,
    speed_steps_per_s: f64,
    started: Instant,
}

impl Motion {
    fn position(&self, now: Instant) -> (f64, bool) {
        let distance = self.to_steps - self.from_steps;
        let travelled = self.speed_steps_per_s * (now - self.started).as_secs_f64();
        if travelled >= distance.abs() {
            (self.to_steps, true)
        } else {
            (self.from_steps + travelled.copysign(distance), false)
        }
    }
}

#[derive(Debug)]
struct VxmModel {
    received: Vec<u8>,
    pending: Vec<u8>,
    online: bool,
    /// Every byte received is sent back (after power-up, until `F`).
    echo: bool,
    /// The limit switches, steps in the register's frame (negative, positive).
    limits_steps: (f64, f64),
    fault: VxmFault,
    position_steps: f64,
    speed_steps_per_s: i64,
    program: Vec<ProgramStep>,
    queue: Vec<ProgramStep>,
    running: bool,
    motion: Option<Motion>,
    unknown_bytes: usize,
    /// The queries (`V`, `X`) left unanswered while stalled, oldest first.
    stalled: Vec<u8>,
    /// Answers to send from outside the emulator's thread (at its next tick).
    outbox: Vec<u8>,
}

impl VxmModel {
    /// The register reads zero here; the limit switches stay where they are.
    fn zero_here(&mut self) {
        let here = self.position_steps;
        self.limits_steps = (self.limits_steps.0 - here, self.limits_steps.1 - here);
        self.position_steps = 0.0;
    }

    fn position_now(&self) -> f64 {
        self.motion
            .map_or(self.position_steps, |m| m.position(Instant::now()).0)
    }

    fn stop_motion(&mut self) {
        self.position_steps = self.position_now().round();
        self.motion = None;
        self.queue.clear();
        self.running = false;
    }

    /// The answer to the query `V` or `X`, now.
    fn answer(&self, query: u8, out: &mut Vec<u8>) {
        match (query, self.fault) {
            (b'V', VxmFault::Garbage) => out.push(b'?'),
            (b'V', _) => out.push(if self.running { b'B' } else { b'R' }),
            (_, VxmFault::Garbage) => out.extend_from_slice(b"?!#\r"),
            _ => {
                let position = self.position_now().round() as i64;
                out.extend_from_slice(format!("{position:+08}\r").as_bytes());
            }
        }
    }

    /// Parses one command from the front of `pending`: `Some(consumed)` or `None` to wait
    /// for more bytes.
    fn parse_one(&mut self, out: &mut Vec<u8>) -> Option<usize> {
        let bytes = &self.pending;
        let first = *bytes.first()?;
        let command = match first {
            b',' | b' ' | b'\r' | b'\n' => return Some(1),
            b'F' => {
                self.online = true;
                self.echo = false;
                return Some(1);
            }
            b'C' => {
                self.program.clear();
                return Some(1);
            }
            b'N' => {
                if self.motion.is_none() {
                    self.position_steps = 0.0;
                }
                return Some(1);
            }
            b'K' | b'D' => {
                self.stop_motion();
                return Some(1);
            }
            b'R' => {
                if !self.running {
                    self.queue = self.program.iter().rev().copied().collect();
                    self.running = true;
                }
                return Some(1);
            }
            b'V' | b'X' => {
                if self.fault == VxmFault::Stall {
                    self.stalled.push(first);
                } else {
                    self.answer(first, out);
                }
                return Some(1);
            }
            b'S' => b"S1M".as_slice(),
            b'I' if bytes.get(1) == Some(&b'A') => b"IA1M".as_slice(),
            b'I' => b"I1M".as_slice(),
            _ => {
                self.unknown_bytes += 1;
                return Some(1);
            }
        };
        // An index or speed command: the prefix, a signed number, then a terminator.
        let prefix_len = command.len().min(bytes.len());
        if bytes[..prefix_len] != command[..prefix_len] {
            self.unknown_bytes += 1;
            return Some(1);
        }
        if bytes.len() <= command.len() {
            return None;
        }
        let mut end = command.len();
        if bytes[end] == b'-' {
            end += 1;
        }
        while end < bytes.len() && bytes[end].is_ascii_digit() {
            end += 1;
        }
        if end == bytes.len() {
            return None;
        }
        let text = core::str::from_utf8(&bytes[command.len()..end]).unwrap_or("");
        let Ok(value) = text.parse::<i64>() else {
            // A sign without digits, or a number too long: dropped.
            self.unknown_bytes += 1;
            return Some(end);
        };
        self.program.push(match (command, text) {
            (b"S1M", _) => ProgramStep::Speed(value),
            (b"IA1M", "-0") => ProgramStep::SetZero,
            (b"IA1M", _) => ProgramStep::Absolute(value),
            (_, "-0") => ProgramStep::ToLimit(false),
            (_, "0") => ProgramStep::ToLimit(true),
            _ => ProgramStep::Relative(value),
        });
        Some(end)
    }
}

impl Device for VxmModel {
    fn feed(&mut self, bytes: &[u8], out: &mut Vec<u8>) {
        self.received.extend_from_slice(bytes);
        if self.echo {
            // Everything up to the `F` that turns the echo off.
            let until = bytes.iter().position(|&b| b == b'F').unwrap_or(bytes.len());
            out.extend_from_slice(&bytes[..until]);
        }
        self.pending.extend_from_slice(bytes);
        while let Some(consumed) = self.parse_one(out) {
            self.pending.drain(..consumed);
        }
    }

    fn tick(&mut self, out: &mut Vec<u8>) {
        out.append(&mut self.outbox);
        if let Some(motion) = self.motion {
            let (position, done) = motion.position(Instant::now());
            if !done {
                return;
            }
            self.position_steps = position;
            self.motion = None;
        }
        while self.running && self.motion.is_none() {
            match self.queue.pop() {
                Some(ProgramStep::Speed(speed)) => self.speed_steps_per_s = speed.max(1),
                Some(ProgramStep::SetZero) => self.zero_here(),
                Some(step) => {
                    let to_steps = match step {
                        ProgramStep::Absolute(to) => to as f64,
                        ProgramStep::Relative(by) => self.position_steps + by as f64,
                        ProgramStep::ToLimit(positive) => {
                            if positive {
                                self.limits_steps.1
                            } else {
                                self.limits_steps.0
                            }
                        }
                        ProgramStep::Speed(_) | ProgramStep::SetZero => self.position_steps,
                    };
                    // The limit switches stop the motor wherever it was sent.
                    let to_steps = to_steps.clamp(self.limits_steps.0, self.limits_steps.1);
                    self.motion = Some(Motion {
                        from_steps: self.position_steps,
                        to_steps,
                        speed_steps_per_s: self.speed_steps_per_s as f64,
                        started: Instant::now(),
                    });
                }
                None => {
                    self.running = false;
                    if self.fault != VxmFault::NeverFinish {
                        out.push(b'^');
                    }
                }
            }
        }
    }
}

/// An emulated VXM on its own thread, answering at the far end of `port`. Moves run in real
/// time at the programmed speed and stop at the limit switches (by default 400 steps below
/// the start and a million above); `I1M-0`/`I1M0` run to a switch and `IA1M-0` zeroes the
/// register there; `^` follows the end of each program; `X` answers `+0000400\r`-style
/// positions; `K` and `D` stop at once without `^`. [`VxmEmulator::power_cycle`] brings it
/// back as after power-up: off line, echoing, the register zeroed where it stands.
#[derive(Debug)]
pub struct VxmEmulator {
    runner: Runner<VxmModel>,
}

impl VxmEmulator {
    /// Starts an emulated VXM at step zero.
    pub fn spawn<P: SerialPort + 'static>(port: P) -> Self {
        Self::spawn_at(port, 0)
    }

    /// Starts an emulated VXM at `position_steps` (e.g. the same controller, back after its
    /// USB link dropped).
    pub fn spawn_at<P: SerialPort + 'static>(port: P, position_steps: i32) -> Self {
        let model = VxmModel {
            received: Vec::new(),
            pending: Vec::new(),
            online: false,
            echo: false,
            limits_steps: (
                f64::from(position_steps) - f64::from(DEFAULT_LIMIT_BELOW_STEPS),
                f64::from(position_steps) + 1e6,
            ),
            fault: VxmFault::None,
            position_steps: f64::from(position_steps),
            speed_steps_per_s: 2000,
            program: Vec::new(),
            queue: Vec::new(),
            running: false,
            motion: None,
            unknown_bytes: 0,
            stalled: Vec::new(),
            outbox: Vec::new(),
        };
        Self {
            runner: Runner::spawn(port, model),
        }
    }

    fn model(&self) -> MutexGuard<'_, VxmModel> {
        self.runner.model()
    }

    /// Puts the negative limit switch `steps` below where the carriage is now.
    pub fn set_limit_below(&self, steps: u32) {
        let mut model = self.model();
        let here = model.position_now();
        model.limits_steps.0 = here - f64::from(steps);
    }

    /// Its power is cycled: the program and motion stop, it comes back off line with echo
    /// on, and the register reads zero where the carriage is (the switches stay put).
    pub fn power_cycle(&self) {
        let mut model = self.model();
        model.stop_motion();
        model.program.clear();
        model.pending.clear();
        model.zero_here();
        model.online = false;
        model.echo = true;
    }

    /// Where the negative limit switch is, steps in the register's frame (0 after homing
    /// against it).
    pub fn negative_limit_steps(&self) -> i64 {
        self.model().limits_steps.0.round() as i64
    }

    /// Makes the emulator misbehave from now on.
    pub fn set_fault(&self, fault: VxmFault) {
        self.model().fault = fault;
    }

    /// The queries left unanswered so far while [`VxmFault::Stall`] was on.
    pub fn stalled_queries(&self) -> usize {
        self.model().stalled.len()
    }

    /// Stops stalling ([`VxmFault::None`] from now on) and answers the queries left
    /// unanswered, in order, as if they had just been asked.
    pub fn answer_stalled(&self) {
        let mut model = self.model();
        model.fault = VxmFault::None;
        let mut answers = Vec::new();
        for query in std::mem::take(&mut model.stalled) {
            model.answer(query, &mut answers);
        }
        model.outbox.append(&mut answers);
    }

    /// Every byte received so far.
    pub fn received(&self) -> Vec<u8> {
        self.model().received.clone()
    }

    /// Forgets the bytes received so far.
    pub fn clear_received(&self) {
        self.model().received.clear();
    }

    /// Whether `F` has been received.
    pub fn is_online(&self) -> bool {
        self.model().online
    }

    /// Whether a program is running.
    pub fn is_busy(&self) -> bool {
        self.model().running
    }

    /// The motor's position now, steps (rounded).
    pub fn position_steps(&self) -> i64 {
        self.model().position_now().round() as i64
    }

    /// The speed last programmed, steps per second.
    pub fn speed_steps_per_s(&self) -> i64 {
        self.model().speed_steps_per_s
    }

    /// Bytes that were not part of any command.
    pub fn unknown_bytes(&self) -> usize {
        self.model().unknown_bytes
    }

    /// The device vanishes: the thread stops and its end of the port is closed.
    pub fn close(mut self) {
        self.runner.close();
    }
}
