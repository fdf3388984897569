//! Run time against error for the equilibrium solvers (issue 4): writes the "Equilibrium"
//! section of docs/benchmarks/equilibrium.md (between `<!-- equilibrium:begin -->` and
//! `<!-- equilibrium:end -->`, appended when missing) and the plot
//! `docs/figures/equilibrium_time_vs_error.svg`.
//!
//! 1. A cantilever (L = 0.36 m, EI = 0.02 N m^2, clamped along x) with a perpendicular dead
//!    tip load, `alpha = F L^2 / EI` in {0.5, 1, 2, 5, 10}: relative error of the tip
//!    deflection against the elastica (the Bisshopp-Drucker closed form) and time per solve,
//!    for chains of n = 8..4096 flexible joints in both layouts of `sim_core::statics::beam` and for
//!    Richardson extrapolation over 2, 3 and 4 Hencky chains.
//! 2. The thesis's robot with its tip pinned (9 links of 40 mm: 8 flexible joints; fast-exponential
//!    stiffness 0.004..0.082 N m/rad, base angle 30 deg): time per solve from a straight
//!    start and warm-started from the previous solution while the pin moves in 0.5 mm steps.
//!
//! Times are medians over repeated solves after a warm-up (`std::time::Instant`, one thread).
//! Run by `scripts/bench-equilibrium` (release build).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use nalgebra::Vector2;
use plotters::prelude::*;
use sim_core::Chain;
use sim_core::design::profile::{SEED_K_MAX_N_M_PER_RAD, SEED_K_MIN_N_M_PER_RAD, StiffnessProfile};
use sim_core::statics::beam::{
    Beam, BeamLayout, RichardsonOptions, richardson_tip, solve_beam_chain,
};
use sim_core::statics::elastica::{
    ElasticaOptions, perpendicular_load_closed_form, solve as solve_elastica,
};
use sim_core::statics::equilibrium::{
    EquilibriumProblem, InitialGuess, SolveOptions, solve_equilibrium,
};

type BoxResult<T> = Result<T, Box<dyn std::error::Error>>;

const BEGIN: &str = "<!-- equilibrium:begin -->";
const END: &str = "<!-- equilibrium:end -->";
const FIGURE: &str = "docs/figures/equilibrium_time_vs_error.svg";
const ALPHAS: [f64; 5] = [0.5, 1.0, 2.0, 5.0, 10.0];
const LENGTH_M: f64 = 0.36;
const EI_N_M2: f64 = 0.02;
/// The accuracy goal and the time budget of the issue.
const GOAL_ERROR: f64 = 1e-6;
const GOAL_TIME_S: f64 = 1e-3;
/// Time spent measuring one configuration (after the warm-up), s.
const BUDGET_S: f64 = 0.08;
/// Error floor for the log plot (exact agreement is drawn here).
const PLOT_FLOOR: f64 = 1e-16;
/// Errors below this are rounding, not discretization: left out of the observed orders.
const ORDER_FLOOR: f64 = 1e-11;

#[derive(Clone, Copy, Debug, PartialEq)]
enum Method {
    EqualLinks,
    Hencky,
    Richardson(usize),
}

impl Method {
    const ALL: [Method; 5] = [
        Method::EqualLinks,
        Method::Hencky,
        Method::Richardson(2),
        Method::Richardson(3),
        Method::Richardson(4),
    ];

    fn label(self) -> String {
        match self {
            Method::EqualLinks => "chain, equal links (order 1)".into(),
            Method::Hencky => "chain, Hencky (order 2)".into(),
            Method::Richardson(s) => format!("Richardson, {s} Hencky solves (order {})", 2 * s),
        }
    }

    fn short(self) -> String {
        match self {
            Method::EqualLinks => "equal links".into(),
            Method::Hencky => "Hencky".into(),
            Method::Richardson(s) => format!("Richardson x{s}"),
        }
    }

    /// Finest chains measured (the largest chain of a Richardson run).
    fn sizes(self) -> Vec<usize> {
        let first = match self {
            Method::EqualLinks | Method::Hencky => 8,
            Method::Richardson(s) => 4 << (s - 1),
        };
        (3..=12)
            .map(|p| 1usize << p)
            .filter(|&n| n >= first)
            .collect()
    }

