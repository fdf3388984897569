//! The hub thread: every acquisition event is streamed, recorded during a trial and
//! summed into the segments' health; it runs the trials (start, end, free space), watches
//! the polling thread's heartbeat and publishes the status.

use super::control::HubRequest;
use super::recording::{Recorded, RecordingThread};
use super::start::PollTotals;
use super::trial::ActiveTrial;
use super::{DaemonOptions, Log, TrialOutcome};
use crate::config::Config;
use crate::hardware::poll::{PollError, SegmentHealth};
use crate::net::foxglove::FoxgloveLive;
use crate::net::{ControlToken, StreamServer};
use crate::service::acquisition::{
    AcquisitionEvent, FirmwareReading, HealthChange, PollRecord, Shared,
};
use crate::service::clock::TrialClock;
use crate::service::estimate::{LiveEstimate, PollInput};
use crate::service::motion::{MotionCommand, RigStatus};
use crate::service::samples::{record_sample, stream_sample};
use crate::service::trial_script::ScriptEnds;
use crate::service::watchdog::{PollWatchdog, WatchdogEvent};
use crate::sim::rig::{SensedPoses, SimState, StepKind};
use antenna_data::record::EstimateMessage as RecordedEstimate;
use antenna_data::record::{
    LogMessage, PhysicsStepKind, PhysicsStepMessage, SegmentsMessage, ServoMessage, StageMessage,
};
use antenna_data::stream::{
    EstimateMessage, PollingStatus, SegmentSample, SegmentStatus, StreamMessage,
};
use antenna_protocol::{Calibration, FIRMWARE_VERSION, StatusFlags};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, Sender};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// The names of the status register's flags that are set, e.g. `["ADC fault"]`.
fn flag_names(flags: StatusFlags) -> Vec<String> {
    let mut names = Vec::new();
    if flags.adc_fault() {
        names.push("ADC fault (angle sensor on a rail)".to_owned());
    }
    if flags.touch_stuck() {
        names.push("touch switch stuck closed".to_owned());
    }
    if flags.address_not_set() {
        names.push("address not assigned".to_owned());
    }
    let unknown = flags.bits() & !StatusFlags::DEFINED;
    if unknown != 0 {
        names.push(format!("unknown flags {unknown:#04x}"));
    }
    names
}

pub(super) struct Hub {
    /// Unix-epoch nanoseconds of the clock's origin: a poll's `t_ns` plus this is its
    /// wall-clock time (the recordings' log times).
    pub(super) unix_origin_ns: u64,
    /// Never recorded: anything a client asks to record is scrubbed of it.
    pub(super) token: ControlToken,
    /// When the free space under the data directory is looked at next during a trial.
    pub(super) free_check_due: Instant,
    pub(super) config: Config,
    pub(super) options: DaemonOptions,
    pub(super) clock: TrialClock,
    pub(super) calibrations: Vec<Calibration>,
    pub(super) server: Option<StreamServer>,
    /// The Foxglove WebSocket server, if it runs.
    pub(super) foxglove: Option<FoxgloveLive>,
    pub(super) log: Log,
    pub(super) trial: Option<ActiveTrial>,
    pub(super) trial_state: Arc<Mutex<Option<String>>>,
    pub(super) next_trial_id: u64,
    pub(super) motion: Sender<MotionCommand>,
    pub(super) script_ends: Arc<ScriptEnds>,
    pub(super) rig_status: Arc<RigStatus>,
    pub(super) stage_mm: Option<f64>,
    pub(super) base_rad: Option<f64>,
    pub(super) health: Vec<SegmentStatus>,
    pub(super) note: Option<String>,
    pub(super) status_due: Instant,
    pub(super) outcomes: Vec<TrialOutcome>,
    pub(super) finished: bool,
    /// The simulated rig's physics (its contact solver's relaxations are logged).
    pub(super) sim_state: Option<Shared<SimState>>,
    /// The poses the simulated segments sensed, by poll (the estimate's truth).
    pub(super) sensed_poses: Option<Arc<SensedPoses>>,
    /// The live wall estimate (`None` with `[estimate] estimator = "none"`).
    pub(super) estimate: Option<LiveEstimate>,
    /// Relaxed steps of the simulation already logged.
    pub(super) sim_relaxed_logged: u64,
    /// Watches the polling thread's heartbeat.
    pub(super) watchdog: PollWatchdog,
    /// The latest poll wake-up after its deadline, as the hub saw the polls.
    pub(super) max_lateness_seen: Duration,
}

