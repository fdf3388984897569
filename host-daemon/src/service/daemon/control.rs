//! Control commands from any client thread ([`ControlHandler`]): the trial commands go to
//! the hub, the motion commands to the motion thread, `stop_all` through the VXM's kill line
//! first (see the control rule in [`super`]).

use super::CONTROL_TIMEOUT;
use crate::hardware::vxm::VxmKill;
use crate::net::ControlHandler;
use crate::service::motion::{MotionCommand, MoveTarget, Reply};
use antenna_data::stream::{ControlCommand, StageTarget};
use anyhow::Result;
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Sender, sync_channel};
use std::sync::{Arc, Mutex};

pub(super) enum HubRequest {
    Start {
        name: String,
        metadata: BTreeMap<String, String>,
        reply: Reply,
    },
    Stop {
        why: &'static str,
        reply: Reply,
    },
}

pub(super) fn ask<T>(sender: &Sender<T>, make: impl FnOnce(Reply) -> T) -> Result<String, String> {
    let (reply, answer) = sync_channel(1);
    sender
        .send(make(reply))
        .map_err(|_| "the daemon is shutting down".to_owned())?;
    answer
        .recv_timeout(CONTROL_TIMEOUT)
        .map_err(|_| "the daemon did not answer in time".to_owned())?
}

/// The control commands, from any client thread.
pub(super) struct DaemonControl {
    pub(super) hub: Mutex<Sender<HubRequest>>,
    pub(super) motion: Mutex<Sender<MotionCommand>>,
    pub(super) trial: Arc<Mutex<Option<String>>>,
    pub(super) max_speed_mm_per_s: f64,
    /// Set by `stop_all` before its command is queued: the motion thread stops before it
    /// carries out anything else, and cancels the moves queued ahead of the stop.
    pub(super) stop_pending: Arc<AtomicBool>,
    /// The VXM's kill line: `stop_all` sends `K` through it from the client's thread first,
    /// so the kill never waits behind a query the motion thread is waiting on.
    pub(super) stage_kill: Option<VxmKill>,
}

impl DaemonControl {
    fn hub(&self) -> Result<Sender<HubRequest>, String> {
        self.hub
            .lock()
            .map(|s| s.clone())
            .map_err(|_| "the daemon is shutting down".to_owned())
    }

    fn motion(&self) -> Result<Sender<MotionCommand>, String> {
        self.motion
            .lock()
            .map(|s| s.clone())
            .map_err(|_| "the daemon is shutting down".to_owned())
    }

    fn refuse_during_trial(&self, what: &str) -> Result<(), String> {
        match self.trial.lock().ok().and_then(|t| t.clone()) {
            Some(name) => Err(format!(
                "{what} refused: trial {name:?} is running and its script drives the stage and \
                 the base; send stop_trial (or stop_all) first"
            )),
            None => Ok(()),
        }
    }
}

