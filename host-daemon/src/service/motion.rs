//! The motion thread, the one loop that moves the rig: it samples the stage and the base at their own
//! rates on the daemon's clock, homes the stage ([`crate::hardware::homing`]) before any move, carries
//! out motion commands at once (a `stop_all` ahead of anything queued before it), runs a
//! trial's script ([`crate::service::trial_script`]) and reports the stage and the servo vanishing and
//! coming back. A script ends early, with the reason, when the stage loses its home (a power
//! cycle) or stays vanished for [`STAGE_LOST_AFTER`] with moves left.

use crate::config::TrialConfig;
use crate::hardware::device::DeviceError;
use crate::service::acquisition::{AcquisitionEvent, EventSender};
use crate::service::clock::{Schedule, TrialClock};
use crate::service::rig::{DaemonRig, RigError};
use crate::service::trial_script::{MoveCounts, STAGE_LOST_AFTER, Script, ScriptEnds};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError, SyncSender};
use std::thread::JoinHandle;
use std::time::Duration;

/// Whether the stage and the servo answer, as the motion thread last found them.
#[derive(Debug)]
pub(crate) struct RigStatus {
    pub(crate) stage: AtomicBool,
    pub(crate) servo: AtomicBool,
}

impl Default for RigStatus {
    fn default() -> Self {
        Self {
            stage: AtomicBool::new(true),
            servo: AtomicBool::new(true),
        }
    }
}

/// Where a commanded stage move goes, millimetres.
#[derive(Debug, Clone, Copy)]
pub(crate) enum MoveTarget {
    To(f64),
    By(f64),
}

/// Where a command's answer goes.
pub(crate) type Reply = SyncSender<Result<String, String>>;

/// What the motion thread is told.
pub(crate) enum MotionCommand {
    RunScript {
        id: u64,
        trial: Box<TrialConfig>,
    },
    EndScript,
    Move {
        target: MoveTarget,
        speed_mm_per_s: f64,
        reply: Reply,
    },
    SetBase {
        angle_deg: f64,
        reply: Reply,
    },
    StopAll {
        reply: Reply,
    },
}

/// What the motion thread shares with the others.
pub(crate) struct MotionShared {
    /// Its commands.
    pub(crate) commands: Receiver<MotionCommand>,
    /// Raised by `stop_all` before its command is queued: the thread stops before it carries
    /// out anything else, and cancels the moves queued ahead of the stop.
    pub(crate) stop_pending: Arc<AtomicBool>,
    /// Ends the thread.
    pub(crate) stop: Arc<AtomicBool>,
    /// Whether the stage and the servo answer.
    pub(crate) status: Arc<RigStatus>,
    /// How scripts ended.
    pub(crate) script_ends: Arc<ScriptEnds>,
}

/// What the motion thread hands back.
#[derive(Debug)]
pub(crate) struct MotionReport {
    /// Moves started and refused, over every script.
    pub(crate) moves: MoveCounts,
}

/// Starts the motion thread on `rig` (see the module documentation): stage samples every
/// `stage_period`, base samples every `base_period`.
pub(crate) fn spawn_motion(
    rig: DaemonRig,
    clock: TrialClock,
    (stage_period, base_period): (Duration, Duration),
    events: EventSender,
    shared: MotionShared,
) -> std::io::Result<JoinHandle<MotionReport>> {
    std::thread::Builder::new()
        .name("antennad-motion".to_owned())
        .spawn(move || motion_loop(rig, clock, (stage_period, base_period), &events, &shared))
}

/// Notes from the motion thread: a repeated failure is sent once a second, not every sample.
pub(crate) struct Notes<'a> {
    events: &'a EventSender,
    last: Option<(String, Duration)>,
}

