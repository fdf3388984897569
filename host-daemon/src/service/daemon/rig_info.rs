//! The rig for the stream's `hello` and the recordings' metadata.

use crate::config::{Config, WallSideName};
use antenna_data::stream::RigInfo;

/// The rig for the stream's `hello` (docs/stream-protocol.md) and every recording: the
/// scene of `[sim] scene` as text (its points files written in, [`crate::config::scene`]), so
/// a client rebuilds the same physics, with the links and mounting angle for clients that only
/// draw, the stage's soft limits and the poll rate.
pub fn rig_info(config: &Config) -> RigInfo {
    let rig = &config.sim.rig;
    let chain = &rig.scene.chain;
    RigInfo {
        poll_hz: config.bus.poll_hz,
        stage_min_m: config.stage.min_mm * 1e-3,
        stage_max_m: config.stage.max_mm * 1e-3,
        scene_toml: Some(rig.text.clone()),
        scene_source: Some(rig.source.clone()),
        link_lengths_m: chain.link_lengths_m().to_vec(),
        base_mount_angle_deg: chain.base_angle_rad().to_degrees(),
        estimate_wall_side: Some(
            match config.estimate.wall_side {
                WallSideName::Left => "left",
                WallSideName::Right => "right",
            }
            .to_owned(),
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use antenna_scene::Scene;

    #[test]
    fn the_hello_carries_the_scene_and_the_stage() {
        let mut config = Config::default();
        config.stage.min_mm = 5.0;
        config.stage.max_mm = 250.0;
        let info = rig_info(&config);
        assert_eq!(info.poll_hz, config.bus.poll_hz);
        assert_eq!((info.stage_min_m, info.stage_max_m), (5e-3, 0.25));
        assert_eq!(info.link_lengths_m, vec![0.04; 9]);
        assert!((info.base_mount_angle_deg - 30.0).abs() < 1e-12);
        assert_eq!(info.estimate_wall_side.as_deref(), Some("left"));
        // The text is the scene in force.
        let scene = Scene::parse(info.scene_toml.as_deref().unwrap(), "hello").unwrap();
        assert_eq!(
            scene,
            Scene {
                locations: scene.locations.clone(),
                ..config.sim.rig.scene.clone()
            }
        );
    }
}