impl ControlHandler for DaemonControl {
    fn handle(&self, command: ControlCommand) -> Result<String, String> {
        match command {
            ControlCommand::StartTrial { name, metadata } => {
                ask(&self.hub()?, |reply| HubRequest::Start {
                    name,
                    metadata,
                    reply,
                })
            }
            ControlCommand::StopTrial => ask(&self.hub()?, |reply| HubRequest::Stop {
                why: "stop_trial",
                reply,
            }),
            ControlCommand::MoveStage {
                target,
                speed_m_per_s,
            } => {
                self.refuse_during_trial("move_stage")?;
                let speed_mm_per_s =
                    speed_m_per_s.map_or(self.max_speed_mm_per_s / 2.0, |v| v * 1e3);
                if speed_mm_per_s > self.max_speed_mm_per_s {
                    return Err(format!(
                        "move_stage refused: {speed_mm_per_s} mm/s is faster than \
                         stage.max_speed_mm_per_s = {} mm/s",
                        self.max_speed_mm_per_s
                    ));
                }
                let target = match target {
                    StageTarget::Absolute { position_m } => MoveTarget::To(position_m * 1e3),
                    StageTarget::Relative { distance_m } => MoveTarget::By(distance_m * 1e3),
                };
                ask(&self.motion()?, |reply| MotionCommand::Move {
                    target,
                    speed_mm_per_s,
                    reply,
                })
            }
            ControlCommand::SetBaseAngle { angle_deg } => {
                self.refuse_during_trial("set_base_angle")?;
                ask(&self.motion()?, |reply| MotionCommand::SetBase {
                    angle_deg,
                    reply,
                })
            }
            ControlCommand::StopAll => {
                if let Some(kill) = &self.stage_kill {
                    // Best effort: the motion thread kills again through the driver.
                    let _ = kill.kill();
                }
                self.stop_pending.store(true, Ordering::SeqCst);
                let stopped = ask(&self.motion()?, |reply| MotionCommand::StopAll { reply });
                let ended = ask(&self.hub()?, |reply| HubRequest::Stop {
                    why: "stop_all",
                    reply,
                });
                let stopped = stopped?;
                Ok(match ended {
                    Ok(ended) => format!("{stopped}; {ended}"),
                    Err(_) => format!("{stopped}; no trial was running"),
                })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::mpsc::{Receiver, channel};

    /// A control handler whose hub and motion thread are these receivers.
    fn control(
        trial: Option<&str>,
    ) -> (DaemonControl, Receiver<HubRequest>, Receiver<MotionCommand>) {
        let (hub, hub_rx) = channel();
        let (motion, motion_rx) = channel();
        let control = DaemonControl {
            hub: Mutex::new(hub),
            motion: Mutex::new(motion),
            trial: Arc::new(Mutex::new(trial.map(str::to_owned))),
            max_speed_mm_per_s: 40.0,
            stop_pending: Arc::new(AtomicBool::new(false)),
            stage_kill: None,
        };
        (control, hub_rx, motion_rx)
    }

    fn move_by(distance_m: f64, speed_m_per_s: Option<f64>) -> ControlCommand {
        ControlCommand::MoveStage {
            target: StageTarget::Relative { distance_m },
            speed_m_per_s,
        }
    }

    #[test]
    fn motion_commands_are_refused_while_a_trial_runs() {
        let (control, _hub, motion) = control(Some("sweep"));
        let refused = control.handle(move_by(0.01, None)).unwrap_err();
        assert!(
            refused.starts_with("move_stage refused: trial \"sweep\""),
            "{refused}"
        );
        let refused = control
            .handle(ControlCommand::SetBaseAngle { angle_deg: 3.0 })
            .unwrap_err();
        assert!(refused.starts_with("set_base_angle refused"), "{refused}");
        assert!(
            motion.try_recv().is_err(),
            "nothing reached the motion thread"
        );
    }

    #[test]
    fn a_move_faster_than_the_stage_allows_is_refused() {
        let (control, _hub, motion) = control(None);
        let refused = control.handle(move_by(0.01, Some(0.05))).unwrap_err();
        assert_eq!(
            refused,
            "move_stage refused: 50 mm/s is faster than stage.max_speed_mm_per_s = 40 mm/s"
        );
        assert!(motion.try_recv().is_err());
    }

    #[test]
    fn a_move_goes_to_the_motion_thread_in_millimetres_at_half_the_top_speed_by_default() {
        let (control, _hub, motion) = control(None);
        let answer = std::thread::spawn(move || match motion.recv() {
            Ok(MotionCommand::Move {
                target: MoveTarget::To(mm),
                speed_mm_per_s,
                reply,
            }) => {
                reply
                    .send(Ok(format!("to {mm} at {speed_mm_per_s}")))
                    .unwrap();
            }
            _ => panic!("expected a move"),
        });
        let command = ControlCommand::MoveStage {
            target: StageTarget::Absolute { position_m: 0.125 },
            speed_m_per_s: None,
        };
        assert_eq!(control.handle(command), Ok("to 125 at 20".to_owned()));
        answer.join().unwrap();
    }

    #[test]
    fn stop_all_stops_the_motion_then_ends_the_trial() {
        let (control, hub, motion) = control(None);
        let stop_pending = Arc::clone(&control.stop_pending);
        let threads = std::thread::spawn(move || {
            match motion.recv() {
                Ok(MotionCommand::StopAll { reply }) => reply.send(Ok("stopped".to_owned())),
                _ => panic!("expected stop_all"),
            }
            .unwrap();
            match hub.recv() {
                Ok(HubRequest::Stop { why, reply }) => reply.send(Err(why.to_owned())),
                _ => panic!("expected the trial's end"),
            }
            .unwrap();
        });
        assert_eq!(
            control.handle(ControlCommand::StopAll),
            Ok("stopped; no trial was running".to_owned())
        );
        assert!(stop_pending.load(Ordering::SeqCst));
        threads.join().unwrap();
    }

    #[test]
    fn a_daemon_shutting_down_says_so() {
        let (control, hub, motion) = control(None);
        drop((hub, motion));
        assert_eq!(
            control.handle(ControlCommand::StopTrial),
            Err("the daemon is shutting down".to_owned())
        );
        assert_eq!(
            control.handle(move_by(0.0, None)),
            Err("the daemon is shutting down".to_owned())
        );
    }
}