impl Notes<'_> {
    pub(crate) fn send(&mut self, now: Duration, text: String) {
        if let Some((last, at)) = &self.last
            && *last == text
            && now < *at + Duration::from_secs(1)
        {
            return;
        }
        self.send_always(now, text);
    }

    /// Sends `text` even if it repeats the last note (what a command did: each is said).
    pub(crate) fn send_always(&mut self, now: Duration, text: String) {
        self.last = Some((text.clone(), now));
        self.events.send(AcquisitionEvent::Note {
            t_ns: nanos(now),
            text,
        });
    }
}

fn nanos(d: Duration) -> u64 {
    u64::try_from(d.as_nanos()).unwrap_or(u64::MAX)
}

/// The motion thread's state besides the rig.
struct Motion<'a> {
    notes: Notes<'a>,
    script: Option<Script>,
    script_ends: &'a ScriptEnds,
    moves: MoveCounts,
    stage_ok: bool,
    servo_ok: bool,
    /// Since when the stage has been unavailable.
    stage_gone_since: Option<Duration>,
}

impl Motion<'_> {
    /// Ends the running script, if any, because `why` (its trial ends with that reason), and
    /// stops the stage.
    fn fail_script(&mut self, rig: &mut DaemonRig, now: Duration, why: String) {
        if self.script.is_some() {
            let _ = rig.stop(now);
            self.end_script(now, why);
        }
    }

    /// Ends the running script, if any, because `why`, leaving the stage alone.
    fn end_script(&mut self, now: Duration, why: String) {
        if let Some(script) = self.script.take() {
            self.notes.send(now, format!("trial script ended: {why}"));
            self.script_ends.set_failed(script.id, why);
        }
    }

    /// After any rig call: a home lost, a stage gone too long with moves left.
    fn check_stage(&mut self, rig: &mut DaemonRig, now: Duration) {
        if let Some(why) = rig.take_home_lost() {
            self.notes
                .send(now, format!("stage home lost, homing again: {why}"));
            // The script ends without a stop: the power cycle that lost the home stopped the
            // motor already, and the homing again may be under way by now (the loss is taken
            // here after the rig call that saw it, and a `step_homing` may have come between:
            // the script's own query can be the one that sees the echo). A stop would fail
            // that homing ("stopped"), and nothing would home the stage before the next trial.
            self.end_script(now, format!("the stage lost its home ({why})"));
        }
        if rig.stage_available() {
            self.stage_gone_since = None;
        } else {
            let since = *self.stage_gone_since.get_or_insert(now);
            if now.saturating_sub(since) >= STAGE_LOST_AFTER
                && self.script.as_ref().is_some_and(|s| !s.is_done())
            {
                let why = format!(
                    "the stage vanished ({}) with moves left and was not back within {} s",
                    rig.stage_description(),
                    STAGE_LOST_AFTER.as_secs_f64()
                );
                self.fail_script(rig, now, why);
            }
        }
    }
}

