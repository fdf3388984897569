//! A jammed antenna: where the sweep physically cannot go on.

use nalgebra::Vector2;

use crate::contact::feature::Feature;

/// The antenna jammed against the walls: no posture within the joints' limits keeps every
/// link out of the walls with the base where it was to go; the contacts pin the chain and
/// the joints that could give are on their stops.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("the antenna jammed moving the base to ({base_x_m}, {base_y_m}) m: {description}")]
pub struct Jam {
    /// The base position aimed for, x.
    pub base_x_m: f64,
    /// The base position aimed for, y.
    pub base_y_m: f64,
    /// The contacts that pin it (at the last step solved).
    pub contacts: Vec<JammedContact>,
    /// The joints on a stop (`1..=n`).
    pub joints_on_stops: Vec<usize>,
    /// What pins it, in words.
    pub description: String,
}

/// A contact that pins a jammed antenna.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JammedContact {
    /// What touches.
    pub feature: Feature,
    /// Which wall.
    pub wall: usize,
    /// Where, ground frame, metres.
    pub point_m: Vector2<f64>,
    /// Its normal force at the last step solved, newtons.
    pub normal_force_n: f64,
}

// The diagnosis: a step the solver could not take, and the least penetration a posture near
// the last one can reach with the base at the goal.

use super::QuasiStatic;
use crate::contact::ContactError;
use crate::contact::broad_phase::Inputs;
use crate::contact::geometry::{PairGeometry, evaluate, generalized};
use crate::contact::pair::{PairKey, PairKind};
use crate::contact::posture::theta_of;
use crate::contact::posture::{Pose, Posture, perp};
use nalgebra::{DMatrix, DVector};

use crate::{Hair, JointLimit};

/// A step is a jam when no posture near the last one gets the links out of the walls by
/// better than this, metres.
const JAM_DEPTH_M: f64 = 1e-6;

/// The weight of a held tip's distance from the hand against a link's depth in a wall in
/// the least-penetration search: the hand holds the tip all but rigidly.
const HAND_WEIGHT: f64 = 1e3;

/// Gauss-Newton iterations of the least-penetration search.
const SEARCH_ITERATIONS: usize = 60;

/// A joint this close to a limit is on its stop, radians.
const ON_STOP_RAD: f64 = 1e-9;

impl QuasiStatic {
    /// Why a step to `goal` failed: a [`Jam`] where no posture near the last one (the joints
    /// within their limits, friction and springs aside) keeps every link out of the walls
    /// with the base at `goal` (pivot and angle); otherwise `error` as it was (the solver's
    /// failure).
    pub(super) fn diagnose_failure(&mut self, goal: Pose, error: ContactError) -> ContactError {
        if !matches!(error, ContactError::NoConvergence { .. }) {
            return error;
        }
        let (depth, deepest) = self.least_penetration(goal);
        if depth > JAM_DEPTH_M {
            ContactError::Jammed(Box::new(self.jam(goal, depth, &deepest)))
        } else {
            error
        }
    }