    fn color(self) -> RGBColor {
        match self {
            Method::EqualLinks => RGBColor(150, 150, 150),
            Method::Hencky => RGBColor(31, 119, 180),
            Method::Richardson(2) => RGBColor(255, 127, 14),
            Method::Richardson(3) => RGBColor(44, 160, 44),
            Method::Richardson(_) => RGBColor(214, 39, 40),
        }
    }
}

#[derive(Clone, Debug)]
struct Point {
    method: Method,
    alpha: f64,
    /// Flexible joints of the finest chain solved.
    links: usize,
    time_s: f64,
    relative_error: f64,
    /// Newton iterations over all solves of one run.
    iterations: usize,
}

/// Median time of `f` over repeats filling [`BUDGET_S`] (at least 5, at most 2001), after
/// one warm-up call whose result is returned.
fn time_median<R>(mut f: impl FnMut() -> BoxResult<R>) -> BoxResult<(f64, R)> {
    let result = f()?;
    let start = Instant::now();
    f()?;
    let first_s = start.elapsed().as_secs_f64().max(1e-9);
    let repeats = ((BUDGET_S / first_s) as usize).clamp(5, 2001);
    let mut times = Vec::with_capacity(repeats);
    for _ in 0..repeats {
        let start = Instant::now();
        std::hint::black_box(f()?);
        times.push(start.elapsed().as_secs_f64());
    }
    Ok((median(&mut times), result))
}

fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n == 0 {
        f64::NAN
    } else if n % 2 == 1 {
        values[n / 2]
    } else {
        0.5 * (values[n / 2 - 1] + values[n / 2])
    }
}

/// The elastica shooting solver at one alpha: time per solve and error against the closed
/// form.
struct ElasticaRun {
    alpha: f64,
    time_s: f64,
    relative_error: f64,
}

fn measure_cantilever() -> BoxResult<(Vec<Point>, Vec<ElasticaRun>)> {
    let beam = Beam::uniform(LENGTH_M, EI_N_M2, 0.0);
    let mut points = Vec::new();
    let mut elastica = Vec::new();
    for alpha in ALPHAS {
        let force = Vector2::new(0.0, alpha * EI_N_M2 / (LENGTH_M * LENGTH_M));
        let exact_m = perpendicular_load_closed_form(alpha)?.tip_transverse_over_length * LENGTH_M;
        // The reference solver itself: shooting with a Gragg-Bulirsch-Stoer integrator.
        let problem = beam.elastica_problem(force);
        let (time_s, sol) =
            time_median(|| Ok(solve_elastica(&problem, &ElasticaOptions::default())?))?;
        elastica.push(ElasticaRun {
            alpha,
            time_s,
            relative_error: (sol.tip_position_m[1] / exact_m - 1.0).abs(),
        });
        for method in Method::ALL {
            for links in method.sizes() {
                let (time_s, (y_m, iterations)) = match method {
                    Method::EqualLinks | Method::Hencky => {
                        let layout = if method == Method::Hencky {
                            BeamLayout::Hencky
                        } else {
                            BeamLayout::EqualLinks
                        };
                        time_median(|| {
                            let tip = solve_beam_chain(
                                &beam,
                                links,
                                layout,
                                force,
                                &InitialGuess::Straight,
                                &SolveOptions {
                                    tolerance: RichardsonOptions::default().tolerance_times_links
                                        / links as f64,
                                    ..SolveOptions::default()
                                },
                            )?;
                            Ok((tip.tip_position_m.y, tip.iterations))
                        })?
                    }
                    Method::Richardson(solves) => {
                        let options = RichardsonOptions {
                            coarsest_links: links >> (solves - 1),
                            solves,
                            ..RichardsonOptions::default()
                        };
                        time_median(|| {
                            let r = richardson_tip(&beam, force, &options)?;
                            let its = r.solves.iter().map(|s| s.iterations).sum();
                            Ok((r.tip_position_m.y, its))
                        })?
                    }
                };
                let relative_error = (y_m / exact_m - 1.0).abs();
                eprintln!(
                    "alpha {alpha:>4} {:<16} n {links:>5}: {:>10}  error {relative_error:.2e}  ({iterations} its)",
                    method.short(),
                    fmt_time(time_s)
                );
                points.push(Point {
                    method,
                    alpha,
                    links,
                    time_s,
                    relative_error,
                    iterations,
                });
            }
        }
    }
    Ok((points, elastica))
}

