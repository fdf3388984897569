//! Putting the antenna against the walls before a sweep (docs/model.md 6: "provide a way to place
//! the antenna in a chosen posture against the wall, release it, and then sweep; say what
//! was done").

use nalgebra::Vector2;

use super::{SweepError, SweepScene};
use crate::contact::{ContactError, ContactSettings, QuasiStatic, StepReport};
use crate::{EquilibriumProblem, InitialGuess, SolveOptions, Wall, solve_equilibrium};

/// How the antenna starts. Every placement ends by letting the antenna settle where it was
/// put, which may be a long snap (a held antenna let go springing onto the wall): that
/// settle has ten times a sweep step's budgets, `max_step_iterations` and `max_snap_steps`
/// scaled with the chain's joints ([`crate::contact::ContactSettings::step_iteration_budget`]),
/// and the placement's note says what a snap took. A release that lands on another
/// equilibrium is refined and followed as a snap at every N (the jump test bounds the
/// change of curvature, [`crate::contact::ContactSettings::jump_threshold_rad`]).
/// A held antenna that cannot be brought onto the wall is refused with the jam in words
/// (the contacts, the joints on their stops).
#[derive(Clone, Debug, PartialEq)]
pub enum Placement {
    /// The rest posture at the start position, as it is (it must be clear of the walls).
    Rest,
    /// Explicit joint angles `theta_1..theta_n` (radians) at the start position, settled
    /// where they are.
    Angles(Vec<f64>),
    /// The base starts `distance_m` farther from wall `wall` (along the wall's normal at the
    /// point nearest the tip) and `along_m` back along the direction of motion, and moves in
    /// a straight line onto its start position in `steps` equal steps: the tip meets the
    /// wall and the antenna bends, as when a robot comes up to a wall. With `along_m = 0` or
    /// negative (the base sliding back as it comes in, dragging the tip backward) the antenna
    /// ends projecting forward (the thesis 3.3.1 start, "projecting in the direction of
    /// motion"); a steep antenna meeting the wall head-on needs the backward slide.
    Approach {
        /// The wall to approach.
        wall: usize,
        /// How far away the base starts, metres.
        distance_m: f64,
        /// How far the base travels along the direction of motion while it comes in, metres
        /// (negative: backward).
        along_m: f64,
        /// In how many steps it comes.
        steps: usize,
    },
    /// The tip is held on wall `wall` at the point `ahead_m` ahead of the base along the
    /// direction of motion, the chain solved for that pin from `start` (a pinned
    /// equilibrium: with a C start the antenna bends toward the wall and its distal part
    /// lies back along it, the thesis 4.2.1 start "bent backwards and in contact with the
    /// wall"), then let go and settled with friction.
    TipOnWall {
        /// The wall.
        wall: usize,
        /// Where along the motion the tip is put, relative to the base pivot, metres.
        ahead_m: f64,
        /// The start of the pinned search.
        start: InitialGuess,
    },
}

