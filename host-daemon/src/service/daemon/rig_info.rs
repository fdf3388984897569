//! The rig's geometry for the stream's `hello`.

use crate::config::Config;
use antenna_data::stream::{RigInfo, RigWall};

/// The rig's geometry for the stream's `hello` (docs/stream-protocol.md): the antenna and
/// wall of `[sim.antenna]` and `[sim.wall]`, the stage's soft limits and the poll rate.
pub fn rig_info(config: &Config) -> RigInfo {
    let antenna = &config.sim.antenna;
    let link_lengths_m = vec![antenna.link_length_m; antenna.links + 1];
    let stiffness_n_m_per_rad = antenna
        .profile()
        .and_then(|p| {
            p.stiffness_n_m_per_rad(
                &link_lengths_m,
                antenna.k_min_n_m_per_rad,
                antenna.k_max_n_m_per_rad,
            )
            .ok()
        })
        .unwrap_or_default();
    RigInfo {
        poll_hz: config.bus.poll_hz,
        link_lengths_m,
        base_mount_angle_deg: antenna.base_angle_deg,
        stiffness_profile: antenna.stiffness_profile.clone(),
        k_min_n_m_per_rad: antenna.k_min_n_m_per_rad,
        k_max_n_m_per_rad: antenna.k_max_n_m_per_rad,
        stiffness_n_m_per_rad,
        wall: RigWall {
            distance_m: config.sim.wall.distance_m,
            angle_deg: config.sim.wall.angle_deg,
            stiffness_n_per_m: config.sim.wall.stiffness_n_per_m,
        },
        stage_min_m: config.stage.min_mm * 1e-3,
        stage_max_m: config.stage.max_mm * 1e-3,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_hello_describes_the_configured_antenna_wall_and_stage() {
        let mut config = Config::default();
        config.stage.min_mm = 5.0;
        config.stage.max_mm = 250.0;
        let info = rig_info(&config);
        let antenna = &config.sim.antenna;
        assert_eq!(info.poll_hz, config.bus.poll_hz);
        assert_eq!(info.link_lengths_m.len(), antenna.links + 1);
        assert!(
            info.link_lengths_m
                .iter()
                .all(|&l| l == antenna.link_length_m)
        );
        assert_eq!(info.base_mount_angle_deg, antenna.base_angle_deg);
        assert_eq!(info.stiffness_profile, antenna.stiffness_profile);
        // A known profile gives one stiffness per joint, within the configured range.
        assert!(!info.stiffness_n_m_per_rad.is_empty());
        assert!(info.stiffness_n_m_per_rad.iter().all(|&k| {
            (antenna.k_min_n_m_per_rad - 1e-12..=antenna.k_max_n_m_per_rad + 1e-12).contains(&k)
        }));
        assert_eq!(info.wall.distance_m, config.sim.wall.distance_m);
        assert_eq!(info.wall.angle_deg, config.sim.wall.angle_deg);
        assert_eq!((info.stage_min_m, info.stage_max_m), (5e-3, 0.25));
    }

    #[test]
    fn an_unknown_stiffness_profile_leaves_the_stiffness_out() {
        let mut config = Config::default();
        config.sim.antenna.stiffness_profile = "rubber".to_owned();
        assert!(rig_info(&config).stiffness_n_m_per_rad.is_empty());
    }
}