fn motion_loop(
    mut rig: DaemonRig,
    clock: TrialClock,
    (stage_period, base_period): (Duration, Duration),
    events: &EventSender,
    shared: &MotionShared,
) -> MotionReport {
    let MotionShared {
        commands,
        stop_pending,
        stop,
        status,
        script_ends,
    } = shared;
    let mut stage_schedule = Schedule::new(clock, stage_period);
    let mut base_schedule = Schedule::new(clock, base_period);
    let mut m = Motion {
        notes: Notes { events, last: None },
        script: None,
        script_ends,
        moves: MoveCounts::default(),
        stage_ok: true,
        servo_ok: true,
        stage_gone_since: None,
    };
    while !stop.load(Ordering::Relaxed) {
        if stop_pending.swap(false, Ordering::SeqCst) {
            let _ = stop_first(&mut rig, commands, clock.elapsed(), &mut m);
        }
        let stage_next = stage_schedule.next_deadline() <= base_schedule.next_deadline();
        let due = stage_schedule
            .next_deadline()
            .min(base_schedule.next_deadline());
        let now = clock.elapsed();
        if due > now {
            match commands.recv_timeout((due - now).min(Duration::from_millis(50))) {
                Ok(command) => {
                    let now = clock.elapsed();
                    if stop_pending.swap(false, Ordering::SeqCst) {
                        // The stop was queued behind this command: it goes first.
                        let kept = on_stop_pending(command);
                        let stopped = stop_first(&mut rig, commands, now, &mut m);
                        if let Some(MotionCommand::StopAll { reply }) = kept {
                            let _ = reply.send(stopped);
                        }
                    } else {
                        on_motion_command(&mut rig, command, now, &mut m);
                    }
                    check_availability(&rig, status, &mut m, now);
                    m.check_stage(&mut rig, now);
                    send_physics_steps(&mut rig, events);
                    continue;
                }
                Err(RecvTimeoutError::Timeout) => {
                    if clock.elapsed() < due {
                        continue;
                    }
                }
                Err(RecvTimeoutError::Disconnected) => {
                    std::thread::sleep(due - now);
                }
            }
        }
        let tick = if stage_next {
            stage_schedule.wait_next()
        } else {
            base_schedule.wait_next()
        };
        let now = tick.woke;
        if stage_next {
            match rig.step_homing(now) {
                Ok(Some(text)) => m.notes.send(now, text),
                Ok(None)
                | Err(RigError::Device(
                    DeviceError::Unavailable { .. } | DeviceError::NotHomed(_),
                )) => {}
                Err(e) => m.notes.send(now, format!("homing the stage: {e}")),
            }
            match rig.stage_mm(now) {
                Ok(position_mm) => events.send(AcquisitionEvent::Stage {
                    t_ns: nanos(now),
                    position_mm,
                }),
                Err(RigError::Device(
                    DeviceError::Unavailable { .. }
                    | DeviceError::NotHomed(_)
                    | DeviceError::HomingFailed(_),
                )) => {}
                Err(e) => m
                    .notes
                    .send(now, format!("stage position unavailable: {e}")),
            }
        } else {
            match rig.base_angle_rad(now) {
                Ok(angle_rad) => events.send(AcquisitionEvent::Base {
                    t_ns: nanos(now),
                    angle_rad,
                }),
                Err(RigError::Device(DeviceError::Unavailable { .. })) => {}
                Err(e) => m.notes.send(now, format!("base angle unavailable: {e}")),
            }
        }
        m.check_stage(&mut rig, now);
        let mut script_done = None;
        if let Some(s) = &mut m.script {
            match s.step(&mut rig, now, &mut m.notes, &mut m.moves) {
                Ok(()) => {
                    if s.is_done() {
                        script_done = Some(s.id);
                    }
                }
                Err(why) => m.fail_script(&mut rig, now, why),
            }
        }
        check_availability(&rig, status, &mut m, now);
        send_physics_steps(&mut rig, events);
        // Done only once this tick's samples and physics steps are sent: the hub, seeing the
        // script done, drains the channel once more before it ends the trial, so the trial
        // holds the last stage sample.
        if let Some(id) = script_done {
            m.script_ends.set_done(id);
        }
    }
    if let Err(e) = rig.stop(clock.elapsed()) {
        m.notes
            .send(clock.elapsed(), format!("stopping the stage failed: {e}"));
    }
    MotionReport { moves: m.moves }
}

/// The simulated antenna's placements and steps since the last call, as events (each
/// recorded during a trial).
fn send_physics_steps(rig: &mut DaemonRig, events: &EventSender) {
    for (at, step) in rig.take_physics_steps() {
        events.send(AcquisitionEvent::Physics {
            t_ns: nanos(at),
            step: Box::new(step),
        });
    }
}

/// A command that was queued ahead of a `stop_all`: a move or a base angle is cancelled
/// (answered so), a script is dropped; a stop is kept to be answered.
fn on_stop_pending(command: MotionCommand) -> Option<MotionCommand> {
    match command {
        MotionCommand::Move { reply, .. } | MotionCommand::SetBase { reply, .. } => {
            let _ = reply.send(Err(
                "cancelled: a stop_all came before it was carried out".to_owned()
            ));
            None
        }
        MotionCommand::RunScript { .. } | MotionCommand::EndScript => None,
        stop @ MotionCommand::StopAll { .. } => Some(stop),
    }
}