/// Places the antenna; returns the simulation, what was done, and the settling's report.
pub(super) fn place(scene: &SweepScene) -> Result<(QuasiStatic, String, StepReport), SweepError> {
    let chain = scene.chain.clone();
    let base = scene.base_start_m;
    let wall_of = |wall: usize| -> Result<&Wall, SweepError> {
        scene.walls.get(wall).ok_or_else(|| {
            SweepError::Placement(format!(
                "wall {wall} does not exist (the scene has {} wall(s))",
                scene.walls.len()
            ))
        })
    };
    let new_sim = |base_m: Vector2<f64>, theta: &[f64]| {
        let mut sim = QuasiStatic::new(
            chain.clone(),
            scene.walls.clone(),
            base_m,
            theta,
            scene.settings,
        )?;
        sim.set_tip_force_n(scene.tip_force_n);
        Ok::<_, SweepError>(sim)
    };
    base_link_clear(scene)?;
    match &scene.placement {
        Placement::Rest => {
            let mut sim = new_sim(base, &chain.rest_theta())?;
            let report = settle(&mut sim)?;
            Ok((sim, "rest posture at the start position".to_owned(), report))
        }
        Placement::Angles(angles) => {
            if angles.len() != chain.n() {
                return Err(SweepError::Placement(format!(
                    "{} angles given, the chain has {} flexible joints",
                    angles.len(),
                    chain.n()
                )));
            }
            let mut theta = vec![chain.base_angle_rad()];
            theta.extend_from_slice(angles);
            let mut sim = new_sim(base, &theta)?;
            let report = settle(&mut sim)?;
            Ok((
                sim,
                format!("given joint angles, settled{}", snapped(&report)),
                report,
            ))
        }
        Placement::Approach {
            wall,
            distance_m,
            along_m,
            steps,
        } => {
            let w = wall_of(*wall)?;
            if !(distance_m.is_finite() && *distance_m >= 0.0 && along_m.is_finite()) || *steps == 0
            {
                return Err(SweepError::Placement(format!(
                    "approach needs distance_m >= 0, a finite along_m and steps >= 1 (got \
                     {distance_m}, {along_m}, {steps})"
                )));
            }
            let rest = chain.rest_theta();
            let tip = base
                + crate::tip_pose(&chain, &rest)
                    .map_err(|e| SweepError::Placement(e.to_string()))?
                    .position_m;
            let away = w.signed_distance(&tip).normal;
            let forward = motion_direction(scene);
            let from = base + away * *distance_m - forward * *along_m;
            let mut sim = new_sim(from, &rest).map_err(|e| {
                SweepError::Placement(format!(
                    "the base {distance_m} m back from wall {wall} still leaves the antenna in \
                     a wall ({e}); start farther away"
                ))
            })?;
            let mut total = settle(&mut sim)?;
            for k in 1..=*steps {
                let at = from + (base - from) * (k as f64 / *steps as f64);
                let r = sim.step_to(at).map_err(|source| SweepError::Step {
                    step: 0,
                    t_s: 0.0,
                    source,
                })?;
                total.accumulate(&r);
            }
            let note = format!(
                "approach: the base started {distance_m} m back from wall {wall} along its \
                 normal ({:.4}, {:.4}), travelling {along_m} m along the motion, and came onto \
                 ({:.4}, {:.4}) m in {steps} steps; {} contact(s){}",
                away.x,
                away.y,
                base.x,
                base.y,
                sim.contacts().len(),
                snapped(&total)
            );
            Ok((sim, note, total))
        }
        Placement::TipOnWall {
            wall,
            ahead_m,
            start,
        } => {
            let w = wall_of(*wall)?;
            let along = motion_direction(scene);
            let pin = point_ahead(w, base, along, *ahead_m);
            let mut start_note = String::new();
            let reach_m: f64 = chain.link_lengths_m().iter().sum();
            let distance_m = (pin - base).norm();
            if distance_m.is_nan() || distance_m >= reach_m {
                return Err(SweepError::Placement(format!(
                    "the tip cannot reach wall {wall} {ahead_m} m ahead of the base: the wall \
                     point there, ({:.4}, {:.4}) m, is {distance_m:.4} m from the base pivot \
                     and the antenna is {reach_m:.4} m long; move the base nearer the wall or \
                     choose another ahead_m",
                    pin.x, pin.y
                )));
            }
            let problem = EquilibriumProblem::new(&chain).with_tip_pin_m(pin - base);
            let mut eq = solve_equilibrium(&problem, start, &SolveOptions::default())?;
            if !eq.converged {
                // Another start's pinned equilibrium (said in the note), or the error.
                let residual = eq.kkt_residual;
                let found = other_starts(start).into_iter().find_map(|other| {
                    solve_equilibrium(&problem, &other, &SolveOptions::default())
                        .ok()
                        .filter(|alt| alt.converged)
                        .map(|alt| (other, alt))
                });
                let Some((other, alt)) = found else {
                    return Err(SweepError::Placement(format!(
                        "the pinned equilibrium with the tip at ({:.4}, {:.4}) m did not \
                         converge from a {start:?} start (KKT residual {residual:e}) nor from \
                         any other start",
                        pin.x, pin.y
                    )));
                };
                eq = alt;
                start_note = format!(
                    " (from the {start:?} start it did not converge, KKT residual \
                     {residual:.1e}; the {other:?} start's is used)"
                );
            }
            let crossing = deepest_crossing(&chain, &scene.walls, base, &eq.theta_rad);
            let tolerance = scene.settings.penetration_tolerance_m;
            let clear = |theta: &[f64]| {
                deepest_crossing(&chain, &scene.walls, base, theta)
                    .is_none_or(|c| c.depth_m <= tolerance)
            };
            // The pinned posture from the requested start where it is clear of the walls;
            // else the antenna held by its tip and brought onto the walls; else the first of
            // the other starts whose pinned posture is clear (said in the note).
            let place_clear = |theta: &[f64], iterations: usize, instead: &str| {
                // The pinned posture is clear of the walls, its tip on the wall: put it there,
                // let go and let it settle with friction.
                let mut sim = new_sim(base, theta)?;
                let report = settle(&mut sim)?;
                let flip = super::distal_flip(&sim, along.y.atan2(along.x));
                let note = format!(
                    "tip placed on wall {wall} at ({:.4}, {:.4}) m ({ahead_m} m ahead of the \
                     base): the pinned equilibrium from a {start:?} start ({iterations} \
                     iterations){instead}, let go and settled with friction{}; {} contact(s), \
                     distal segment at {:.1} deg to the wall",
                    pin.x,
                    pin.y,
                    snapped(&report),
                    sim.contacts().len(),
                    flip.map_or(f64::NAN, |f| f.angle_to_wall_rad.to_degrees()),
                );
                Ok::<_, SweepError>((sim, note, report))
            };
            if crossing.as_ref().is_none_or(|c| c.depth_m <= tolerance) {
                return place_clear(&eq.theta_rad, eq.iterations, &start_note);
            }
            // The pinned posture ignores the walls and crosses one: hold the tip there and
            // bring the held antenna onto the walls from where it is clear of them.
            let crossing_words = crossing
                .as_ref()
                .map(|c| {
                    format!(
                        "the {start:?} posture pinned there puts {} {:.2} mm inside wall {} at \
                         ({:.4}, {:.4}) m",
                        c.what,
                        c.depth_m * 1e3,
                        c.wall,
                        c.point_m.x,
                        c.point_m.y
                    )
                })
                .unwrap_or_default();
            let explain = |why: String| {
                SweepError::Placement(format!(
                    "with the tip pinned at ({:.4}, {:.4}) m on wall {wall}, {crossing_words}, \
                     and bringing the antenna onto the wall held by its tip failed: {why}; try \
                     another ahead_m or start",
                    pin.x, pin.y
                ))
            };
            let held = || -> Result<(QuasiStatic, String, StepReport), SweepError> {
                let away = w.signed_distance(&pin).normal;
                // Back off along the normal until clear (on a curved wall one step may not do).
                let mut clear_m = 0.0;
                for _ in 0..50 {
                    let depth = deepest_crossing(
                        &chain,
                        &scene.walls,
                        base + away * clear_m,
                        &eq.theta_rad,
                    )
                    .map_or(0.0, |c| c.depth_m);
                    if depth <= 0.0 {
                        break;
                    }
                    clear_m += depth + 1e-3;
                }
                let from = base + away * clear_m;
                let mut sim = new_sim(from, &eq.theta_rad).map_err(|e| explain(e.to_string()))?;
                sim.hold_tip(Some(pin - base));
                let mut total = settle(&mut sim).map_err(|e| explain(e.to_string()))?;
                let steps = ((clear_m / 2e-4).ceil() as usize).max(1);
                for k in 1..=steps {
                    let at = from + (base - from) * (k as f64 / steps as f64);
                    let r = sim.step_to(at).map_err(|e| explain(e.to_string()))?;
                    total.accumulate(&r);
                }
                let held_n = sim.hand_force_n();
                sim.hold_tip(None);
                let report = settle(&mut sim).map_err(|e| explain(e.to_string()))?;
                total.accumulate(&report);
                let flip = super::distal_flip(&sim, along.y.atan2(along.x));
                let note = format!(
                    "tip placed on wall {wall} at ({:.4}, {:.4}) m ({ahead_m} m ahead of the base): \
                 the pinned equilibrium from a {start:?} start ({} iterations){start_note} \
                 crosses a wall ({crossing_words}), so it was held by the tip and brought {clear_m:.4} m onto \
                 the wall in {steps} steps (the hand held it with ({:.4}, {:.4}) N), let go and \
                 settled with friction{}; {} contact(s), distal segment at {:.1} deg to the wall",
                    pin.x,
                    pin.y,
                    eq.iterations,
                    held_n.x,
                    held_n.y,
                    snapped(&report),
                    sim.contacts().len(),
                    flip.map_or(f64::NAN, |f| f.angle_to_wall_rad.to_degrees()),
                );
                Ok((sim, note, total))
            };
            let held_error = match held() {
                Ok(placed) => return Ok(placed),
                Err(e) => e,
            };
            for other in other_starts(start) {
                let Ok(alt) = solve_equilibrium(&problem, &other, &SolveOptions::default()) else {
                    continue;
                };
                if alt.converged && clear(&alt.theta_rad) {
                    let instead = format!(
                        " ({crossing_words}, and bringing it onto the wall held by its tip \
                         failed; the {other:?} start's pinned posture is clear and was used)"
                    );
                    return place_clear(&alt.theta_rad, alt.iterations, &instead);
                }
            }
            Err(held_error)
        }
    }
}