/// The thesis's robot as docs/scene-format.md counts it: 9 links of 40 mm (the base link and 8
/// flexible joints), fast-exponential stiffness, base at 30 deg.
fn seed_chain() -> BoxResult<Chain> {
    let lengths = vec![0.04; 9];
    let k = StiffnessProfile::FastExponential.stiffness_n_m_per_rad(
        &lengths,
        SEED_K_MIN_N_M_PER_RAD,
        SEED_K_MAX_N_M_PER_RAD,
    )?;
    Ok(Chain::builder(8)
        .link_lengths_m(lengths)
        .base_angle_rad(30f64.to_radians())
        .stiffnesses_nm_per_rad(k)
        .build()?)
}

struct PinnedResult {
    label: String,
    time_s: f64,
    iterations_median: f64,
    converged: usize,
    solves: usize,
    same_as_warm: usize,
}

/// The pinned-tip sweep: one result per start, the number of steps, the first and last pin.
struct Pinned {
    results: Vec<PinnedResult>,
    steps: usize,
    first_m: [f64; 2],
    last_m: [f64; 2],
}

fn measure_pinned() -> BoxResult<Pinned> {
    let chain = seed_chain()?;
    let options = SolveOptions::default();
    let start_pin = Vector2::new(0.26, 0.10);
    let steps = 100;
    let step = Vector2::new(-0.0005, 0.0);
    let pins: Vec<Vector2<f64>> = (0..=steps).map(|i| start_pin + step * i as f64).collect();
    let problem = |pin: Vector2<f64>| EquilibriumProblem {
        chain: &chain,
        tip_force_n: Vector2::zeros(),
        tip_pin_m: Some(pin),
    };

    // The sweep: every solve starts from the previous answer; the first from a C.
    let mut warm_thetas: Vec<Vec<f64>> = Vec::with_capacity(pins.len());
    let mut warm_times = Vec::new();
    let mut warm_its = Vec::new();
    let mut warm_converged = 0;
    let first = solve_equilibrium(&problem(pins[0]), &InitialGuess::C, &options)?;
    warm_thetas.push(first.theta_rad.clone());
    for pin in &pins[1..] {
        let initial = InitialGuess::Angles(warm_thetas[warm_thetas.len() - 1][1..].to_vec());
        let p = problem(*pin);
        let (time_s, eq) = time_median(|| Ok(solve_equilibrium(&p, &initial, &options)?))?;
        warm_times.push(time_s);
        warm_its.push(eq.iterations as f64);
        warm_converged += usize::from(eq.converged);
        warm_thetas.push(eq.theta_rad);
    }
    let mut results = vec![PinnedResult {
        label: "warm start: previous step's answer (the sweep)".into(),
        time_s: median(&mut warm_times),
        iterations_median: median(&mut warm_its),
        converged: warm_converged,
        solves: steps,
        same_as_warm: steps,
    }];
    for (label, initial) in [
        ("cold start: straight", InitialGuess::Straight),
        ("cold start: C", InitialGuess::C),
    ] {
        let mut times = Vec::new();
        let mut its = Vec::new();
        let (mut converged, mut same) = (0, 0);
        for (pin, warm) in pins[1..].iter().zip(&warm_thetas[1..]) {
            let p = problem(*pin);
            let (time_s, eq) = time_median(|| Ok(solve_equilibrium(&p, &initial, &options)?))?;
            times.push(time_s);
            its.push(eq.iterations as f64);
            converged += usize::from(eq.converged);
            let gap = eq
                .theta_rad
                .iter()
                .zip(warm)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            same += usize::from(gap < 1e-6);
        }
        results.push(PinnedResult {
            label: label.into(),
            time_s: median(&mut times),
            iterations_median: median(&mut its),
            converged,
            solves: steps,
            same_as_warm: same,
        });
    }
    let last = pins[steps];
    Ok(Pinned {
        results,
        steps,
        first_m: [start_pin.x, start_pin.y],
        last_m: [last.x, last.y],
    })
}

fn fmt_time(s: f64) -> String {
    if s < 1e-6 {
        format!("{:.0} ns", s * 1e9)
    } else if s < 1e-3 {
        format!("{:.1} µs", s * 1e6)
    } else if s < 1.0 {
        format!("{:.2} ms", s * 1e3)
    } else {
        format!("{s:.2} s")
    }
}

fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".to_string())
}

