//! The body: its state and one step of its motion under a command held over the step.
//!
//! # Frame and signs
//! Everything here is in the frame where the wall is on the body's **left** (the loop solves
//! a right-wall run as its mirror image): `heading_rad` is the ground-frame heading,
//! counter-clockwise, and the turning rate `omega` is positive turning **away** from the
//! wall, i.e. clockwise: `d heading / dt = -omega`. The point of rotation (POR) runs at the
//! forward speed `v` along the heading: `d por / dt = v (cos heading, sin heading)`.
//!
//! # The two bodies and their integrators
//! - [`BodyModel::Template`] (Cowan, Lee and Full 2006): the command is the moment `u`
//!   (N m, positive away from the wall), held over the step (a zero-order hold);
//!   `J d omega / dt = -b omega + u`. The state `(por, heading, omega)` is advanced by the
//!   classic fourth-order Runge-Kutta method (RK4): a global error of order `h^4` in the
//!   step `h` (halving the step cuts it about 16 times; a test checks it).
//! - [`BodyModel::Wheeled`]: the command is the wanted turning rate (rad/s, positive away
//!   from the wall), clamped to the rate limit; the turning rate moves toward it at the
//!   acceleration limit, linearly within the step, and stays there once reached (so it moves
//!   by at most `max_turn_accel dt` a step). The turning rate and the heading are integrated
//!   exactly (piecewise linear and quadratic in time); the position exactly on the stretch
//!   of constant rate (an arc, or a straight line) and by five-point Gauss-Legendre
//!   quadrature of `v (cos heading, sin heading)` on the ramp (exact for a polynomial
//!   integrand of degree 9: an error of order `h^11` per step, far below RK4's).
//!
//! A step of no duration (or a non-finite or negative one) leaves the state as it is; a
//! non-finite command gives a non-finite state (no panic): the caller checks its commands.

use core::f64::consts::PI;

use nalgebra::Vector2;

use super::BodyModel;

/// The body's state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyState {
    /// The point of rotation, ground frame, m.
    pub por_m: Vector2<f64>,
    /// The heading, ground frame, counter-clockwise, radians.
    pub heading_rad: f64,
    /// The turning rate, rad/s, positive away from the wall (clockwise, the wall on the
    /// left): `d heading / dt = -omega`.
    pub omega_rad_per_s: f64,
}

impl BodyState {
    /// A body at rest in turning (`omega = 0`) at `por_m` with `heading_rad`.
    pub fn new(por_m: Vector2<f64>, heading_rad: f64) -> BodyState {
        BodyState {
            por_m,
            heading_rad,
            omega_rad_per_s: 0.0,
        }
    }

    /// The unit vector along the heading (the body's x axis), ground frame.
    pub fn forward(&self) -> Vector2<f64> {
        Vector2::new(self.heading_rad.cos(), self.heading_rad.sin())
    }

    /// The unit vector toward the wall (the body's y axis: the heading's left), ground
    /// frame.
    pub fn toward_wall(&self) -> Vector2<f64> {
        Vector2::new(-self.heading_rad.sin(), self.heading_rad.cos())
    }

    /// A point given in the body frame (x ahead, y toward the wall), in the ground frame.
    pub fn to_ground(&self, body_m: &Vector2<f64>) -> Vector2<f64> {
        self.por_m + self.forward() * body_m.x + self.toward_wall() * body_m.y
    }
}

/// One step of `dt_s` seconds of a body running at `speed_m_per_s` under `command` (the
/// template's moment `u`, N m; the wheeled robot's wanted turning rate, rad/s; both
/// positive away from the wall), held over the step. See the module docs for the
/// integrators.
pub fn step_body(
    model: &BodyModel,
    speed_m_per_s: f64,
    state: &BodyState,
    command: f64,
    dt_s: f64,
) -> BodyState {
    if !(dt_s > 0.0 && dt_s.is_finite()) {
        return *state;
    }
    match *model {
        BodyModel::Template {
            inertia_kg_m2,
            damping_n_m_s_per_rad,
        } => step_template(
            inertia_kg_m2,
            damping_n_m_s_per_rad,
            speed_m_per_s,
            state,
            command,
            dt_s,
        ),
        BodyModel::Wheeled {
            max_turn_rate_rad_per_s,
            max_turn_accel_rad_per_s2,
        } => step_wheeled(
            max_turn_rate_rad_per_s,
            max_turn_accel_rad_per_s2,
            speed_m_per_s,
            state,
            command,
            dt_s,
        ),
    }
}