/// The starts tried after `start` when its pinned posture crosses a wall.
fn other_starts(start: &InitialGuess) -> Vec<InitialGuess> {
    [
        InitialGuess::C,
        InitialGuess::S,
        InitialGuess::Mirror(Box::new(InitialGuess::C)),
        InitialGuess::Mirror(Box::new(InitialGuess::S)),
        InitialGuess::Straight,
    ]
    .into_iter()
    .filter(|s| s != start)
    .collect()
}

/// The base link (the rigid link from the base pivot at the base angle) must be clear of
/// every wall before anything is placed: nothing the joints do can free it, so a wall through
/// it is said first ([`ContactError::BaseInsideWall`]), not as the failure of a placement.
fn base_link_clear(scene: &SweepScene) -> Result<(), SweepError> {
    let chain = &scene.chain;
    let base = scene.base_start_m;
    let poses = crate::frame_poses(chain, &chain.rest_theta(), crate::Frame::GROUND)
        .map_err(|e| SweepError::Placement(e.to_string()))?;
    let Some(end) = poses.position_m(crate::Frame::link(0)) else {
        return Ok(());
    };
    let end = base + end;
    for (w, wall) in scene.walls.iter().enumerate() {
        let gap_m = wall
            .segment_contact(&base, &end)
            .wall
            .gap_m
            .min(wall.signed_distance(&base).gap_m);
        if gap_m.is_nan() || gap_m < -scene.settings.penetration_tolerance_m {
            return Err(SweepError::Contact(ContactError::BaseInsideWall {
                wall: w,
                depth_m: -gap_m,
                base_x_m: base.x,
                base_y_m: base.y,
            }));
        }
    }
    Ok(())
}