impl Hub {
    pub(super) fn run(
        &mut self,
        receiver: &Receiver<AcquisitionEvent>,
        requests: &Receiver<HubRequest>,
        stop: &AtomicBool,
    ) {
        let mut watchdog_due = Instant::now();
        while !stop.load(Ordering::Relaxed) && !self.finished {
            // The hub proves the daemon alive: wedged, it stops the pings.
            if let Some(watchdog) = &self.options.watchdog
                && Instant::now() >= watchdog_due
            {
                watchdog_due = Instant::now() + watchdog.ping_every();
                if let Err(e) = watchdog.ping() {
                    tracing::warn!(target: "antennad", "watchdog ping failed: {e}");
                }
            }
            if let Ok(event) = receiver.recv_timeout(Duration::from_millis(10)) {
                self.on_event(&event);
                self.drain(receiver);
            }
            while let Ok(request) = requests.try_recv() {
                self.on_request(request);
            }
            self.check_watchdog();
            self.check_recording();
            // A script that ended sent its last samples first: take them into the trial
            // before it ends (they may have come after the drain above).
            if self.trial_script_ended() {
                self.drain(receiver);
            }
            self.check_trial_end();
            if Instant::now() >= self.status_due {
                self.publish_status();
            }
        }
    }

    /// Looks at the polling thread's heartbeat: a stall starting or ending is logged,
    /// recorded in the trial and sent in a status line.
    fn check_watchdog(&mut self) {
        let now_ns = self.clock.elapsed_ns();
        let Some(event) = self.watchdog.check(now_ns) else {
            return;
        };
        let text = match event {
            WatchdogEvent::Stalled {
                last_poll_ns,
                silent,
            } => format!(
                "polling stalled: no poll since t = {:.3} s, {} ms ago (bound {} ms); the \
                 polling thread is stuck, most likely in an I2C transfer that does not return; \
                 no samples until it does",
                self.t_s(last_poll_ns),
                silent.as_millis(),
                self.watchdog.status(now_ns).bound.as_millis()
            ),
            WatchdogEvent::Resumed {
                stalled_for,
                missed_deadlines,
            } => format!(
                "polling resumed after {} ms without a poll; {missed_deadlines} poll deadlines \
                 missed",
                stalled_for.as_millis()
            ),
        };
        self.log
            .line(format!("{:7.2}   -- {text}", self.t_s(now_ns)));
        self.record_log(now_ns, &text);
        self.note = Some(text);
        self.publish_status();
    }

    /// The polling thread did not stop within `waited` (stuck in a transfer): said in the
    /// log and, before it is finalized, in the running trial's recording.
    pub(super) fn poll_thread_left_behind(&mut self, waited: Duration) {
        let now_ns = self.clock.elapsed_ns();
        let text = format!(
            "the polling thread did not stop within {} ms (last poll at t = {:.3} s; stuck in a \
             bus transfer): left behind, the recording is finalized without it",
            waited.as_millis(),
            self.t_s(self.watchdog.heartbeat().last_poll_ns())
        );
        self.log.line(format!("antennad: {text}"));
        self.record_log(now_ns, &text);
    }

    /// Polls, deadlines skipped, the latest wake-up and the health per segment as the hub
    /// counted them (for a polling thread that never reported; `stale` counts polls made
    /// while the segment was stale).
    pub(super) fn totals_seen(&self) -> PollTotals {
        let heartbeat = self.watchdog.heartbeat();
        let health = self
            .health
            .iter()
            .map(|s| SegmentHealth {
                ok: s.ok,
                nacks: s.nack,
                pec_errors: s.pec_error,
                bus_errors: s.bus_error,
                stale: s.stale,
            })
            .collect();
        (
            heartbeat.polls(),
            heartbeat.missed_deadlines(),
            self.max_lateness_seen,
            health,
        )
    }

    /// Whether the running trial's script is done or failed.
    fn trial_script_ended(&self) -> bool {
        self.trial.as_ref().is_some_and(|t| {
            self.script_ends.is_done(t.id) || self.script_ends.failure(t.id).is_some()
        })
    }

    pub(super) fn drain(&mut self, receiver: &Receiver<AcquisitionEvent>) {
        while let Ok(event) = receiver.try_recv() {
            self.on_event(&event);
        }
    }

    pub(super) fn finish(&mut self) {
        if self.trial.is_some() {
            self.end_trial("the daemon stopped");
        }
        if let Some(server) = self.server.take() {
            server.shutdown();
        }
        if let Some(foxglove) = self.foxglove.take() {
            foxglove.stop();
        }
    }

