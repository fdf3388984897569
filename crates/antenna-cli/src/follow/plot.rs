//! `antenna follow --plot FILE.svg|FILE.png`: the run from above (the walls, the footprint
//! along the path, the antenna every k steps, the estimator's wall points) above the error
//! against time (the true distance's error against the setpoint, and the estimate's against
//! the true `d` at its preview).

use std::ops::Range;
use std::path::Path;

use nalgebra::Vector2;
use plotters::coord::Shift;
use plotters::prelude::*;
use sim_core::Wall;

use crate::sweep::plot::{Drawing, PlotError, draw_walls, tick, write_drawing};
use antenna_scene::follow_lines::FollowStepLine;

/// Figure size, pixels (PNG) or user units (SVG).
pub const FIGURE_SIZE: (u32, u32) = (1200, 1000);
/// Snapshots of the body and antenna drawn when no interval is given.
pub const DEFAULT_SNAPSHOTS: usize = 30;

const BODY: RGBColor = RGBColor(60, 60, 60);
const ANTENNA: RGBColor = RGBColor(0, 90, 200);
const ESTIMATED: RGBColor = RGBColor(230, 120, 0);
const PATH: RGBColor = RGBColor(0, 150, 90);
const COLLISION: RGBColor = RGBColor(220, 0, 60);

#[derive(Debug, Clone)]
struct Snapshot {
    footprint_m: [Vector2<f64>; 5],
    antenna_m: Vec<Vector2<f64>>,
    collided: bool,
}

/// Collects what the figure needs while a run goes; [`Self::write`] draws it.
#[derive(Debug, Clone)]
pub struct FollowPlot {
    every: usize,
    footprint_m: [f64; 2],
    link_lengths_m: Vec<f64>,
    snapshots: Vec<Snapshot>,
    path_m: Vec<Vector2<f64>>,
    estimated_m: Vec<Vector2<f64>>,
    /// `(t, true error, estimate error)`.
    errors: Vec<(f64, Option<f64>, Option<f64>)>,
    steps: usize,
}

impl FollowPlot {
    /// A plot of a run of `steps` steps, a snapshot every `every` steps (`None`: about
    /// [`DEFAULT_SNAPSHOTS`]).
    pub fn new(
        steps: usize,
        footprint_m: [f64; 2],
        link_lengths_m: &[f64],
        every: Option<usize>,
    ) -> FollowPlot {
        FollowPlot {
            every: every
                .unwrap_or_else(|| steps.div_ceil(DEFAULT_SNAPSHOTS))
                .max(1),
            footprint_m,
            link_lengths_m: link_lengths_m.to_vec(),
            snapshots: Vec::new(),
            path_m: Vec::new(),
            estimated_m: Vec::new(),
            errors: Vec::new(),
            steps: 0,
        }
    }

    /// Adds a step.
    pub fn push(&mut self, line: &FollowStepLine) {
        let por = Vector2::new(line.pose_m[0], line.pose_m[1]);
        self.path_m.push(por);
        let estimate_error = match (line.estimate_m, line.true_distance_at_preview_m) {
            (Some(e), Some(d)) => Some(e - d),
            _ => None,
        };
        self.errors.push((line.t_s, line.error_m, estimate_error));
        if self.steps.is_multiple_of(self.every) {
            let (sin, cos) = line.heading_rad.sin_cos();
            let (ahead, left) = (Vector2::new(cos, sin), Vector2::new(-sin, cos));
            let (hl, hw) = (0.5 * self.footprint_m[0], 0.5 * self.footprint_m[1]);
            let corner = |a: f64, b: f64| por + ahead * a + left * b;
            let footprint_m = [
                corner(hl, hw),
                corner(hl, -hw),
                corner(-hl, -hw),
                corner(-hl, hw),
                corner(hl, hw),
            ];
            let mut antenna_m = Vec::new();
            if let Some(base) = line.base_m {
                let mut p = Vector2::new(base[0], base[1]);
                antenna_m.push(p);
                let mut phi = 0.0;
                for (theta, length) in line.theta_rad.iter().zip(&self.link_lengths_m) {
                    phi += theta;
                    p += Vector2::new(phi.cos(), phi.sin()) * *length;
                    antenna_m.push(p);
                }
            }
            self.snapshots.push(Snapshot {
                footprint_m,
                antenna_m,
                collided: line.collided,
            });
            self.estimated_m.extend(
                line.estimated_points_m
                    .iter()
                    .map(|p| Vector2::new(p[0], p[1])),
            );
        }
        self.steps += 1;
    }

