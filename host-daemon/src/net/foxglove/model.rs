//! [`chain_model`]: the chain Foxglove draws, from the daemon's configuration.

use crate::config::Config;
use antenna_data::foxglove::ChainModel;
use sim_core::{Wall, WallShape};

/// How far beyond the stage's travel and the chain's reach a wall is drawn, m.
const WALL_MARGIN_M: f64 = 0.25;
/// Points per wavelength of a sinusoidal wall.
const SINUSOID_POINTS_PER_WAVELENGTH: f64 = 24.0;
/// At most this many points per wall (a very short wavelength is drawn coarser).
const MAX_WALL_POINTS: f64 = 2000.0;

/// The chain of `config` as Foxglove draws it: the links and the base mount angle as the
/// stream's `hello` gives them ([`crate::service::daemon::rig_info`]), the base pivot with the
/// stage at 0 at the scene's `[base] position_m`, the stage travelling along the scene's
/// direction of motion (`+x` when it has none, as the simulated rig moves it) and, on the
/// simulated rig only (`bus.device = "sim"`), the scene's walls as polylines covering the
/// stage's travel and the chain's reach.
pub fn chain_model(config: &Config) -> ChainModel {
    let scene = &config.sim.rig.scene;
    let chain = &scene.chain;
    let v = scene.motion.velocity_m_per_s;
    let travel_angle_rad = if v.x == 0.0 && v.y == 0.0 || !(v.x.is_finite() && v.y.is_finite()) {
        0.0
    } else {
        v.y.atan2(v.x)
    };
    let origin_m = [scene.base_position_m.x, scene.base_position_m.y];
    let walls_m = if config.bus.is_sim() {
        let (sin, cos) = travel_angle_rad.sin_cos();
        let mid_m = 0.5 * (config.stage.min_mm + config.stage.max_mm) * 1e-3;
        let near_m = [origin_m[0] + mid_m * cos, origin_m[1] + mid_m * sin];
        let reach_m: f64 = chain.link_lengths_m().iter().sum();
        let half_length_m = 0.5 * (config.stage.max_mm - config.stage.min_mm).abs() * 1e-3
            + reach_m
            + WALL_MARGIN_M;
        scene
            .walls
            .iter()
            .map(|wall| wall_polyline_m(wall, near_m, half_length_m))
            .collect()
    } else {
        Vec::new()
    };
    ChainModel {
        link_lengths_m: chain.link_lengths_m().to_vec(),
        // The carriage frame turns with the travel: the base link's angle from it.
        base_mount_angle_rad: chain.base_angle_rad() - travel_angle_rad,
        origin_m,
        travel_angle_rad,
        walls_m,
    }
}

/// `wall` as a polyline in the scene frame: the part within about `half_length_m` of `near_m`
/// (a line's two end points; a polyline's vertices with its end rays drawn `half_length_m`
/// long; a sinusoid sampled [`SINUSOID_POINTS_PER_WAVELENGTH`] times per wavelength).
fn wall_polyline_m(wall: &Wall, near_m: [f64; 2], half_length_m: f64) -> Vec<[f64; 2]> {
    let along = |point: [f64; 2], angle_rad: f64| {
        let (sin, cos) = angle_rad.sin_cos();
        let s = (near_m[0] - point[0]) * cos + (near_m[1] - point[1]) * sin;
        move |t: f64| [point[0] + (s + t) * cos, point[1] + (s + t) * sin]
    };
    match &wall.shape {
        WallShape::Line(line) => {
            let p = line.point_m();
            let at = along([p.x, p.y], line.angle_rad());
            vec![at(-half_length_m), at(half_length_m)]
        }
        WallShape::Polyline(polyline) => {
            let v: Vec<[f64; 2]> = polyline.vertices_m().iter().map(|p| [p.x, p.y]).collect();
            let ray = |from: [f64; 2], toward: [f64; 2]| {
                let (dx, dy) = (from[0] - toward[0], from[1] - toward[1]);
                let norm = dx.hypot(dy);
                if norm > 0.0 {
                    [
                        from[0] + dx / norm * half_length_m,
                        from[1] + dy / norm * half_length_m,
                    ]
                } else {
                    from
                }
            };
            let mut points = Vec::with_capacity(v.len() + 2);
            if let [a, b, ..] = v.as_slice() {
                points.push(ray(*a, *b));
            }
            points.extend_from_slice(&v);
            if let [.., a, b] = v.as_slice() {
                points.push(ray(*b, *a));
            }
            points
        }
        WallShape::Sinusoid(sinusoid) => {
            let p = sinusoid.baseline_point_m();
            let (sin, cos) = sinusoid.direction_rad().sin_cos();
            let centre_m = (near_m[0] - p.x) * cos + (near_m[1] - p.y) * sin;
            let step_m = (sinusoid.wavelength_m() / SINUSOID_POINTS_PER_WAVELENGTH)
                .max(2.0 * half_length_m / MAX_WALL_POINTS);
            let count = (2.0 * half_length_m / step_m).ceil() as usize;
            (0..=count)
                .map(|k| {
                    let q = sinusoid.point_at_m(centre_m - half_length_m + k as f64 * step_m);
                    [q.x, q.y]
                })
                .collect()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::service::daemon::rig_info;

    #[test]
    fn the_model_is_the_hello_s_chain_placed_in_the_scene() {
        let config = Config::default();
        let model = chain_model(&config);
        let info = rig_info(&config);
        assert_eq!(model.link_lengths_m, info.link_lengths_m);
        assert!(
            (model.base_mount_angle_rad.to_degrees() - info.base_mount_angle_deg).abs() < 1e-12
        );
        let scene = &config.sim.rig.scene;
        assert_eq!(
            model.origin_m,
            [scene.base_position_m.x, scene.base_position_m.y]
        );
        // The built-in scene's stage travels along +x, one straight wall.
        assert_eq!(model.travel_angle_rad, 0.0);
        assert_eq!(model.walls_m.len(), 1);
        let wall = &model.walls_m[0];
        assert_eq!(wall.len(), 2);
        // The wall's ends lie on it, beyond the stage's travel on both sides.
        for p in wall {
            let d = scene.walls[0]
                .signed_distance(&nalgebra::Vector2::new(p[0], p[1]))
                .gap_m;
            assert!(d.abs() < 1e-9, "{p:?}: {d}");
        }
        assert!(wall[0][0] < config.stage.min_mm * 1e-3 && wall[1][0] > config.stage.max_mm * 1e-3);
    }

    #[test]
    fn hardware_draws_no_walls() {
        let mut config = Config::default();
        config.bus.device = "/dev/i2c-1".to_owned();
        assert!(chain_model(&config).walls_m.is_empty());
    }
}
