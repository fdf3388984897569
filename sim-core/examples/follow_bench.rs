//! The closed loop's own cost (issue #47, item 9): writes the "Sweeps: closed loop" section of
//! docs/benchmarks/sweeps.md (between `<!-- follow:begin -->` and `<!-- follow:end -->`,
//! appended when missing).
//!
//! A 10 s follow at 100 Hz of the thesis's 4.2.1 antenna (9 links of 40 mm, fast-exponential
//! 0.004..0.082 N m/rad, mounted 30 deg) along the 4.2.1 wall (smooth, mu = 0.3, at 8 deg), the
//! template body at 0.3 m/s, the contact-line estimator, the thesis robot's sensors (ideal
//! here: what is measured is the loop), against an open-loop replay of the same run: the
//! antenna placed the same way and stepped through the poses the run solved it at, with
//! `QuasiStatic::step_to_pose`, in the same pieces. The replay's joint angles are compared
//! with the run's (they must be identical: the same solver on the same path). The goal: the
//! loop costs at most 1.5x the replay (sensing, estimating, control, the body, the truth and
//! the records are the loop's own cost).
//!
//! Times are medians of rounds that interleave the two (`std::time::Instant`, one thread);
//! the placement is not timed. Run by `scripts/bench-follow` (release build); `--rounds N`
//! (default 7).

mod bench_common;

use std::path::PathBuf;
use std::time::Instant;

use nalgebra::Vector2;
use sim_core::follow::{Follow, FollowConfig};
use sim_core::sweep::{BasePose, Motion, Placement, SweepScene, place_at};
use sim_core::{Chain, JointLimit, Line, SensorSettings, SolidSide, StiffnessProfile, Wall};

use bench_common::{date, human, median, write_section};

const BEGIN: &str = "<!-- follow:begin -->";
const END: &str = "<!-- follow:end -->";

fn scene(config: &FollowConfig) -> Result<SweepScene, Box<dyn std::error::Error>> {
    let k = StiffnessProfile::FastExponential.stiffness_n_m_per_rad(&[0.04; 9], 0.004, 0.082)?;
    let chain = Chain::builder(8)
        .link_length_m(0.04)
        .base_angle_rad(config.robot.mount_angle_rad)
        .joint_limit(JointLimit::new(
            -std::f64::consts::FRAC_PI_2,
            std::f64::consts::FRAC_PI_2,
        ))
        .stiffnesses_nm_per_rad(k)
        .build()?;
    let wall = Wall::smooth(Line::new(
        Vector2::new(0.0, 0.2),
        8f64.to_radians(),
        SolidSide::Left,
    )?);
    Ok(SweepScene {
        placement: Placement::Approach {
            wall: 0,
            distance_m: 0.36,
            along_m: 0.0,
            steps: 180,
        },
        ..SweepScene::new(chain, vec![wall])
    })
}

/// One closed-loop run: its time, the antenna's poses and joint angles per step, its status.
struct Run {
    seconds: f64,
    poses: Vec<BasePose>,
    thetas: Vec<Vec<f64>>,
    status: String,
}

fn follow(scene: &SweepScene, config: &FollowConfig) -> Result<Run, Box<dyn std::error::Error>> {
    let mut run = Follow::new(scene, &SensorSettings::IDEAL, config)?;
    let mut poses = Vec::with_capacity(run.steps());
    let mut thetas = Vec::with_capacity(run.steps());
    let started = Instant::now();
    while let Some(step) = run.next_step() {
        let step = step?;
        if let Some(base_m) = step.base_m {
            poses.push(BasePose {
                base_m,
                base_angle_rad: step.theta_rad[0],
            });
            thetas.push(step.theta_rad);
        }
    }
    Ok(Run {
        seconds: started.elapsed().as_secs_f64(),
        poses,
        thetas,
        status: run.summary().status.name().to_string(),
    })
}