/// Carries out a `stop_all` before anything else: stops the stage and the script, and
/// answers every command queued before the stop (moves cancelled, stops done).
fn stop_first(
    rig: &mut DaemonRig,
    commands: &Receiver<MotionCommand>,
    now: Duration,
    m: &mut Motion<'_>,
) -> Result<String, String> {
    let stopped = stop_all(rig, now, m);
    while let Ok(command) = commands.try_recv() {
        if let Some(MotionCommand::StopAll { reply }) = on_stop_pending(command) {
            let _ = reply.send(stopped.clone());
        }
    }
    stopped
}

/// Drops the script and stops the stage.
fn stop_all(rig: &mut DaemonRig, now: Duration, m: &mut Motion<'_>) -> Result<String, String> {
    m.script = None;
    let stopped = match rig.stop(now) {
        Ok(()) => Ok("stage stopped".to_owned()),
        Err(e) => Err(format!("stopping the stage failed: {e}")),
    };
    let (Ok(text) | Err(text)) = &stopped;
    // Every stop_all is said, however soon after the last.
    m.notes.send_always(now, format!("stop_all: {text}"));
    stopped
}

fn check_availability(rig: &DaemonRig, status: &RigStatus, m: &mut Motion<'_>, now: Duration) {
    let stage = rig.stage_available();
    if stage != m.stage_ok {
        m.stage_ok = stage;
        status.stage.store(stage, Ordering::Relaxed);
        m.notes.send(
            now,
            if stage {
                format!(
                    "stage back: {} reopened and on line; stage samples resume",
                    rig.stage_description()
                )
            } else {
                format!(
                    "stage unavailable: {} vanished; polling and recording go on without stage \
                     samples, reopening it every {} ms",
                    rig.stage_description(),
                    crate::service::rig::REOPEN_INTERVAL.as_millis()
                )
            },
        );
    }
    let servo = rig.servo_available();
    if servo != m.servo_ok {
        m.servo_ok = servo;
        status.servo.store(servo, Ordering::Relaxed);
        m.notes.send(
            now,
            if servo {
                format!("servo back: {} reopened", rig.servo_description())
            } else {
                format!(
                    "servo unavailable: {} vanished; polling and recording go on without base \
                     samples, reopening it every {} ms",
                    rig.servo_description(),
                    crate::service::rig::REOPEN_INTERVAL.as_millis()
                )
            },
        );
    }
}

