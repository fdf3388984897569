//! The posture sim-core predicts for a base pose and the wall, behind one trait.
//!
//! The chain panel overlays the measured chain with [`Prediction`]s and draws their
//! difference; it knows only [`Predictor`]. [`predictor_for`] is the one place that chooses
//! the model: today [`QuasiStaticPredictor`], the simulated rig's own physics built from the
//! rig's scene (`antenna_sim_physics::SimPhysics`: sim-core's quasi-static contact solver
//! with the scene's friction against its walls, hairs included, placed as the scene says and
//! stepping from the previous posture). Another model is another implementation of
//! [`Predictor`] and a change to [`predictor_for`].
//!
//! Solving can take milliseconds for long chains, so the UI asks a [`PredictionWorker`]: a
//! thread that always solves the latest requested pose and never makes the UI wait. It uses
//! at most a third of a core (it rests twice as long as its last solve took, and at least
//! until 33 ms have passed since that solve started).

use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use antenna_sim_physics::SimPhysics;

use crate::error::MonitorError;
use crate::rig::RigGeometry;

/// The shortest time between the starts of two solves.
const MIN_SOLVE_INTERVAL: Duration = Duration::from_millis(33);

/// Where the antenna's base is: the stage position and the servo angle (the base link's
/// angle is the mounting angle plus the servo angle).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BasePose {
    /// Stage carriage position, metres.
    pub stage_position_m: f64,
    /// Servo angle, radians.
    pub servo_angle_rad: f64,
}

/// A predicted posture.
#[derive(Debug, Clone, PartialEq)]
pub struct Prediction {
    /// The pose it was predicted for.
    pub pose: BasePose,
    /// Joint angles, one per segment, base to tip, radians.
    pub joint_angles_rad: Vec<f64>,
    /// Each segment's touch bits as its switches would close, base to tip (bit `i`: switch
    /// `i`, bit 0 the most proximal), 0..=15.
    pub touch_bits: Vec<u8>,
    /// The wall's force on the tip, newtons.
    pub tip_force_n: f64,
}

/// Predicts the chain's posture for a base pose against the rig's walls.
pub trait Predictor: Send + std::fmt::Debug {
    /// The model's name, for the legend.
    fn name(&self) -> &'static str;

    /// The posture for `pose`. Implementations may warm-start from the previous call.
    fn predict(&mut self, pose: BasePose) -> Result<Prediction, MonitorError>;
}

/// The predictor the monitor uses for `rig`: the one switch point between models.
pub fn predictor_for(rig: &RigGeometry) -> Result<Box<dyn Predictor>, MonitorError> {
    Ok(Box::new(QuasiStaticPredictor::new(rig)?))
}

/// sim-core's quasi-static contact solver, exactly the simulated rig's physics
/// (`antenna_sim_physics::SimPhysics`) on the rig's scene.
#[derive(Debug)]
pub struct QuasiStaticPredictor {
    physics: SimPhysics,
}

impl QuasiStaticPredictor {
    /// The predictor for `rig`, which needs its scene (daemons since issue #46 send it).
    ///
    /// # Errors
    /// [`MonitorError::Prediction`] without a scene, or when its placement fails.
    pub fn new(rig: &RigGeometry) -> Result<Self, MonitorError> {
        let scene = rig.scene.clone().ok_or_else(|| {
            MonitorError::Prediction(
                "the source gives no scene (no wall to predict against)".to_owned(),
            )
        })?;
        let mut physics =
            SimPhysics::new(scene).map_err(|e| MonitorError::Prediction(e.to_string()))?;
        physics
            .set_touch_threshold_n(rig.touch_threshold_n)
            .map_err(|e| MonitorError::Prediction(e.to_string()))?;
        Ok(Self { physics })
    }
}

impl Predictor for QuasiStaticPredictor {
    fn name(&self) -> &'static str {
        "sim-core, quasi-static contact"
    }

    fn predict(&mut self, pose: BasePose) -> Result<Prediction, MonitorError> {
        let state = self
            .physics
            .update(pose.stage_position_m, pose.servo_angle_rad)
            .map_err(|e| MonitorError::Prediction(format!("{e:#}")))?;
        Ok(Prediction {
            pose,
            touch_bits: state.touch.iter().map(|t| t.bits()).collect(),
            joint_angles_rad: state.joint_angles_rad,
            tip_force_n: state.tip_force_n,
        })
    }
}