    /// The least penetration (metres) of the links and hair tips into the walls a projected
    /// Gauss-Newton search over the joint angles and the hair angles reaches from the current
    /// posture with the base at `goal` (pivot and angle), and what stays deepest ("link 3",
    /// "the hair tip of link 3").
    fn least_penetration(&mut self, goal: Pose) -> (f64, String) {
        let n = self.world.chain().n();
        // The coordinates: the joints `1..=n`, then the hair angle of each link with a hair.
        let hair_links: Vec<usize> = (0..=n)
            .filter(|&l| {
                self.world
                    .chain()
                    .hairs()
                    .get(l)
                    .is_some_and(Option::is_some)
            })
            .collect();
        let size = n + hair_links.len();
        let mut limits: Vec<JointLimit> = self.world.chain().joint_limits()[1..].to_vec();
        limits.extend(
            hair_links
                .iter()
                .filter_map(|&l| self.world.chain().hairs()[l].as_ref().map(Hair::fold_limit)),
        );
        let mut x: Vec<f64> = self.committed.theta()[1..].to_vec();
        x.extend(hair_links.iter().map(|&l| self.committed.beta()[l]));
        let mut posture = Posture::default();
        let mut beta = self.committed.beta().to_vec();
        // A hand holding the tip carries it with the base: the tip stays where the hand
        // holds it now, moved by the base's displacement and turned about the pivot by its
        // turn.
        let from = self.committed.pose();
        let hand_m = self.world.holds_tip().then(|| {
            posture.update(
                self.world.chain(),
                self.committed.base_m(),
                self.committed.theta(),
            );
            from.carry(&goal, posture.end_m[n])
        });
        // The penetrating pairs at `x`: each one's gap and geometry.
        let penetrating = |sim: &Self,
                           posture: &mut Posture,
                           beta: &mut Vec<f64>,
                           x: &[f64],
                           out: &mut Vec<(PairKey, PairGeometry)>| {
            posture.update_at(
                sim.world.chain(),
                goal,
                &theta_of(sim.committed.theta(), &x[..n]),
            );
            for (k, &l) in hair_links.iter().enumerate() {
                beta[l] = x[n + k];
            }
            out.clear();
            let inputs = Inputs {
                world: &sim.world,
                committed: &sim.committed,
                friction_off: sim.friction_off,
            };
            let touching = sim
                .broad_phase
                .touching(inputs, posture, beta, 0.0, usize::MAX);
            for key in point_keys(touching) {
                let mut geo = PairGeometry::at(key.link, 1.0, Vector2::zeros());
                evaluate(
                    sim.world.chain(),
                    &sim.world.pieces().walls[key.piece],
                    posture,
                    beta,
                    &key,
                    &mut geo,
                );
                if geo.gap_m < 0.0 && geo.gap_m.is_finite() {
                    out.push((key, geo));
                }
            }
        };
        let mut pairs = Vec::new();
        let mut measure = |sim: &Self, posture: &mut Posture, beta: &mut Vec<f64>, x: &[f64]| {
            penetrating(sim, posture, beta, x, &mut pairs);
            let mut sum = hand_m.map_or(0.0, |h| {
                0.5 * (HAND_WEIGHT * (posture.end_m[n] - h)).norm_squared()
            });
            let (mut deepest, mut what) = (0.0_f64, None);
            for (key, geo) in &pairs {
                sum += 0.5 * geo.gap_m * geo.gap_m;
                if -geo.gap_m > deepest {
                    deepest = -geo.gap_m;
                    what = Some(*key);
                }
            }
            (sum, deepest, what)
        };
        let (mut merit, mut deepest, mut link) = measure(self, &mut posture, &mut beta, &x);
        let mut damping = 1e-6;
        let mut row = vec![0.0; size];
        let mut at_x = Vec::new();
        for _ in 0..SEARCH_ITERATIONS {
            if deepest <= JAM_DEPTH_M * 1e-3 {
                break;
            }
            // The penetrating pairs' gradients at the current posture.
            penetrating(self, &mut posture, &mut beta, &x, &mut at_x);
            let mut ata = DMatrix::<f64>::zeros(size, size);
            let mut atr = DVector::<f64>::zeros(size);
            let mut add = |row: &[f64], residual: f64| {
                for i in 0..size {
                    atr[i] += row[i] * residual;
                    for j in 0..size {
                        ata[(i, j)] += row[i] * row[j];
                    }
                }
            };
            for (key, geo) in &at_x {
                row.fill(0.0);
                let hair_entry = generalized(&posture, geo, geo.normal, &mut row[..n]);
                if let Some(k) = key
                    .hair_link()
                    .and_then(|l| hair_links.iter().position(|&h| h == l))
                {
                    row[n + k] = hair_entry;
                }
                add(&row, geo.gap_m);
            }
            if let Some(h) = hand_m {
                let miss = posture.end_m[n] - h;
                for axis in 0..2 {
                    row.fill(0.0);
                    for (i, r) in row[..n].iter_mut().enumerate() {
                        *r = HAND_WEIGHT * perp(posture.end_m[n] - posture.end_m[i])[axis];
                    }
                    add(&row, HAND_WEIGHT * miss[axis]);
                }
            }
            // Joints on a stop that the step would push further are held.
            let scale = (0..size)
                .fold(0.0_f64, |a, i| a.max(ata[(i, i)]))
                .max(1e-12);
            let mut improved = false;
            for _ in 0..12 {
                let mut m = ata.clone();
                for i in 0..size {
                    m[(i, i)] += damping * scale;
                }
                let Some(dx) = m.lu().solve(&(-&atr)) else {
                    damping *= 10.0;
                    continue;
                };
                let trial: Vec<f64> = (0..size)
                    .map(|i| (x[i] + dx[i]).clamp(limits[i].cw_rad, limits[i].ccw_rad))
                    .collect();
                let (m2, d2, l2) = measure(self, &mut posture, &mut beta, &trial);
                if m2 < merit {
                    x = trial;
                    (merit, deepest, link) = (m2, d2, l2);
                    damping = (damping * 0.1).max(1e-9);
                    improved = true;
                    break;
                }
                damping *= 10.0;
            }
            if !improved {
                break;
            }
        }
        let what = link.map_or_else(
            || "no link".to_owned(),
            |key| match key.hair_link() {
                Some(l) => format!("the hair tip of link {l}"),
                None => format!("link {}", key.link),
            },
        );
        (deepest, what)
    }