    /// Sends `message` to every stream client (TCP and Foxglove); never blocks on a socket.
    pub(super) fn publish(&mut self, message: &StreamMessage) {
        if let Some(server) = &self.server {
            server.publish(message);
        }
        if let Some(foxglove) = &mut self.foxglove {
            foxglove.publish(message);
        }
    }

    pub(super) fn t_s(&self, t_ns: u64) -> f64 {
        t_ns as f64 * 1e-9
    }

    /// Records the message `make` builds from the trial time if a trial runs and `t_ns` is
    /// inside it: handed to the recording's thread, never waited for.
    pub(super) fn record(&mut self, t_ns: u64, make: impl FnOnce(f64) -> Recorded) {
        let Some(trial) = &mut self.trial else { return };
        if t_ns < trial.start_ns {
            return;
        }
        let t_s = (t_ns - trial.start_ns) as f64 * 1e-9;
        if let Some(recording) = &mut trial.recorder {
            recording.record(make(t_s));
        }
    }

    /// Hands the recording its waiting messages when they are due; a recording that failed
    /// (a write refused, a stalled disk) ends its trial.
    fn check_recording(&mut self) {
        if let Some(recording) = self.trial.as_mut().and_then(|t| t.recorder.as_mut()) {
            recording.hand_over_if_due();
        }
        let failure = self
            .trial
            .as_ref()
            .and_then(|t| t.recorder.as_ref())
            .and_then(RecordingThread::failure);
        if let Some(why) = failure {
            self.log.error(format!(
                "antennad: recording failed, ending the trial: {why}"
            ));
            self.end_trial("the recording failed");
        }
    }

    fn on_event(&mut self, event: &AcquisitionEvent) {
        if let Some(tap) = &self.options.on_event {
            (tap.0)(event);
        }
        match event {
            AcquisitionEvent::Poll(poll) => self.on_poll(poll),
            AcquisitionEvent::Stage { t_ns, position_mm } => {
                self.stage_mm = Some(*position_mm);
                let position_m = position_mm * 1e-3;
                self.record(*t_ns, |t_s| {
                    Recorded::Stage(StageMessage { t_s, position_m })
                });
            }
            AcquisitionEvent::Base { t_ns, angle_rad } => {
                self.base_rad = Some(*angle_rad);
                let base_angle_rad = *angle_rad;
                self.record(*t_ns, |t_s| {
                    Recorded::Servo(ServoMessage {
                        t_s,
                        base_angle_rad,
                    })
                });
            }
            AcquisitionEvent::Physics { t_ns, step } => {
                self.record(*t_ns, |t_s| {
                    Recorded::Physics(PhysicsStepMessage {
                        t_s,
                        kind: match step.kind {
                            StepKind::Place => PhysicsStepKind::Place,
                            StepKind::Step => PhysicsStepKind::Step,
                        },
                        stage_m: step.stage_m,
                        base_x_m: step.pose.base_m.x,
                        base_y_m: step.pose.base_m.y,
                        base_angle_rad: step.pose.base_angle_rad,
                        joint_angles_rad: step.joint_angles_rad.clone(),
                    })
                });
            }
            AcquisitionEvent::Health {
                t_ns,
                address,
                change,
            } => {
                let text = match change {
                    HealthChange::Stale => {
                        format!("segment {address:#04x}: counter stopped (stale)")
                    }
                    HealthChange::Recovered => {
                        format!("segment {address:#04x}: counter moving again")
                    }
                };
                let line = format!("{:7.2}   -- {text}", self.t_s(*t_ns));
                match change {
                    HealthChange::Stale => self.log.warn(line),
                    HealthChange::Recovered => self.log.line(line),
                }
                self.record_log(*t_ns, &text);
                self.note = Some(text);
                self.publish_status();
            }
            AcquisitionEvent::Note { t_ns, text } => {
                self.log
                    .line(format!("{:7.2}   -- {text}", self.t_s(*t_ns)));
                self.record_log(*t_ns, text);
                self.note = Some(text.clone());
                self.publish_status();
            }
            AcquisitionEvent::Firmware {
                t_ns,
                address,
                reading,
            } => self.on_firmware(*t_ns, *address, *reading),
        }
    }