/// The template's state as a vector `(x, y, heading, omega)` and its derivative.
fn template_derivative(
    inertia_kg_m2: f64,
    damping_n_m_s_per_rad: f64,
    speed_m_per_s: f64,
    moment_n_m: f64,
    s: &[f64; 4],
) -> [f64; 4] {
    let (sin, cos) = s[2].sin_cos();
    [
        speed_m_per_s * cos,
        speed_m_per_s * sin,
        -s[3],
        (moment_n_m - damping_n_m_s_per_rad * s[3]) / inertia_kg_m2,
    ]
}

/// One classic RK4 step of the template.
fn step_template(
    inertia_kg_m2: f64,
    damping_n_m_s_per_rad: f64,
    speed_m_per_s: f64,
    state: &BodyState,
    moment_n_m: f64,
    h: f64,
) -> BodyState {
    let f = |s: &[f64; 4]| {
        template_derivative(
            inertia_kg_m2,
            damping_n_m_s_per_rad,
            speed_m_per_s,
            moment_n_m,
            s,
        )
    };
    let add = |s: &[f64; 4], k: &[f64; 4], scale: f64| {
        [
            s[0] + scale * k[0],
            s[1] + scale * k[1],
            s[2] + scale * k[2],
            s[3] + scale * k[3],
        ]
    };
    let s0 = [
        state.por_m.x,
        state.por_m.y,
        state.heading_rad,
        state.omega_rad_per_s,
    ];
    let k1 = f(&s0);
    let k2 = f(&add(&s0, &k1, 0.5 * h));
    let k3 = f(&add(&s0, &k2, 0.5 * h));
    let k4 = f(&add(&s0, &k3, h));
    let mut s1 = s0;
    for i in 0..4 {
        s1[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
    }
    BodyState {
        por_m: Vector2::new(s1[0], s1[1]),
        heading_rad: s1[2],
        omega_rad_per_s: s1[3],
    }
}

/// Five-point Gauss-Legendre nodes and weights on `[-1, 1]`.
const GAUSS_5: [(f64, f64); 5] = [
    (0.0, 0.568_888_888_888_888_9),
    (-0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
    (0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
    (-0.906_179_845_938_664, 0.236_926_885_056_189_1),
    (0.906_179_845_938_664, 0.236_926_885_056_189_1),
];

/// One step of the wheeled robot: the turning rate ramps toward the clamped command at the
/// acceleration limit, then holds.
fn step_wheeled(
    max_turn_rate_rad_per_s: f64,
    max_turn_accel_rad_per_s2: f64,
    speed_m_per_s: f64,
    state: &BodyState,
    command_rad_per_s: f64,
    h: f64,
) -> BodyState {
    let target = command_rad_per_s.clamp(-max_turn_rate_rad_per_s, max_turn_rate_rad_per_s);
    let omega0 = state.omega_rad_per_s;
    let change = target - omega0;
    // The ramp: omega0 + accel t over [0, ramp_s], then `omega1` held.
    let accel = max_turn_accel_rad_per_s2.copysign(change);
    let ramp_s = if change == 0.0 {
        0.0
    } else {
        (change.abs() / max_turn_accel_rad_per_s2).min(h)
    };
    let omega1 = if ramp_s < h {
        target
    } else {
        omega0 + accel * h
    };
    let mut por_m = state.por_m;
    let mut heading = state.heading_rad;
    if ramp_s > 0.0 {
        // heading(t) = heading0 - omega0 t - accel t^2 / 2 over the ramp.
        let half = 0.5 * ramp_s;
        let mut sum = Vector2::zeros();
        for (x, w) in GAUSS_5 {
            let t = half * (1.0 + x);
            let a = heading - omega0 * t - 0.5 * accel * t * t;
            sum += Vector2::new(a.cos(), a.sin()) * w;
        }
        por_m += sum * (half * speed_m_per_s);
        heading -= omega0 * ramp_s + 0.5 * accel * ramp_s * ramp_s;
    }
    let rest_s = h - ramp_s;
    if rest_s > 0.0 {
        // An arc at the constant rate omega1: the chord of the turn by -omega1 rest_s.
        let turn = -omega1 * rest_s;
        let length_m = speed_m_per_s * rest_s;
        // (sin(turn / 2) / (turn / 2), computed without a cancellation for small turns.)
        let half = 0.5 * turn;
        let sinc = if half.abs() < 1e-4 {
            1.0 - half * half / 6.0
        } else {
            half.sin() / half
        };
        let chord_angle = heading + half;
        por_m += Vector2::new(chord_angle.cos(), chord_angle.sin()) * (length_m * sinc);
        heading += turn;
    }
    BodyState {
        por_m,
        heading_rad: heading,
        omega_rad_per_s: omega1,
    }
}

/// The heading wrapped to `(-pi, pi]`.
pub fn wrap_angle_rad(angle_rad: f64) -> f64 {
    let wrapped = (angle_rad + PI).rem_euclid(2.0 * PI) - PI;
    if wrapped == -PI { PI } else { wrapped }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEMPLATE: BodyModel = BodyModel::Template {
        inertia_kg_m2: 2.0e-4,
        damping_n_m_s_per_rad: 4.0e-3,
    };

    fn run(model: &BodyModel, v: f64, start: BodyState, u: f64, dt: f64, t: f64) -> BodyState {
        let steps = (t / dt).round() as usize;
        let mut s = start;
        for _ in 0..steps {
            s = step_body(model, v, &s, u, dt);
        }
        s
    }

    fn distance(a: &BodyState, b: &BodyState) -> f64 {
        (a.por_m - b.por_m)
            .norm()
            .max((a.heading_rad - b.heading_rad).abs())
            .max((a.omega_rad_per_s - b.omega_rad_per_s).abs() * 1e-2)
    }

    #[test]
    fn the_template_is_integrated_to_fourth_order() {
        let start = BodyState {
            por_m: Vector2::new(0.1, -0.2),
            heading_rad: 0.3,
            omega_rad_per_s: 4.0,
        };
        let (v, u, t) = (0.8, -2.0e-3, 0.4);
        let reference = run(&TEMPLATE, v, start, u, 1e-5, t);
        let coarse = distance(&run(&TEMPLATE, v, start, u, 0.01, t), &reference);
        let fine = distance(&run(&TEMPLATE, v, start, u, 0.005, t), &reference);
        let ratio = coarse / fine;
        assert!((12.0..20.0).contains(&ratio), "{coarse} / {fine} = {ratio}");
        // And the turning rate against its closed form.
        let (j, b) = (2.0e-4, 4.0e-3);
        let exact = u / b + (4.0 - u / b) * (-b / j * t).exp();
        let omega = run(&TEMPLATE, v, start, u, 0.005, t).omega_rad_per_s;
        assert!((omega - exact).abs() < 1e-5, "{omega} vs {exact}");
    }

    #[test]
    fn a_constant_moment_settles_at_its_turning_rate() {
        let u = 1.0e-3;
        let s = run(
            &TEMPLATE,
            0.3,
            BodyState::new(Vector2::zeros(), 0.0),
            u,
            0.01,
            2.0,
        );
        assert!((s.omega_rad_per_s - u / 4.0e-3).abs() < 1e-9, "{s:?}");
        // Positive: away from the wall on the left, clockwise.
        assert!(s.heading_rad < 0.0);
    }

    #[test]
    fn no_moment_and_no_turn_run_straight() {
        let start = BodyState::new(Vector2::new(1.0, 2.0), 0.7);
        let s = run(&TEMPLATE, 0.5, start, 0.0, 0.01, 3.0);
        assert_eq!(s.heading_rad, 0.7);
        assert_eq!(s.omega_rad_per_s, 0.0);
        let expected = Vector2::new(1.0, 2.0) + start.forward() * 1.5;
        assert!((s.por_m - expected).norm() < 1e-12, "{s:?}");
        // A step of no (or no valid) duration changes nothing.
        for dt in [0.0, -0.01, f64::NAN] {
            assert_eq!(step_body(&TEMPLATE, 0.5, &start, 1.0, dt), start);
        }
    }

    const WHEELED: BodyModel = BodyModel::Wheeled {
        max_turn_rate_rad_per_s: 2.0,
        max_turn_accel_rad_per_s2: 10.0,
    };

    #[test]
    fn the_wheeled_robot_keeps_its_limits() {
        let dt = 0.01;
        let mut s = BodyState::new(Vector2::zeros(), 0.0);
        let mut rates = Vec::new();
        for k in 0..100 {
            let command = if k < 50 { 100.0 } else { -100.0 };
            let next = step_body(&WHEELED, 0.3, &s, command, dt);
            assert!(
                (next.omega_rad_per_s - s.omega_rad_per_s).abs() <= 10.0 * dt + 1e-12,
                "step {k}"
            );
            assert!(next.omega_rad_per_s.abs() <= 2.0 + 1e-12);
            rates.push(next.omega_rad_per_s);
            s = next;
        }
        // The rate reaches the limit after 0.2 s, and turns back at the acceleration limit.
        assert!((rates[19] - 2.0).abs() < 1e-12 && (rates[49] - 2.0).abs() < 1e-12);
        assert!((rates[50] - 1.9).abs() < 1e-12);
        assert!((rates[99] + 2.0).abs() < 1e-12);
        // Within reach in a step: the command exactly.
        let s = step_body(
            &WHEELED,
            0.3,
            &BodyState::new(Vector2::zeros(), 0.0),
            0.05,
            dt,
        );
        assert_eq!(s.omega_rad_per_s, 0.05);
    }

    #[test]
    fn a_constant_turning_rate_draws_a_circle_of_radius_v_over_omega() {
        let (v, omega, dt) = (0.4, 1.5, 0.01);
        let radius = v / omega;
        let mut s = BodyState::new(Vector2::new(0.2, 0.1), 0.5);
        // Ramp up first; then every point lies on one circle, centred on the right.
        for _ in 0..20 {
            s = step_body(&WHEELED, v, &s, omega, dt);
        }
        assert_eq!(s.omega_rad_per_s, omega);
        let centre = s.por_m - s.toward_wall() * radius;
        for _ in 0..500 {
            s = step_body(&WHEELED, v, &s, omega, dt);
            let r = (s.por_m - centre).norm();
            assert!((r - radius).abs() < 1e-12, "{r} vs {radius}");
        }
        // The ramp's heading: exact (quadratic), and its path against fine RK4 steps of
        // the same rate profile.
        let start = BodyState::new(Vector2::zeros(), 0.2);
        let ramped = step_body(&WHEELED, v, &start, 2.0, 0.1);
        assert!((ramped.heading_rad - (0.2 - 0.5 * 10.0 * 0.01)).abs() < 1e-15);
        let mut p = Vector2::zeros();
        let n = 10_000;
        let h = 0.1 / n as f64;
        let heading = |t: f64| 0.2 - 5.0 * t * t;
        let vel = |t: f64| Vector2::new(heading(t).cos(), heading(t).sin()) * v;
        for k in 0..n {
            let t = k as f64 * h;
            p += (vel(t) + vel(t + 0.5 * h) * 4.0 + vel(t + h)) * (h / 6.0);
        }
        assert!(
            (ramped.por_m - p).norm() < 1e-13,
            "{:?} vs {p:?}",
            ramped.por_m
        );
    }

    #[test]
    fn angles_wrap_to_a_half_open_interval() {
        assert_eq!(wrap_angle_rad(PI), PI);
        assert_eq!(wrap_angle_rad(-PI), PI);
        assert!((wrap_angle_rad(3.0 * PI + 0.1) - (-PI + 0.1)).abs() < 1e-12);
        assert!((wrap_angle_rad(-0.2) + 0.2).abs() < 1e-15);
    }
}