/// Median observed order `log2(e(n) / e(2n))` over consecutive sizes with both errors above
/// [`ORDER_FLOOR`] (below it, rounding dominates: the floor is about 1e-13).
fn observed_order(points: &[&Point]) -> Option<(f64, f64, f64)> {
    let mut orders: Vec<f64> = points
        .windows(2)
        .filter(|w| w[0].relative_error > ORDER_FLOOR && w[1].relative_error > ORDER_FLOOR)
        .map(|w| (w[0].relative_error / w[1].relative_error).log2())
        .collect();
    if orders.is_empty() {
        return None;
    }
    let lo = orders.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = orders.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    Some((median(&mut orders), lo, hi))
}

fn section(
    points: &[Point],
    elastica: &[ElasticaRun],
    pinned: &Pinned,
    total_s: f64,
) -> BoxResult<String> {
    let mut s = String::new();
    let cpus = std::thread::available_parallelism().map_or(0, |n| n.get());
    writeln!(s, "{BEGIN}")?;
    writeln!(s, "## Equilibrium: run time against error (sim-core)\n")?;
    writeln!(
        s,
        "Regenerate with `scripts/bench-equilibrium` (`cargo run -p sim-core --release --example equilibrium_bench`; {:.0} s on this machine). Machine: {}, {cpus} logical CPUs, one thread. Time per solve is the median over repeated solves (at least 5, about {:.0} ms of repeats per configuration) after a warm-up, measured with `std::time::Instant`; it includes building the chain.\n",
        total_s,
        cpu_model(),
        BUDGET_S * 1e3
    )?;
    writeln!(
        s,
        "**Cantilever.** L = {LENGTH_M} m, EI = {EI_N_M2} N m^2, clamped along x, dead tip load perpendicular to the clamp, `alpha = F L^2 / EI`. Error: `|y_tip / y_elastica - 1|` of the tip deflection, the elastica from the Bisshopp-Drucker closed form (`perpendicular_load_closed_form`; the shooting solver agrees to 1e-10). Chains (`sim_core::statics::beam`) are solved by `solve_equilibrium`, every n-link chain to KKT tolerance 1e-13 / n (`RichardsonOptions::tolerance_times_links`: the tip sums n joint errors), plain chains from a straight start; `n` is the number of flexible joints (of the finest chain for Richardson, which solves n/2^(m-1), ..., n/2, n, each finer chain warm-started from the coarser answer). Equal links: docs/model.md 5 read literally, `n + 1` links of `L/(n+1)`, the base link rigid. Hencky: springs at the midpoints of `n` pieces of `L/n`, half-length end links.\n"
    )?;
    writeln!(
        s,
        "![relative error of the tip deflection against time per solve, one panel per alpha](../figures/equilibrium_time_vs_error.svg)\n"
    )?;

    // The goal.
    writeln!(
        s,
        "Goal: relative error {GOAL_ERROR:.0e} in under 1 ms for every alpha. Fastest configuration reaching {GOAL_ERROR:.0e}:\n"
    )?;
    writeln!(
        s,
        "| alpha | fastest chain method reaching 1e-6 | n | error | time per solve | goal met | plain Hencky chain reaching 1e-6 (n, time) | elastica shooting (time, error) |"
    )?;
    writeln!(s, "|---:|---|---:|---:|---:|:---:|---:|---:|")?;
    let mut all_met = true;
    for &alpha in &ALPHAS {
        let best = points
            .iter()
            .filter(|p| p.alpha == alpha && p.relative_error <= GOAL_ERROR)
            .min_by(|a, b| a.time_s.total_cmp(&b.time_s));
        let hencky = points
            .iter()
            .filter(|p| {
                p.alpha == alpha && p.method == Method::Hencky && p.relative_error <= GOAL_ERROR
            })
            .min_by_key(|p| p.links);
        let e = elastica.iter().find(|e| e.alpha == alpha);
        let hencky_cell = hencky.map_or("not reached by n = 4096".to_string(), |p| {
            format!("{}, {}", p.links, fmt_time(p.time_s))
        });
        let elastica_cell = e.map_or(String::new(), |e| {
            format!("{}, {:.0e}", fmt_time(e.time_s), e.relative_error)
        });
        match best {
            Some(p) => {
                let met = p.time_s < GOAL_TIME_S;
                all_met &= met;
                writeln!(
                    s,
                    "| {alpha} | {} | {} | {:.1e} | {} | {} | {hencky_cell} | {elastica_cell} |",
                    p.method.label(),
                    p.links,
                    p.relative_error,
                    fmt_time(p.time_s),
                    if met { "yes" } else { "no" }
                )?;
            }
            None => {
                all_met = false;
                writeln!(
                    s,
                    "| {alpha} | none reaches it | | | | no | {hencky_cell} | {elastica_cell} |"
                )?;
            }
        }
    }
    writeln!(
        s,
        "\n**Goal {}** for every alpha.\n",
        if all_met { "met" } else { "not met" }
    )?;

    // Observed orders.
    writeln!(
        s,
        "Observed order `log2(e(n) / e(2n))`, median (min..max) over consecutive n with both errors above {ORDER_FLOOR:.0e} (rounding is at about 1e-13):\n"
    )?;
    write!(s, "| method |")?;
    for alpha in ALPHAS {
        write!(s, " alpha {alpha} |")?;
    }
    writeln!(s)?;
    writeln!(s, "|---|{}", "---:|".repeat(ALPHAS.len()))?;
    for method in Method::ALL {
        write!(s, "| {} |", method.label())?;
        for alpha in ALPHAS {
            let series: Vec<&Point> = points
                .iter()
                .filter(|p| p.method == method && p.alpha == alpha)
                .collect();
            match observed_order(&series) {
                Some((m, lo, hi)) => write!(s, " {m:.2} ({lo:.2}..{hi:.2}) |")?,
                None => write!(s, " below {ORDER_FLOOR:.0e} |")?,
            }
        }
        writeln!(s)?;
    }

    // Everything.
    writeln!(
        s,
        "\nAll runs: relative error / time per solve (Newton iterations, summed over a run's solves):\n"
    )?;
    write!(s, "| method | n |")?;
    for alpha in ALPHAS {
        write!(s, " alpha {alpha} |")?;
    }
    writeln!(s)?;
    writeln!(s, "|---|---:|{}", "---:|".repeat(ALPHAS.len()))?;
    for method in Method::ALL {
        for links in method.sizes() {
            write!(s, "| {} | {links} |", method.short())?;
            for alpha in ALPHAS {
                match points
                    .iter()
                    .find(|p| p.method == method && p.alpha == alpha && p.links == links)
                {
                    Some(p) => write!(
                        s,
                        " {:.1e} / {} ({}) |",
                        p.relative_error,
                        fmt_time(p.time_s),
                        p.iterations
                    )?,
                    None => write!(s, " |")?,
                }
            }
            writeln!(s)?;
        }
    }

    // Pinned tip.
    let Pinned {
        results,
        steps,
        first_m: first,
        last_m: last,
    } = pinned;
    writeln!(
        s,
        "\n**Pinned tip, 9 links.** The thesis's robot: 9 links of 40 mm (a base link at 30 deg and 8 flexible joints, as docs/scene-format.md counts `links`), fast-exponential stiffness {SEED_K_MIN_N_M_PER_RAD}..{SEED_K_MAX_N_M_PER_RAD} N m/rad (`design/profile.rs`), joint limits +-90 deg, no load; the tip pinned at ({}, {}) m and moved in {steps} steps of 0.5 mm to ({:.3}, {}) m. The sweep starts from a C at the first pin and then from each previous answer; the cold starts solve every pin point afresh. Default solver options (KKT tolerance 1e-10). Time: median over the pin points of each point's median time per solve.\n",
        first[0], first[1], last[0], last[1]
    )?;
    writeln!(
        s,
        "| start | time per solve | Newton iterations (median) | converged | same equilibrium as the sweep |"
    )?;
    writeln!(s, "|---|---:|---:|---:|---:|")?;
    for r in results {
        writeln!(
            s,
            "| {} | {} | {:.0} | {}/{} | {}/{} |",
            r.label,
            fmt_time(r.time_s),
            r.iterations_median,
            r.converged,
            r.solves,
            r.same_as_warm,
            r.solves
        )?;
    }
    writeln!(s, "{END}")?;
    Ok(s)
}