fn on_motion_command(
    rig: &mut DaemonRig,
    command: MotionCommand,
    now: Duration,
    m: &mut Motion<'_>,
) {
    match command {
        MotionCommand::RunScript { id, trial } => {
            // A homing that failed (or was stopped) is tried again for the trial.
            rig.retry_homing();
            if let Err(e) = rig.set_base_angle_rad(trial.base_angle_deg.to_radians(), now) {
                m.notes.send(now, format!("base angle refused: {e}"));
            }
            m.script = Some(Script::new(id, trial));
        }
        MotionCommand::EndScript => {
            if m.script.take().is_some()
                && let Err(e) = rig.stop(now)
            {
                m.notes.send(now, format!("stopping the stage failed: {e}"));
            }
        }
        MotionCommand::Move {
            target,
            speed_mm_per_s,
            reply,
        } => {
            let result = match target {
                MoveTarget::To(mm) => rig.start_move_to_mm(mm, speed_mm_per_s, now),
                MoveTarget::By(mm) => rig.start_move_mm(mm, speed_mm_per_s, now),
            };
            let answer = match result {
                Ok(()) => {
                    let text = match target {
                        MoveTarget::To(mm) => {
                            format!("stage moving to {mm:.1} mm at {speed_mm_per_s} mm/s")
                        }
                        MoveTarget::By(mm) => {
                            format!("stage moving {mm:+.1} mm at {speed_mm_per_s} mm/s")
                        }
                    };
                    m.notes.send(now, text.clone());
                    Ok(text)
                }
                Err(e) => {
                    let text = format!("move_stage refused: {e}");
                    m.notes.send(now, text.clone());
                    Err(text)
                }
            };
            let _ = reply.send(answer);
        }
        MotionCommand::SetBase { angle_deg, reply } => {
            let answer = match rig.set_base_angle_rad(angle_deg.to_radians(), now) {
                Ok(()) => Ok(format!("base angle set to {angle_deg} deg")),
                Err(e) => Err(format!("set_base_angle refused: {e}")),
            };
            let (Ok(text) | Err(text)) = &answer;
            m.notes.send(now, text.clone());
            let _ = reply.send(answer);
        }
        MotionCommand::StopAll { reply } => {
            let _ = reply.send(stop_all(rig, now, m));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Config;
    use crate::hardware::homing::HomingState;
    use crate::service::acquisition::event_channel;
    use crate::sim::emulator::VxmEmulator;
    use serialport::{SerialPort, TTYPort};
    use std::time::Instant;

    /// Only a hang takes this long, however loaded the machine.
    const PATIENCE: Duration = Duration::from_secs(60);

    fn step_until(rig: &mut DaemonRig, what: &str) {
        let deadline = Instant::now() + PATIENCE;
        loop {
            if let Ok(Some(text)) = rig.step_homing(Duration::ZERO)
                && text.contains(what)
            {
                return;
            }
            assert!(Instant::now() < deadline, "no {what:?}");
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    #[test]
    fn a_home_lost_mid_trial_ends_its_script_but_not_the_homing_that_follows() {
        let (master, slave) = TTYPort::pair().unwrap();
        let path = slave.name().unwrap();
        drop(slave);
        let vxm = VxmEmulator::spawn(master);
        let mut config = Config::default();
        config.stage.port = path;
        config.stage.reply_timeout_ms = 2000;
        config.stage.steps_per_mm = 80.0;
        config.stage.max_mm = 60.0;
        config.stage.homing_speed_mm_per_s = 40.0;
        config.servo.port = "sim".to_owned();
        let mut rig = DaemonRig::open(&config, None).unwrap();
        step_until(&mut rig, "homing the stage");
        step_until(&mut rig, "stage homed");

        let (events, _received) = event_channel(1024);
        let script_ends = ScriptEnds::default();
        let mut m = Motion {
            notes: Notes {
                events: &events,
                last: None,
            },
            script: Some(Script::new(1, Box::new(config.trials[0].clone()))),
            script_ends: &script_ends,
            moves: MoveCounts::default(),
            stage_ok: true,
            servo_ok: true,
            stage_gone_since: None,
        };
        rig.start_move_mm(50.0, 5.0, Duration::ZERO).unwrap();
        let deadline = Instant::now() + PATIENCE;
        while !vxm.is_busy() {
            assert!(Instant::now() < deadline, "the move never started");
            std::thread::sleep(Duration::from_millis(5));
        }
        vxm.power_cycle();
        // The script's own query sees the echo, and the loop's next homing step comes before
        // the loss is taken: the order that used to leave the stage unhomed for good.
        let moving = rig.stage_moving(Duration::ZERO);
        assert!(
            matches!(moving, Err(RigError::Device(DeviceError::NotHomed(_)))),
            "{moving:?}"
        );
        assert!(
            rig.step_homing(Duration::ZERO)
                .unwrap()
                .is_some_and(|text| text.contains("homing the stage"))
        );
        m.check_stage(&mut rig, Duration::ZERO);
        assert!(m.script.is_none());
        assert!(
            script_ends
                .failure(1)
                .is_some_and(|why| why.contains("lost its home")),
        );
        assert_eq!(rig.homing_state(), HomingState::Homing);
        step_until(&mut rig, "stage homed");
        assert_eq!(vxm.negative_limit_steps(), 0);
        assert_eq!(vxm.position_steps(), 0);
    }
}