    /// The jam at the current state, for a step to `goal` that leaves `deepest` (a link or a
    /// hair tip, in words) at least `depth_m` inside a wall.
    fn jam(&self, goal: Pose, depth_m: f64, deepest: &str) -> Jam {
        let contacts: Vec<JammedContact> = self
            .contacts()
            .iter()
            .filter(|c| c.normal_force_n > 0.0)
            .map(|c| JammedContact {
                feature: c.feature,
                wall: c.wall,
                point_m: c.point_m,
                normal_force_n: c.normal_force_n,
            })
            .collect();
        let limits = self.world.chain().joint_limits();
        let mut joints_on_stops = Vec::new();
        let mut stops = Vec::new();
        for (j, (&t, lim)) in self
            .committed
            .theta()
            .iter()
            .zip(limits)
            .enumerate()
            .skip(1)
        {
            if t <= lim.cw_rad + ON_STOP_RAD {
                joints_on_stops.push(j);
                stops.push(format!("joint {j} on its clockwise stop"));
            } else if t >= lim.ccw_rad - ON_STOP_RAD {
                joints_on_stops.push(j);
                stops.push(format!("joint {j} on its counter-clockwise stop"));
            }
        }
        let pins: Vec<String> = contacts
            .iter()
            .map(|c| {
                format!(
                    "{} against wall {} at ({:.4}, {:.4}) m with {:.3} N",
                    describe(c.feature, self.world.chain().n()),
                    c.wall,
                    c.point_m.x,
                    c.point_m.y,
                    c.normal_force_n
                )
            })
            .collect();
        let turn_rad = goal.angle_rad - self.committed.theta()[0];
        let turning = if turn_rad == 0.0 {
            String::new()
        } else {
            format!(
                " with the base turned by {:.3} degrees",
                turn_rad.to_degrees()
            )
        };
        let description = format!(
            "no posture near the last one{turning}{} keeps {deepest} out of the walls (it \
             stays {:.3} mm inside); {}; pinned by {}",
            if self.world.holds_tip() {
                " with the tip where the hand holds it"
            } else {
                ""
            },
            depth_m * 1e3,
            if stops.is_empty() {
                "no joint on a stop".to_owned()
            } else {
                stops.join(", ")
            },
            if pins.is_empty() {
                "no loaded contact".to_owned()
            } else {
                pins.join("; ")
            }
        );
        Jam {
            base_x_m: goal.base_m.x,
            base_y_m: goal.base_m.y,
            contacts,
            joints_on_stops,
            description,
        }
    }
}

/// A feature in words.
fn describe(feature: Feature, n: usize) -> String {
    match feature {
        Feature::Vertex { link } if link == n => "the tip".to_owned(),
        Feature::Vertex { link } => format!("joint {}", link + 1),
        Feature::Link { link } => format!("link {link} between its joints"),
        Feature::HairTip { link } => format!("the hair tip of link {link}"),
    }
}

/// `keys` with each point's corner-edge pairs taken back to its point pair: a point on a
/// corner is inside the wall only where it is behind both edge lines, which its distance to
/// the piece measures and either line alone overstates.
fn point_keys(keys: Vec<PairKey>) -> Vec<PairKey> {
    let mut out: Vec<PairKey> = keys
        .into_iter()
        .map(|key| match key.kind {
            PairKind::CornerEdge { point, .. } => PairKey::point(point, key.piece),
            _ => key,
        })
        .collect();
    out.sort();
    out.dedup();
    out
}