fn plot(points: &[Point], path: &Path) -> BoxResult<()> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir)?;
    }
    let root = SVGBackend::new(path, (1500, 960)).into_drawing_area();
    root.fill(&WHITE)?;
    let (title, body) = root.split_vertically(40);
    title.draw(&Text::new(
        "Cantilever with a perpendicular tip load: relative error of the tip deflection against time per solve",
        (20, 12),
        ("sans-serif", 20).into_font(),
    ))?;
    let panels = body.split_evenly((2, 3));
    for (panel, alpha) in panels.iter().zip(ALPHAS) {
        let mut chart = ChartBuilder::on(panel)
            .caption(format!("alpha = F L^2 / EI = {alpha}"), ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(42)
            .y_label_area_size(62)
            .build_cartesian_2d((1e-6f64..1e-2).log_scale(), (PLOT_FLOOR..1.0).log_scale())?;
        chart
            .configure_mesh()
            .x_desc("time per solve (s)")
            .y_desc("relative error")
            .x_label_formatter(&|v| format!("{v:.0e}"))
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .label_style(("sans-serif", 13))
            .light_line_style(RGBColor(235, 235, 235))
            .draw()?;
        let goal = RGBColor(200, 0, 0);
        chart.draw_series(std::iter::once(PathElement::new(
            vec![(1e-6, GOAL_ERROR), (1e-2, GOAL_ERROR)],
            goal.stroke_width(1),
        )))?;
        chart.draw_series(std::iter::once(PathElement::new(
            vec![(GOAL_TIME_S, PLOT_FLOOR), (GOAL_TIME_S, 1.0)],
            goal.stroke_width(1),
        )))?;
        for method in Method::ALL {
            let series: Vec<(f64, f64)> = points
                .iter()
                .filter(|p| p.method == method && p.alpha == alpha)
                .map(|p| (p.time_s, p.relative_error.max(PLOT_FLOOR)))
                .collect();
            let color = method.color();
            chart.draw_series(LineSeries::new(series.clone(), color.stroke_width(2)))?;
            chart.draw_series(
                series
                    .iter()
                    .map(|&(x, y)| Circle::new((x, y), 3, color.filled())),
            )?;
        }
    }
    // The sixth panel: the legend and what the marks mean.
    let note = &panels[5];
    for (i, method) in Method::ALL.iter().enumerate() {
        let y = 40 + 26 * i as i32;
        let color = method.color();
        note.draw(&PathElement::new(
            vec![(20, y), (60, y)],
            color.stroke_width(3),
        ))?;
        note.draw(&Circle::new((40, y), 4, color.filled()))?;
        note.draw(&Text::new(
            method.label(),
            (72, y - 8),
            ("sans-serif", 15).into_font(),
        ))?;
    }
    let lines = [
        "Each point: one configuration, n = 8 ... 4096 flexible joints",
        "(the finest chain of a Richardson run); more links = further right.",
        "Red lines: the goal, error 1e-6 in under 1 ms.",
        "Equal links: docs/model.md 5 literally (rigid base link), O(1/n).",
        "Hencky: springs at piece midpoints, half-length end links, O(1/n^2).",
        "Richardson over m Hencky chains n/2^(m-1) .. n: O(1/n^(2m)).",
        "Errors below 1e-16 are drawn at 1e-16.",
    ];
    for (i, line) in lines.iter().enumerate() {
        note.draw(&Text::new(
            *line,
            (20, 40 + 26 * (Method::ALL.len() + 1 + i) as i32),
            ("sans-serif", 14).into_font(),
        ))?;
    }
    root.present()?;
    Ok(())
}