    /// A firmware register read: kept in the segment's status; a change of its flags, or a
    /// version other than the one this antennad speaks, is logged and recorded.
    fn on_firmware(&mut self, t_ns: u64, address: u8, reading: FirmwareReading) {
        let Some(status) = self.health.iter_mut().find(|s| s.address == address) else {
            return;
        };
        let text = match reading {
            FirmwareReading::Status(flags) => {
                let previous = status.status_flags.replace(flags.bits());
                if previous.unwrap_or(0) == flags.bits() {
                    return;
                }
                let names = flag_names(flags);
                if names.is_empty() {
                    format!("segment {address:#04x}: firmware status clear again")
                } else {
                    format!("segment {address:#04x} reports {}", names.join(", "))
                }
            }
            FirmwareReading::Version(major, minor) => {
                let version = format!("{major}.{minor}");
                let previous = status.firmware_version.replace(version.clone());
                if previous.as_ref() == Some(&version) || (major, minor) == FIRMWARE_VERSION {
                    return;
                }
                format!(
                    "segment {address:#04x} runs firmware {version}; this antennad speaks \
                     protocol {}.{}",
                    FIRMWARE_VERSION.0, FIRMWARE_VERSION.1
                )
            }
            FirmwareReading::Unread(_) => return,
        };
        self.log.line(format!("{:7.2}   -- {text}", self.t_s(t_ns)));
        self.record_log(t_ns, &text);
        self.note = Some(text);
        self.publish_status();
    }

    pub(super) fn record_log(&mut self, t_ns: u64, text: &str) {
        self.record(t_ns, |t_s| {
            Recorded::Log(LogMessage {
                t_s,
                text: text.to_owned(),
            })
        });
    }

    /// Logs what the simulation's contact solver relaxed since the last poll (a line per
    /// relaxed step, with the stage position).
    fn log_sim_relaxations(&mut self) {
        let Some(state) = &self.sim_state else {
            return;
        };
        let (relaxed, said) = match state.lock() {
            Ok(s) => (s.relaxed_steps, s.relaxations.join(", ")),
            Err(_) => return,
        };
        if relaxed > self.sim_relaxed_logged {
            self.sim_relaxed_logged = relaxed;
            let at = self
                .stage_mm
                .map_or_else(String::new, |mm| format!(" at stage {mm:.1} mm"));
            self.log.line(format!(
                "antennad: simulation{at}: the contact solver relaxed a step ({said}); \
                 {relaxed} relaxed step(s) so far"
            ));
        }
    }

    fn on_poll(&mut self, poll: &PollRecord) {
        self.log_sim_relaxations();
        self.max_lateness_seen = self.max_lateness_seen.max(Duration::from_nanos(
            poll.t_ns.saturating_sub(poll.deadline_ns),
        ));
        for (k, (reading, status)) in poll.readings.iter().zip(&mut self.health).enumerate() {
            match reading.result {
                Ok(_) => status.ok += 1,
                Err(PollError::Nack { .. }) => status.nack += 1,
                Err(PollError::Corrupted { .. }) => status.pec_error += 1,
                Err(PollError::Bus { .. }) => status.bus_error += 1,
            }
            if poll.is_stale(k) {
                status.stale += 1;
            }
        }
        if !self.rig_status.stage.load(Ordering::Relaxed) {
            self.stage_mm = None;
        }
        if !self.rig_status.servo.load(Ordering::Relaxed) {
            self.base_rad = None;
        }
        let streamed = self.server.is_some() || self.foxglove.is_some();
        if streamed || self.estimate.is_some() {
            let segments: Vec<SegmentSample> = poll
                .readings
                .iter()
                .zip(&self.calibrations)
                .enumerate()
                .map(|(k, (r, c))| stream_sample(r, *c, poll.is_stale(k)))
                .collect();
            let estimate = self.estimate_at(poll, &segments);
            if streamed {
                self.publish(&StreamMessage::Samples {
                    seq: poll.seq,
                    t_ns: poll.t_ns,
                    segments,
                    stage_position_m: self.stage_mm.map(|mm| mm * 1e-3),
                    base_angle_deg: self.base_rad.map(f64::to_degrees),
                });
            }
            if let Some(estimate) = estimate {
                let recorded = RecordedEstimate {
                    t_s: 0.0,
                    seq: estimate.seq,
                    estimator: estimate.estimator.clone(),
                    distance_m: estimate.distance_m,
                    wall_angle_rad: estimate.angle_rad,
                    preview_m: estimate.preview_m,
                    reason: estimate.reason.clone(),
                    true_distance_m: estimate.true_distance_m,
                    true_angle_rad: estimate.true_angle_rad,
                };
                let t_ns = estimate.t_ns;
                if streamed {
                    self.publish(&StreamMessage::Estimate(estimate));
                }
                self.record(t_ns, |t_s| {
                    Recorded::Estimate(RecordedEstimate { t_s, ..recorded })
                });
            }
        }
        let calibrations = self.calibrations.clone();
        let seq = poll.seq;
        self.record(poll.t_ns, |t_s| {
            Recorded::Segments(SegmentsMessage {
                seq: Some(seq),
                t_s,
                segments: poll
                    .readings
                    .iter()
                    .zip(&calibrations)
                    .enumerate()
                    .map(|(k, (r, &c))| record_sample(r, c, poll.is_stale(k)))
                    .collect(),
            })
        });
        if self.options.echo
            && let Some(trial) = &self.trial
            && poll.t_ns >= trial.start_ns
            && poll.seq.is_multiple_of(trial.print_every)
        {
            let t_s = (poll.t_ns - trial.start_ns) as f64 * 1e-9;
            self.log
                .sample(sample_line(t_s, self.stage_mm, poll, &self.calibrations));
        }
    }