#[derive(Debug, Default)]
struct Slot {
    request: Option<BasePose>,
    result: Option<Result<Prediction, String>>,
    stop: bool,
}

/// A thread that solves the latest requested pose (see the module documentation).
#[derive(Debug)]
pub struct PredictionWorker {
    name: &'static str,
    shared: Arc<(Mutex<Slot>, Condvar)>,
    last_requested: Option<BasePose>,
    latest: Option<Result<Prediction, String>>,
    thread: Option<JoinHandle<()>>,
}

impl PredictionWorker {
    /// Starts the thread around `predictor`.
    pub fn start(mut predictor: Box<dyn Predictor>) -> Result<Self, MonitorError> {
        let name = predictor.name();
        let shared = Arc::new((Mutex::new(Slot::default()), Condvar::new()));
        let worker_shared = Arc::clone(&shared);
        let thread = std::thread::Builder::new()
            .name("monitor-prediction".to_owned())
            .spawn(move || {
                let (lock, ready) = &*worker_shared;
                loop {
                    let pose = {
                        let Ok(mut slot) = lock.lock() else { return };
                        loop {
                            if slot.stop {
                                return;
                            }
                            if let Some(pose) = slot.request.take() {
                                break pose;
                            }
                            slot = match ready.wait(slot) {
                                Ok(s) => s,
                                Err(_) => return,
                            };
                        }
                    };
                    let started = Instant::now();
                    let result = predictor.predict(pose).map_err(|e| e.to_string());
                    let took = started.elapsed();
                    if let Ok(mut slot) = lock.lock() {
                        slot.result = Some(result);
                    } else {
                        return;
                    }
                    // At most a third of a core, and at most 30 solves a second: the UI and
                    // the stream come first (a long chain's prediction then lags a little).
                    std::thread::sleep((took * 2).max(MIN_SOLVE_INTERVAL.saturating_sub(took)));
                }
            })
            .map_err(|e| MonitorError::Prediction(format!("starting its thread: {e}")))?;
        Ok(Self {
            name,
            shared,
            last_requested: None,
            latest: None,
            thread: Some(thread),
        })
    }

    /// The model's name.
    pub fn name(&self) -> &'static str {
        self.name
    }

    /// Asks for `pose` (ignored if it is the pose last asked for); never waits.
    pub fn request(&mut self, pose: BasePose) {
        if self.last_requested == Some(pose) {
            return;
        }
        self.last_requested = Some(pose);
        let (lock, ready) = &*self.shared;
        if let Ok(mut slot) = lock.lock() {
            slot.request = Some(pose);
            ready.notify_one();
        }
    }

    /// The newest finished prediction (or its error), without waiting.
    pub fn latest(&mut self) -> Option<&Result<Prediction, String>> {
        if let Ok(mut slot) = self.shared.0.lock()
            && let Some(result) = slot.result.take()
        {
            self.latest = Some(result);
        }
        self.latest.as_ref()
    }

    /// Whether the newest finished prediction is for the pose last asked for.
    pub fn is_current(&mut self) -> bool {
        let requested = self.last_requested;
        matches!(self.latest(), Some(Ok(p)) if Some(p.pose) == requested)
    }
}