/// Where a posture crosses a wall: the deepest crossing of a link or an open hair tip.
struct Crossing {
    /// What crosses, in words.
    what: String,
    /// The wall.
    wall: usize,
    /// How deep, metres.
    depth_m: f64,
    /// Where, ground frame.
    point_m: Vector2<f64>,
}

/// The deepest crossing of any link or open hair tip of the posture into any wall (`None`
/// if nothing reaches into a wall).
fn deepest_crossing(
    chain: &crate::Chain,
    walls: &[Wall],
    base: Vector2<f64>,
    theta: &[f64],
) -> Option<Crossing> {
    let poses = crate::frame_poses(chain, theta, crate::Frame::GROUND).ok()?;
    let mut deepest: Option<Crossing> = None;
    let mut consider = |what: &dyn Fn() -> String, wall: usize, gap_m: f64, point_m| {
        if gap_m < 0.0 && deepest.as_ref().is_none_or(|d| -gap_m > d.depth_m) {
            deepest = Some(Crossing {
                what: what(),
                wall,
                depth_m: -gap_m,
                point_m,
            });
        }
    };
    let mut at = base;
    for link in 0..=chain.n() {
        let Some(end) = poses.position_m(crate::Frame::link(link)) else {
            continue;
        };
        let end = base + end;
        for (w, wall) in walls.iter().enumerate() {
            let sc = wall.segment_contact(&at, &end);
            consider(&|| format!("link {link}"), w, sc.wall.gap_m, sc.point_m);
        }
        at = end;
    }
    // Hair tips, open against their stops.
    let open: Vec<f64> = chain
        .hairs()
        .iter()
        .map(|h| h.map_or(0.0, |h| h.rest_angle_rad()))
        .collect();
    if let Ok(hairs) = crate::hair_poses(chain, theta, &open, crate::Frame::GROUND) {
        for h in hairs {
            let tip = base + h.tip_m;
            for (w, wall) in walls.iter().enumerate() {
                let link = h.link;
                consider(
                    &|| format!("the hair tip of link {link}"),
                    w,
                    wall.signed_distance(&tip).gap_m,
                    tip,
                );
            }
        }
    }
    deepest
}