fn write_section(workspace: &Path, section: &str) -> BoxResult<()> {
    let path = workspace.join("docs/benchmarks/equilibrium.md");
    let old = std::fs::read_to_string(&path)
        .unwrap_or_else(|_| "# Benchmarks: Equilibrium (sim-core)\n".to_string());
    let new = match (old.find(BEGIN), old.find(END)) {
        (Some(b), Some(e)) if b < e => {
            format!(
                "{}{}{}",
                &old[..b],
                section.trim_end(),
                &old[e + END.len()..]
            )
        }
        _ => format!(
            "{}\n{}",
            old.trim_end_matches('\n').to_string() + "\n",
            section
        ),
    };
    std::fs::write(&path, new)?;
    Ok(())
}

fn main() -> BoxResult<()> {
    let started = Instant::now();
    let manifest = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let workspace = manifest.parent().ok_or("no workspace dir")?.to_path_buf();
    let (points, elastica) = measure_cantilever()?;
    let pinned = measure_pinned()?;
    for r in &pinned.results {
        eprintln!(
            "pinned, {}: {} per solve, {} its, {}/{} converged, {}/{} same as the sweep",
            r.label,
            fmt_time(r.time_s),
            r.iterations_median,
            r.converged,
            r.solves,
            r.same_as_warm,
            r.solves
        );
    }
    plot(&points, &workspace.join(FIGURE))?;
    let text = section(&points, &elastica, &pinned, started.elapsed().as_secs_f64())?;
    write_section(&workspace, &text)?;
    println!("{text}");
    Ok(())
}