/// The replay of `poses` through `step_to_pose`, in the loop's pieces; its time and whether
/// every step's joint angles are the run's.
fn replay(
    scene: &SweepScene,
    config: &FollowConfig,
    poses: &[BasePose],
    thetas: &[Vec<f64>],
) -> Result<(f64, bool), Box<dyn std::error::Error>> {
    let (sin, cos) = config.settings.heading_rad.sin_cos();
    let placed = SweepScene {
        motion: Motion {
            velocity_m_per_s: Vector2::new(cos, sin) * config.robot.speed_m_per_s,
            ..Motion::default()
        },
        ..scene.clone()
    };
    let (mut sim, _, _) = place_at(&placed, &poses[0])?;
    let reach_m = scene.chain.total_length_m();
    let step_m = config.settings.antenna_step_m;
    let mut identical = sim.theta_rad() == thetas[0].as_slice();
    let started = Instant::now();
    for (k, goal) in poses.iter().enumerate().skip(1) {
        let from = poses[k - 1];
        let d_angle = goal.base_angle_rad - from.base_angle_rad;
        let travel = (goal.base_m - from.base_m)
            .norm()
            .max(reach_m * d_angle.abs());
        let pieces = (travel / step_m).ceil().max(1.0) as usize;
        for p in 1..=pieces {
            let f = p as f64 / pieces as f64;
            sim.step_to_pose(
                from.base_m + (goal.base_m - from.base_m) * f,
                from.base_angle_rad + d_angle * f,
            )?;
        }
        identical &= sim.theta_rad() == thetas[k].as_slice();
    }
    Ok((started.elapsed().as_secs_f64(), identical))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let rounds: usize = std::env::args()
        .skip_while(|a| a != "--rounds")
        .nth(1)
        .map_or(Ok(7), |r| r.parse())?;
    let mut config = FollowConfig::default();
    config.settings.duration_s = 10.0;
    config.settings.step_s = 0.01;
    config.settings.pose_m = Vector2::new(0.0, 0.10);
    config.settings.heading_rad = 8f64.to_radians();
    let scene = scene(&config)?;
    let (mut loop_s, mut replay_s) = (Vec::new(), Vec::new());
    let mut steps = 0;
    let mut status = String::new();
    let mut identical = true;
    for _ in 0..rounds {
        let run = follow(&scene, &config)?;
        loop_s.push(run.seconds);
        steps = run.poses.len();
        status = run.status;
        let (seconds, same) = replay(&scene, &config, &run.poses, &run.thetas)?;
        replay_s.push(seconds);
        identical &= same;
    }
    let (l, r) = (median(&loop_s), median(&replay_s));
    let per_loop = l / steps as f64;
    let per_replay = r / (steps - 1) as f64;
    let ratio = per_loop / per_replay;
    let goal = if ratio <= 1.5 { "met" } else { "NOT met" };
    let section = format!(
        "{BEGIN}\n## Sweeps: closed loop\n\n\
         Measured {} by `scripts/bench-follow` (sim-core's `follow_bench`, release build, one \
         thread, medians of {rounds} interleaved rounds).\n\n\
         A 10 s follow at 100 Hz ({steps} steps) of the thesis's 4.2.1 antenna along the 4.2.1 \
         wall (8 deg, mu = 0.3), the template body at 0.3 m/s, the contact-line estimator \
         (status `{status}`), against an open-loop replay of the same run's antenna poses \
         through `QuasiStatic::step_to_pose` in the same pieces (joint angles identical to the \
         run's at every step: {identical}).\n\n\
         | | whole run | per step |\n|---|---|---|\n\
         | closed loop (`Follow::next_step`) | {} | {} |\n\
         | open-loop replay (`step_to_pose`) | {} | {} |\n\n\
         Goal (issue #47): the loop costs at most 1.5x the replay per step: {ratio:.2}x, \
         {goal}.\n{END}\n",
        date(),
        human(l),
        human(per_loop),
        human(r),
        human(per_replay),
    );
    print!("{section}");
    let workspace = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    write_section(&workspace, BEGIN, END, &section)?;
    Ok(())
}