    /// Draws the figure to `path` (`.svg` or `.png`).
    ///
    /// # Errors
    /// [`PlotError`] for another extension, a drawing failure or a file that cannot be
    /// written.
    pub fn write(&self, path: &Path, walls: &[Wall], title: &str) -> Result<(), PlotError> {
        struct Figure<'a>(&'a FollowPlot, &'a [Wall], &'a str);
        impl Drawing for Figure<'_> {
            fn draw<DB: DrawingBackend>(
                &self,
                root: &DrawingArea<DB, Shift>,
            ) -> Result<(), String> {
                self.0.draw(root, self.1, self.2)
            }
        }
        write_drawing(path, FIGURE_SIZE, &Figure(self, walls, title))
    }

    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        walls: &[Wall],
        title: &str,
    ) -> Result<(), String> {
        let text = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
        root.fill(&WHITE).map_err(text)?;
        let (top, bottom) = root.split_vertically(FIGURE_SIZE.1 as i32 * 62 / 100);
        self.draw_top(&top, walls, title)?;
        self.draw_errors(&bottom)?;
        Ok(())
    }

    fn view(&self) -> (Range<f64>, Range<f64>) {
        let mut lo = Vector2::new(f64::INFINITY, f64::INFINITY);
        let mut hi = Vector2::new(f64::NEG_INFINITY, f64::NEG_INFINITY);
        let points = self.path_m.iter().chain(
            self.snapshots
                .iter()
                .flat_map(|s| s.antenna_m.iter().chain(s.footprint_m.iter())),
        );
        for p in points.filter(|p| p.x.is_finite() && p.y.is_finite()) {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        if !(lo.x.is_finite() && hi.x.is_finite()) {
            lo = Vector2::new(-0.1, -0.1);
            hi = Vector2::new(0.1, 0.1);
        }
        let pad = 0.08 * (hi - lo).max().max(0.05);
        (lo.x - pad..hi.x + pad, lo.y - pad..hi.y + pad)
    }

    fn draw_top<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        walls: &[Wall],
        title: &str,
    ) -> Result<(), String> {
        let text = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
        let (x, y) = self.view();
        // Equal scales: widen the shorter range to the area's aspect.
        let (w, h) = area.dim_in_pixel();
        let w_px = (f64::from(w) - 80.0).max(1.0);
        let h_px = (f64::from(h) - 85.0).max(1.0);
        let per_px = ((x.end - x.start) / w_px).max((y.end - y.start) / h_px);
        let (cx, cy) = (0.5 * (x.start + x.end), 0.5 * (y.start + y.end));
        let x = cx - 0.5 * per_px * w_px..cx + 0.5 * per_px * w_px;
        let y = cy - 0.5 * per_px * h_px..cy + 0.5 * per_px * h_px;
        let mut chart = ChartBuilder::on(area)
            .caption(title, ("sans-serif", 20))
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(60)
            .build_cartesian_2d(x.clone(), y.clone())
            .map_err(text)?;
        chart
            .configure_mesh()
            .x_desc("x (m)")
            .y_desc("y (m)")
            .x_label_formatter(&|v| tick(*v, 2))
            .y_label_formatter(&|v| tick(*v, 2))
            .light_line_style(WHITE)
            .draw()
            .map_err(text)?;
        draw_walls(&mut chart, walls, &x, &y).map_err(text)?;
        chart
            .draw_series(LineSeries::new(
                self.path_m.iter().map(|p| (p.x, p.y)),
                PATH.stroke_width(2),
            ))
            .map_err(text)?
            .label("path of the point of rotation")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 16, y)], PATH.stroke_width(2)));
        for s in &self.snapshots {
            let colour = if s.collided { COLLISION } else { BODY };
            chart
                .draw_series(LineSeries::new(
                    s.footprint_m.iter().map(|p| (p.x, p.y)),
                    colour.mix(0.6),
                ))
                .map_err(text)?;
            chart
                .draw_series(LineSeries::new(
                    s.antenna_m.iter().map(|p| (p.x, p.y)),
                    ANTENNA.mix(0.7),
                ))
                .map_err(text)?;
        }
        chart
            .draw_series(std::iter::once(PathElement::new(
                Vec::<(f64, f64)>::new(),
                BODY,
            )))
            .map_err(text)?
            .label(format!(
                "footprint and antenna every {} steps (red: in a wall)",
                self.every
            ))
            .legend(|(x, y)| PathElement::new([(x, y), (x + 16, y)], ANTENNA));
        chart
            .draw_series(
                self.estimated_m
                    .iter()
                    .map(|p| Circle::new((p.x, p.y), 2, ESTIMATED.filled())),
            )
            .map_err(text)?
            .label("estimated wall points")
            .legend(|(x, y)| Circle::new((x + 8, y), 3, ESTIMATED.filled()));
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.3))
            .label_font(("sans-serif", 14))
            .position(SeriesLabelPosition::LowerRight)
            .draw()
            .map_err(text)?;
        Ok(())
    }

    fn draw_errors<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), String> {
        let text = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
        let t_end = self.errors.last().map_or(1.0, |e| e.0.max(1e-3));
        // Ticks with enough decimals to tell a short run's apart.
        let t_decimals = if t_end < 2.0 { 2 } else { 1 };
        let values = self
            .errors
            .iter()
            .flat_map(|e| [e.1, e.2])
            .flatten()
            .filter(|v| v.is_finite())
            .map(|v| v * 1e3);
        let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
        let (lo, hi) = if lo.is_finite() {
            let pad = ((hi - lo) * 0.1).max(1.0);
            (lo - pad, hi + pad)
        } else {
            (-10.0, 10.0)
        };
        let mut chart = ChartBuilder::on(area)
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..t_end, lo..hi)
            .map_err(text)?;
        chart
            .configure_mesh()
            .x_desc("t (s)")
            .y_desc("error (mm)")
            .x_label_formatter(&|v| tick(*v, t_decimals))
            .y_label_formatter(&|v| tick(*v, 0))
            .light_line_style(WHITE)
            .draw()
            .map_err(text)?;
        for (pick, colour, label) in [
            (
                1usize,
                PATH,
                "distance to the wall minus the setpoint (truth)",
            ),
            (2, ESTIMATED, "estimate minus the true d at its preview"),
        ] {
            let mut runs: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
            for e in &self.errors {
                match if pick == 1 { e.1 } else { e.2 } {
                    Some(v) if v.is_finite() => {
                        if let Some(run) = runs.last_mut() {
                            run.push((e.0, v * 1e3));
                        }
                    }
                    _ => {
                        if runs.last().is_some_and(|r| !r.is_empty()) {
                            runs.push(Vec::new());
                        }
                    }
                }
            }
            let mut first = true;
            for run in runs.into_iter().filter(|r| !r.is_empty()) {
                let series = chart
                    .draw_series(LineSeries::new(run, colour.stroke_width(2)))
                    .map_err(text)?;
                if first {
                    series
                        .label(label)
                        .legend(move |(x, y)| PathElement::new([(x, y), (x + 16, y)], colour));
                    first = false;
                }
            }
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.3))
            .label_font(("sans-serif", 14))
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(text)?;
        Ok(())
    }
}