impl Drop for PredictionWorker {
    fn drop(&mut self) {
        if let Ok(mut slot) = self.shared.0.lock() {
            slot.stop = true;
        }
        self.shared.1.notify_all();
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use antenna_data::stream::RigInfo;

    #[test]
    fn predicts_a_bend_against_the_wall_in_the_background() {
        let rig = crate::rig::tests::default_rig();
        let mut worker = PredictionWorker::start(predictor_for(&rig).unwrap()).unwrap();
        let home = BasePose {
            stage_position_m: 0.0,
            servo_angle_rad: 0.0,
        };
        let along = BasePose {
            stage_position_m: 0.15,
            servo_angle_rad: 0.0,
        };
        for pose in [home, along] {
            worker.request(pose);
            // Generous: only a hang takes this long, however loaded the machine.
            let deadline = Instant::now() + Duration::from_secs(60);
            while !worker.is_current() {
                assert!(Instant::now() < deadline, "no prediction for {pose:?}");
                std::thread::sleep(Duration::from_millis(2));
            }
        }
        let Some(Ok(p)) = worker.latest() else {
            panic!("no prediction")
        };
        assert_eq!(p.pose, along);
        // The built-in scene's antenna, placed tip on the wall, bent back along it.
        assert!(p.touch_bits.iter().any(|&b| b != 0));
        assert!(p.touch_bits.iter().all(|&b| b <= 0x0F));
        assert!(p.joint_angles_rad.iter().any(|a| a.abs() > 0.3));
    }

    /// The rig of the built-in scene with the wall's friction `mu`.
    fn rig_with_mu(mu: f64) -> RigGeometry {
        let text = host_daemon::service::config::scene::BUILT_IN_SCENE;
        assert!(text.contains("mu = 0.3\n"));
        let info = RigInfo {
            poll_hz: 1000.0,
            stage_min_m: 0.0,
            stage_max_m: 0.6,
            scene_toml: Some(text.replace("mu = 0.3\n", &format!("mu = {mu:?}\n"))),
            scene_source: Some(format!("mu {mu}")),
            link_lengths_m: vec![0.04; 9],
            base_mount_angle_deg: 30.0,
            estimate_wall_side: None,
        };
        RigGeometry::from_rig_info(&info, "test").unwrap()
    }

    /// The prediction is the scene's physics, friction included: along the same path, a
    /// frictionless wall and one with mu = 1 bend the antenna differently, each exactly as
    /// the simulated rig's physics does on that scene.
    #[test]
    fn the_prediction_uses_the_scene_s_friction() {
        let path: Vec<f64> = (1..=50).map(|k| f64::from(k) * 2e-3).collect();
        let run = |mu: f64| {
            let rig = rig_with_mu(mu);
            let mut predictor = predictor_for(&rig).unwrap();
            let mut physics = SimPhysics::new(rig.scene.clone().unwrap()).unwrap();
            let mut last = Vec::new();
            for &s in &path {
                let pose = BasePose {
                    stage_position_m: s,
                    servo_angle_rad: 0.0,
                };
                last = predictor.predict(pose).unwrap().joint_angles_rad;
                assert_eq!(last, physics.update(s, 0.0).unwrap().joint_angles_rad);
            }
            last
        };
        let (slippery, rough) = (run(0.0), run(1.0));
        let difference = slippery
            .iter()
            .zip(&rough)
            .fold(0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(difference.to_degrees() > 1.0, "{slippery:?} {rough:?}");
    }

    /// The scene's `[sensors] touch_threshold_n` is the prediction's, as it is the rig's
    /// segments': a threshold above every contact force leaves the bent antenna's switches
    /// open.
    #[test]
    fn the_prediction_uses_the_scene_s_touch_threshold() {
        let touched = |threshold: Option<f64>| {
            let mut info = RigInfo {
                poll_hz: 1000.0,
                stage_min_m: 0.0,
                stage_max_m: 0.6,
                scene_toml: Some(host_daemon::service::config::scene::BUILT_IN_SCENE.to_owned()),
                scene_source: None,
                link_lengths_m: vec![0.04; 9],
                base_mount_angle_deg: 30.0,
                estimate_wall_side: None,
            };
            if let (Some(text), Some(threshold_n)) = (&mut info.scene_toml, threshold) {
                text.push_str(&format!("[sensors]\ntouch_threshold_n = {threshold_n:?}\n"));
            }
            let rig = RigGeometry::from_rig_info(&info, "test").unwrap();
            assert_eq!(rig.touch_threshold_n, threshold.unwrap_or(0.0));
            let mut predictor = predictor_for(&rig).unwrap();
            let p = predictor
                .predict(BasePose {
                    stage_position_m: 0.05,
                    servo_angle_rad: 0.0,
                })
                .unwrap();
            assert!(p.joint_angles_rad.iter().any(|a| a.abs() > 0.3));
            p.touch_bits.iter().filter(|&&b| b != 0).count()
        };
        assert!(touched(None) > 0);
        assert!(touched(Some(0.0)) > 0);
        assert_eq!(touched(Some(100.0)), 0);
    }

    #[test]
    fn refuses_a_rig_without_a_scene() {
        let rig = RigGeometry::fallback(3).unwrap();
        let err = predictor_for(&rig).unwrap_err().to_string();
        assert!(err.contains("no scene"), "{err}");
    }
}
