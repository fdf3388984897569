//! [`Scene::sweep_scene`]: a scene as sim-core's [`SweepScene`], what `antenna sweep`, the
//! solve of a scene with walls, `antenna study` and the GUI's sweep animation run.

use sim_core::SensorSettings;
use sim_core::follow::FollowConfig;
use sim_core::sweep::SweepScene;

use super::Scene;
use crate::error::{SceneError, SceneErrorKind};

impl Scene {
    /// The sweep this scene describes: its chain (hairs included), `[[walls]]`, the base
    /// pivot starting at `[base] position_m`, `[sweep]`'s motion, `[start]`'s placement, the
    /// `[tip_load]` and the `[contact]` settings. Run it with [`sim_core::sweep::Sweep::new`]:
    ///
    /// ```
    /// # fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// use antenna_scene::Scene;
    /// use sim_core::sweep::Sweep;
    ///
    /// let scene = Scene::parse(
    ///     "[antenna]\nlinks = 3\nlink_length_m = 0.04\nbase_angle_deg = 60.0\n\
    ///      [antenna.stiffness]\nvalues_n_m_per_rad = [0.02, 0.01]\n\
    ///      [[walls]]\nshape = \"line\"\npoint_m = [0.0, 0.2]\nsolid = \"left\"\n\
    ///      [sweep]\nduration_s = 0.05\n",
    ///     "scene.toml",
    /// )?;
    /// let mut sweep = Sweep::new(scene.sweep_scene()?)?;
    /// let mut steps = 0;
    /// while let Some(step) = sweep.next_step() {
    ///     step?;
    ///     steps += 1;
    /// }
    /// assert_eq!(steps, 5);
    /// # Ok(())
    /// # }
    /// ```
    ///
    /// # Errors
    /// A [`SceneError`] naming `[tip_pin]` when the scene pins its tip: a sweep moves the
    /// base and cannot hold the tip on a fixed pin.
    pub fn sweep_scene(&self) -> Result<SweepScene, SceneError> {
        if self.tip_pin_m.is_some() {
            return Err(SceneError {
                path: self.locations.path.clone(),
                location: self.locations.tip_pin_position_m,
                kind: Box::new(SceneErrorKind::Invalid {
                    key: "position_m".to_string(),
                    table: "[tip_pin]".to_string(),
                    reason: "a sweep moves the base and cannot hold the tip on a fixed pin; \
                             remove [tip_pin] to sweep this scene"
                        .to_string(),
                }),
            });
        }
        Ok(SweepScene {
            chain: self.chain.clone(),
            walls: self.walls.clone(),
            base_start_m: self.base_position_m,
            motion: self.motion,
            placement: self.placement.clone(),
            tip_force_n: self.tip_force_n,
            settings: self.contact,
        })
    }

    /// What a follow scene's closed-loop run takes: the sweep scene (the chain at the mount
    /// angle, the walls, the base at the mount's start, the placement, the contact solver;
    /// see [`Scene::follow`]), the robot, controller and run ([`FollowConfig`], validated),
    /// and the sensors. Errors the run finds when it starts are put at their keys by
    /// [`crate::FollowScene::locate`].
    ///
    /// ```
    /// # fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// use antenna_scene::Scene;
    ///
    /// let scene = Scene::parse(
    ///     "[antenna]\nlinks = 9\nlink_length_m = 0.04\n\
    ///      [antenna.stiffness]\nprofile = \"fast-exponential\"\n\
    ///      min_n_m_per_rad = 0.004\nmax_n_m_per_rad = 0.082\n\
    ///      [[walls]]\nshape = \"line\"\npoint_m = [0.0, 0.2]\nsolid = \"left\"\n\
    ///      [robot]\nspeed_m_per_s = 0.5\n",
    ///     "follow.toml",
    /// )?;
    /// let (sweep, config, sensors) = scene.follow_parts()?;
    /// assert_eq!(config.robot.speed_m_per_s, 0.5);
    /// assert_eq!(sweep.chain.base_angle_rad(), config.robot.mount_angle_rad);
    /// assert_eq!(sensors, sim_core::SensorSettings::IDEAL);
    /// # Ok(())
    /// # }
    /// ```
    ///
    /// # Errors
    /// A [`SceneError`] (`no [follow] table: not a follow scene`) for a scene without
    /// `[robot]`, `[controller]` and `[follow]`.
    pub fn follow_parts(&self) -> Result<(SweepScene, FollowConfig, SensorSettings), SceneError> {
        let Some(follow) = &self.follow else {
            return Err(SceneError {
                path: self.locations.path.clone(),
                location: None,
                kind: Box::new(SceneErrorKind::Run {
                    message: "no [follow] table: not a follow scene".to_string(),
                }),
            });
        };
        Ok((self.sweep_scene()?, follow.config, self.sensors.clone()))
    }
}