    /// Feeds `poll` to the live wall estimate; the estimate when one is due.
    fn estimate_at(
        &mut self,
        poll: &PollRecord,
        segments: &[SegmentSample],
    ) -> Option<EstimateMessage> {
        let estimate = self.estimate.as_mut()?;
        let solved_at = self
            .sensed_poses
            .as_ref()
            .and_then(|poses| poses.take_at(poll.t_ns));
        let clock = self.clock;
        estimate.on_poll(
            &PollInput {
                seq: poll.seq,
                t_ns: poll.t_ns,
                segments,
                stage_m: self.stage_mm.map(|mm| mm * 1e-3),
                servo_rad: self.base_rad,
                solved_at,
            },
            || clock.elapsed_ns(),
        )
    }

    pub(super) fn publish_status(&mut self) {
        self.status_due = Instant::now() + Duration::from_secs(1);
        if self.server.is_none() && self.foxglove.is_none() {
            return;
        }
        let mut notes = Vec::new();
        if !self.rig_status.stage.load(Ordering::Relaxed) {
            notes.push("stage unavailable".to_owned());
        }
        if !self.rig_status.servo.load(Ordering::Relaxed) {
            notes.push("servo unavailable".to_owned());
        }
        let now_ns = self.clock.elapsed_ns();
        let polling = self.watchdog.status(now_ns);
        if polling.stalled {
            notes.push(format!(
                "polling stalled for {} ms",
                polling.since_last_poll.as_millis()
            ));
        }
        for segment in &self.health {
            let names = flag_names(StatusFlags::from_bits(segment.status_flags.unwrap_or(0)));
            if !names.is_empty() {
                notes.push(format!(
                    "segment {:#04x}: {}",
                    segment.address,
                    names.join(", ")
                ));
            }
        }
        if let Some(note) = self.note.take() {
            notes.push(note);
        }
        self.publish(&StreamMessage::Status {
            t_ns: now_ns,
            trial: self.trial.as_ref().map(|t| t.name.clone()),
            segments: self.health.clone(),
            note: (!notes.is_empty()).then(|| notes.join("; ")),
            polling: Some(PollingStatus {
                stalled: polling.stalled,
                since_last_poll_ms: u64::try_from(polling.since_last_poll.as_millis())
                    .unwrap_or(u64::MAX),
                stall_after_ms: u64::try_from(polling.bound.as_millis()).unwrap_or(u64::MAX),
                polls: polling.polls,
                missed_deadlines: polling.missed_deadlines,
                stalls: polling.stalls,
            }),
        });
    }
}

/// `   1.25    37.5   -3.1  -2.9 ...   ....#` : trial time, stage, angles, touch marks.
fn sample_line(
    t_s: f64,
    stage_mm: Option<f64>,
    poll: &PollRecord,
    calibrations: &[Calibration],
) -> String {
    let mut angles = String::new();
    let mut touches = String::new();
    for (k, (reading, calibration)) in poll.readings.iter().zip(calibrations).enumerate() {
        match reading.result {
            Ok(word) => {
                let deg = calibration.angle_rad(word.angle_counts()).to_degrees();
                angles.push_str(&format!("{deg:6.1}"));
                touches.push(if poll.is_stale(k) {
                    's'
                } else if word.touch().any() {
                    '#'
                } else {
                    '.'
                });
            }
            Err(_) => {
                angles.push_str("   ---");
                touches.push('?');
            }
        }
    }
    let stage = stage_mm.map_or("     ---".to_owned(), |mm| format!("{mm:8.1}"));
    format!("{t_s:7.2} {stage} {angles}   {touches}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn status_flags_are_named() {
        assert!(flag_names(StatusFlags::from_bits(0)).is_empty());
        assert_eq!(
            flag_names(StatusFlags::from_bits(
                StatusFlags::ADC_FAULT | StatusFlags::ADDRESS_NOT_SET | 0x80
            )),
            [
                "ADC fault (angle sensor on a rail)",
                "address not assigned",
                "unknown flags 0x80"
            ]
        );
    }
}