/// The unit direction of motion (`+x` when standing still).
fn motion_direction(scene: &SweepScene) -> Vector2<f64> {
    let v = scene.motion.velocity_m_per_s;
    if v == Vector2::zeros() {
        Vector2::new(1.0, 0.0)
    } else {
        v.normalize()
    }
}

/// A placement's settle may follow a long snap (a held antenna let go springs onto the
/// wall): it gets this many times the Newton iterations and snap steps of a sweep's step.
/// The factor applies to `max_step_iterations` and `max_snap_steps` as set; the solver then
/// scales both with the chain's joints
/// ([`crate::contact::ContactSettings::budget_reference_joints`]), so the settle's budget
/// grows with N as a step's does (N = 9: 100,000 Newton iterations and 20,000 snap steps,
/// as before; N = 150: 18.6 times that).
const SETTLE_BUDGET_FACTOR: usize = 10;

/// Settles the placed posture (a step of length zero), with [`SETTLE_BUDGET_FACTOR`] times
/// the step's budget (each scaled with the joints by the solver).
fn settle(sim: &mut QuasiStatic) -> Result<StepReport, SweepError> {
    let as_step = |source| SweepError::Step {
        step: 0,
        t_s: 0.0,
        source,
    };
    let step = *sim.settings();
    sim.set_settings(ContactSettings {
        max_step_iterations: step
            .max_step_iterations
            .saturating_mul(SETTLE_BUDGET_FACTOR),
        max_snap_steps: step.max_snap_steps.saturating_mul(SETTLE_BUDGET_FACTOR),
        ..step
    })
    .map_err(as_step)?;
    let settled = sim.settle();
    sim.set_settings(step).map_err(as_step)?;
    settled.map_err(as_step)
}

fn snapped(report: &StepReport) -> String {
    if report.snapped {
        format!(
            " (it snapped to rest: {} Newton iterations, {} pseudo-time steps)",
            report.iterations, report.snap_steps
        )
    } else {
        String::new()
    }
}

/// The point of `wall` whose position along `along` is `ahead_m` from `base`: the nearest
/// wall point to a probe moved along `along` until it is (a few fixed-point corrections).
fn point_ahead(wall: &Wall, base: Vector2<f64>, along: Vector2<f64>, ahead_m: f64) -> Vector2<f64> {
    let mut probe = base + along * ahead_m;
    let mut point = wall.signed_distance(&probe).closest_m;
    for _ in 0..50 {
        let error = ahead_m - (point - base).dot(&along);
        if error.abs() < 1e-13 {
            break;
        }
        probe += along * error;
        point = wall.signed_distance(&probe).closest_m;
    }
    point
}
