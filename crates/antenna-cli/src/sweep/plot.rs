//! `antenna sweep --plot FILE.svg|FILE.png`: snapshots of the chain over the walls (every
//! k-th step, older ones fainter, the last one bold with its contacts) above the metrics over
//! time: the preview distance, the points of bend and of contact, and the distal segment's
//! angle to the wall (beyond 90 degrees it has flipped; snaps are marked).
//!
//! Drawn with plotters: SVG natively, PNG through its bitmap backend and the png encoder;
//! text with ab_glyph and the font egui ships, so no system font library is needed.

use std::ops::Range;
use std::path::{Path, PathBuf};

use nalgebra::Vector2;
use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use sim_core::{Surface, Wall, WallShape};

use super::SweepState;
use antenna_figure::{FigureError, register_font, write_png};

/// Figure size, pixels (PNG) or user units (SVG).
pub const FIGURE_SIZE: (u32, u32) = (1200, 1100);
/// Chain snapshots drawn when no step interval is given.
pub const DEFAULT_SNAPSHOTS: usize = 24;

const CHAIN: RGBColor = RGBColor(0, 90, 200);
const CONTACT: RGBColor = RGBColor(220, 0, 60);
const SMOOTH_WALL: RGBColor = RGBColor(90, 90, 90);
const ROUGH_WALL: RGBColor = RGBColor(150, 90, 20);
const TRACK: RGBColor = RGBColor(120, 120, 120);
const BEND: RGBColor = RGBColor(0, 90, 200);
const TOUCH: RGBColor = RGBColor(230, 120, 0);
const SNAP: RGBColor = RGBColor(220, 0, 60);

/// Why a figure could not be written.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// The file name ends neither in `.svg` nor in `.png`.
    #[error("{}: the plot's file name must end in .svg or .png", path.display())]
    Extension {
        /// The file.
        path: PathBuf,
    },
    /// plotters or the PNG encoder failed.
    #[error("{}: drawing the plot: {message}", path.display())]
    Draw {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// The file could not be written.
    #[error("{}: cannot write the plot: {source}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
}

impl From<FigureError> for PlotError {
    fn from(e: FigureError) -> Self {
        match e {
            FigureError::Write { path, source } => PlotError::Write { path, source },
            FigureError::Encode { path, message } => PlotError::Draw { path, message },
            FigureError::Font => PlotError::Draw {
                path: PathBuf::new(),
                message: e.to_string(),
            },
        }
    }
}

/// A figure that draws itself on any plotters backend.
pub trait Drawing {
    /// Draws the figure on `root`.
    ///
    /// # Errors
    /// plotters' message.
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String>;
}

/// Draws `figure` (`size`: pixels, or SVG user units) to `path`, an SVG or a PNG by the
/// file's extension.
///
/// # Errors
/// [`PlotError`] for another extension, a drawing failure or a file that cannot be written.
pub fn write_drawing(
    path: &Path,
    size: (u32, u32),
    figure: &impl Drawing,
) -> Result<(), PlotError> {
    let draw_error = |message: String| PlotError::Draw {
        path: path.to_path_buf(),
        message,
    };
    register_font().map_err(|e| draw_error(e.to_string()))?;
    let extension = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    match extension.as_deref() {
        Some("svg") => {
            let mut svg = String::new();
            {
                let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
                figure.draw(&root).map_err(draw_error)?;
                root.present().map_err(|e| draw_error(e.to_string()))?;
            }
            std::fs::write(path, svg).map_err(|source| PlotError::Write {
                path: path.to_path_buf(),
                source,
            })
        }
        Some("png") => {
            let (w, h) = size;
            let mut rgb = vec![0u8; (w * h * 3) as usize];
            {
                let root = BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area();
                figure.draw(&root).map_err(draw_error)?;
                root.present().map_err(|e| draw_error(e.to_string()))?;
            }
            write_png(path, w, h, &rgb).map_err(PlotError::from)
        }
        _ => Err(PlotError::Extension {
            path: path.to_path_buf(),
        }),
    }
}

/// One chain snapshot.
#[derive(Debug, Clone)]
struct Snapshot {
    /// The base pivot then the joints, ground frame, metres.
    points_m: Vec<Vector2<f64>>,
    /// The contact points.
    contacts_m: Vec<Vector2<f64>>,
}

/// The metrics of one step.
#[derive(Debug, Clone, Copy)]
struct Sample {
    t_s: f64,
    base_m: Vector2<f64>,
    preview_mm: Option<f64>,
    bend_joint: Option<usize>,
    contact_joint: Option<usize>,
    distal_angle_deg: Option<f64>,
    snapped: bool,
}

/// Collects what the figure needs while a sweep runs; [`Self::write`] draws it.
#[derive(Debug, Clone)]
pub struct SweepPlot {
    every: usize,
    joints: usize,
    snapshots: Vec<Snapshot>,
    last: Option<Snapshot>,
    samples: Vec<Sample>,
}

impl SweepPlot {
    /// A plot of a sweep of `steps` steps with `n` flexible joints, a chain snapshot every
    /// `every` steps (`None`: about [`DEFAULT_SNAPSHOTS`] snapshots).
    pub fn new(steps: usize, n: usize, every: Option<usize>) -> SweepPlot {
        let every = every
            .unwrap_or_else(|| steps.div_ceil(DEFAULT_SNAPSHOTS))
            .max(1);
        SweepPlot {
            every,
            joints: n,
            snapshots: Vec::new(),
            last: None,
            samples: Vec::new(),
        }
    }

    /// The step interval between snapshots.
    pub fn every(&self) -> usize {
        self.every
    }

    /// Adds a state.
    pub fn push(&mut self, state: &SweepState) {
        let step = &state.step;
        let snapshot = Snapshot {
            points_m: state.metrics.points_m.clone(),
            contacts_m: step.contacts.iter().map(|c| c.point_m).collect(),
        };
        if step.step.is_multiple_of(self.every) {
            self.snapshots.push(snapshot.clone());
        }
        self.last = Some(snapshot);
        self.samples.push(Sample {
            t_s: step.t_s,
            base_m: step.base_m,
            preview_mm: step.preview_m.map(|p| p * 1e3),
            bend_joint: step.bend_joint,
            contact_joint: step.contact_joint,
            distal_angle_deg: step.flip.map(|f| f.angle_to_wall_rad.to_degrees()),
            snapped: step.report.snapped,
        });
    }

    /// Draws the figure to `path` (`.svg` or `.png`) with `walls` and a `title`.
    ///
    /// # Errors
    /// [`PlotError`] for another extension, a drawing failure or a file that cannot be
    /// written.
    pub fn write(&self, path: &Path, walls: &[Wall], title: &str) -> Result<(), PlotError> {
        struct Figure<'a>(&'a SweepPlot, &'a [Wall], &'a str);
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
        let (top, bottom) = root.split_vertically(FIGURE_SIZE.1 as i32 * 55 / 100);
        self.draw_scene(&top, walls, title)?;
        let panels = bottom.split_evenly((3, 1));
        let t_end = self.samples.last().map_or(0.0, |s| s.t_s);
        let t_range = 0.0..if t_end > 0.0 { t_end } else { 1.0 };
        self.draw_preview(&panels[0], t_range.clone())?;
        self.draw_joints(&panels[1], t_range.clone())?;
        self.draw_flip(&panels[2], t_range)?;
        Ok(())
    }

    /// The chain snapshots over the walls, at equal scales in x and y.
    fn draw_scene<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        walls: &[Wall],
        title: &str,
    ) -> Result<(), String> {
        let text = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
        let (x, y) = self.view(area);
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
                self.samples.iter().map(|s| (s.base_m.x, s.base_m.y)),
                TRACK.stroke_width(1),
            ))
            .map_err(text)?
            .label("base track")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 16, y)], TRACK));
        let count = self.snapshots.len().max(2) as f64;
        for (i, snapshot) in self.snapshots.iter().enumerate() {
            let alpha = 0.12 + 0.45 * i as f64 / (count - 1.0);
            chart
                .draw_series(LineSeries::new(
                    snapshot.points_m.iter().map(|p| (p.x, p.y)),
                    CHAIN.mix(alpha),
                ))
                .map_err(text)?;
        }
        if let Some(last) = &self.last {
            chart
                .draw_series(LineSeries::new(
                    last.points_m.iter().map(|p| (p.x, p.y)),
                    CHAIN.stroke_width(2),
                ))
                .map_err(text)?
                .label(format!("chain (every {} steps; the last bold)", self.every))
                .legend(|(x, y)| PathElement::new([(x, y), (x + 16, y)], CHAIN.stroke_width(2)));
            chart
                .draw_series(
                    last.points_m
                        .iter()
                        .map(|p| Circle::new((p.x, p.y), 3, CHAIN.filled())),
                )
                .map_err(text)?;
            chart
                .draw_series(
                    last.contacts_m
                        .iter()
                        .map(|p| Circle::new((p.x, p.y), 4, CONTACT.filled())),
                )
                .map_err(text)?
                .label("contacts (last step)")
                .legend(|(x, y)| Circle::new((x + 8, y), 4, CONTACT.filled()));
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

    /// The x and y ranges of the scene panel: every snapshot and the base track, padded, at
    /// equal scales for the panel's plotting area.
    fn view<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> (Range<f64>, Range<f64>) {
        let mut lo = Vector2::new(f64::INFINITY, f64::INFINITY);
        let mut hi = Vector2::new(f64::NEG_INFINITY, f64::NEG_INFINITY);
        let points = self
            .snapshots
            .iter()
            .chain(self.last.iter())
            .flat_map(|s| s.points_m.iter().copied())
            .chain(self.samples.iter().map(|s| s.base_m));
        for p in points.filter(|p| p.x.is_finite() && p.y.is_finite()) {
            lo = lo.inf(&p);
            hi = hi.sup(&p);
        }
        if !(lo.x.is_finite() && hi.x.is_finite()) {
            lo = Vector2::new(-0.1, -0.1);
            hi = Vector2::new(0.1, 0.1);
        }
        let span = (hi - lo).max().max(0.05);
        let pad = 0.08 * span;
        let (mut x0, mut x1) = (lo.x - pad, hi.x + pad);
        let (mut y0, mut y1) = (lo.y - pad, hi.y + pad);
        let (w, h) = area.dim_in_pixel();
        // The plotting area: less the label areas, the margins and the caption.
        let w_px = (f64::from(w) - 60.0 - 20.0).max(1.0);
        let h_px = (f64::from(h) - 35.0 - 20.0 - 30.0).max(1.0);
        let per_px = ((x1 - x0) / w_px).max((y1 - y0) / h_px);
        let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
        x0 = cx - 0.5 * per_px * w_px;
        x1 = cx + 0.5 * per_px * w_px;
        y0 = cy - 0.5 * per_px * h_px;
        y1 = cy + 0.5 * per_px * h_px;
        (x0..x1, y0..y1)
    }

    fn draw_preview<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        t: Range<f64>,
    ) -> Result<(), String> {
        let text = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
        let values: Vec<f64> = self.samples.iter().filter_map(|s| s.preview_mm).collect();
        let lo = values.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let (lo, hi) = if lo.is_finite() {
            let pad = ((hi - lo) * 0.1).max(1.0);
            (lo - pad, hi + pad)
        } else {
            (-1.0, 1.0)
        };
        let mut chart = metric_chart(area, t, lo..hi).map_err(text)?;
        chart
            .configure_mesh()
            .x_desc("t (s)")
            .y_desc("preview (mm)")
            .x_label_formatter(&|v| tick(*v, 1))
            .y_label_formatter(&|v| tick(*v, 0))
            .light_line_style(WHITE)
            .draw()
            .map_err(text)?;
        for run in runs(&self.samples, |s| s.preview_mm) {
            chart
                .draw_series(LineSeries::new(run, CHAIN.stroke_width(2)))
                .map_err(text)?;
        }
        Ok(())
    }

    fn draw_joints<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        t: Range<f64>,
    ) -> Result<(), String> {
        let text = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
        let top = self.joints as f64 + 1.5;
        let mut chart = metric_chart(area, t, -0.5..top).map_err(text)?;
        chart
            .configure_mesh()
            .x_desc("t (s)")
            .y_desc("joint")
            .x_label_formatter(&|v| tick(*v, 1))
            .y_label_formatter(&|v| tick(*v, 0))
            .light_line_style(WHITE)
            .draw()
            .map_err(text)?;
        let series = [
            (
                "point of bend",
                BEND,
                Box::new(|s: &Sample| s.bend_joint.map(|j| j as f64)) as Box<dyn Fn(&Sample) -> _>,
            ),
            (
                "point of contact",
                TOUCH,
                Box::new(|s: &Sample| s.contact_joint.map(|j| j as f64)),
            ),
        ];
        for (label, colour, value) in series {
            let mut first = true;
            for run in runs(&self.samples, |s| value(s)) {
                let drawn = chart
                    .draw_series(LineSeries::new(run, colour.stroke_width(2)))
                    .map_err(text)?;
                if first {
                    drawn
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

    fn draw_flip<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        t: Range<f64>,
    ) -> Result<(), String> {
        let text = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
        let mut chart = metric_chart(area, t.clone(), 0.0..180.0).map_err(text)?;
        chart
            .configure_mesh()
            .x_desc("t (s)")
            .y_desc("distal angle to wall (deg)")
            .x_label_formatter(&|v| tick(*v, 1))
            .y_label_formatter(&|v| tick(*v, 0))
            .light_line_style(WHITE)
            .draw()
            .map_err(text)?;
        chart
            .draw_series(LineSeries::new(
                [(t.start, 90.0), (t.end, 90.0)],
                BLACK.mix(0.6).stroke_width(2),
            ))
            .map_err(text)?
            .label("flip threshold (90 deg)")
            .legend(|(x, y)| {
                PathElement::new([(x, y), (x + 16, y)], BLACK.mix(0.6).stroke_width(2))
            });
        for run in runs(&self.samples, |s| s.distal_angle_deg) {
            chart
                .draw_series(LineSeries::new(run, CHAIN.stroke_width(2)))
                .map_err(text)?;
        }
        let snaps: Vec<f64> = self
            .samples
            .iter()
            .filter(|s| s.snapped)
            .map(|s| s.t_s)
            .collect();
        if !snaps.is_empty() {
            chart
                .draw_series(
                    snaps
                        .iter()
                        .map(|&t| PathElement::new([(t, 0.0), (t, 180.0)], SNAP.mix(0.35))),
                )
                .map_err(text)?
                .label("snap")
                .legend(|(x, y)| PathElement::new([(x, y), (x + 16, y)], SNAP));
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

type MetricChart<'a, DB> = ChartContext<
    'a,
    DB,
    Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
>;

/// A tick label with `decimals` decimals, never `-0`.
pub(crate) fn tick(value: f64, decimals: usize) -> String {
    let text = format!("{value:.decimals$}");
    if text.starts_with('-') && text[1..].chars().all(|c| c == '0' || c == '.') {
        text[1..].to_string()
    } else {
        text
    }
}

/// A metric-over-time panel.
fn metric_chart<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    t: Range<f64>,
    y: Range<f64>,
) -> Result<MetricChart<'a, DB>, DrawingAreaErrorKind<DB::ErrorType>> {
    ChartBuilder::on(area)
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(60)
        .build_cartesian_2d(t, y)
}

/// The runs of consecutive samples where `value` is defined, as `(t, value)` points.
fn runs(samples: &[Sample], value: impl Fn(&Sample) -> Option<f64>) -> Vec<Vec<(f64, f64)>> {
    let mut out: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut current = Vec::new();
    for s in samples {
        match value(s) {
            Some(v) if v.is_finite() => current.push((s.t_s, v)),
            _ => {
                if !current.is_empty() {
                    out.push(std::mem::take(&mut current));
                }
            }
        }
    }
    if !current.is_empty() {
        out.push(current);
    }
    out
}

/// Draws `walls` on a top view's `chart` of ranges `x` and `y`: each wall's curve within the
/// view (rough stretches brown, smooth ones grey) with hatches into its solid side.
///
/// # Errors
/// plotters' error.
pub(crate) fn draw_walls<DB: DrawingBackend>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    walls: &[Wall],
    x: &Range<f64>,
    y: &Range<f64>,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let diagonal = ((x.end - x.start).powi(2) + (y.end - y.start).powi(2)).sqrt();
    for wall in walls {
        let points = wall_points(wall, x, y, diagonal);
        for run in inside_runs(&points, x, y) {
            for (rough, piece) in surface_runs(wall, run) {
                let colour = if rough { ROUGH_WALL } else { SMOOTH_WALL };
                chart.draw_series(LineSeries::new(
                    piece.iter().map(|p| (p.x, p.y)),
                    colour.stroke_width(2),
                ))?;
            }
            // Hatches into the solid side.
            let hatch_m = 0.012 * diagonal;
            let stride = (run.len() / 60).max(1);
            for p in run.iter().step_by(stride) {
                let normal = wall.signed_distance(p).normal;
                let q = p - normal * hatch_m;
                chart.draw_series(LineSeries::new(
                    [(p.x, p.y), (q.x, q.y)],
                    SMOOTH_WALL.mix(0.5),
                ))?;
            }
        }
    }
    Ok(())
}

/// Points along a wall's curve covering a view of size `diagonal` around its centre.
fn wall_points(wall: &Wall, x: &Range<f64>, y: &Range<f64>, diagonal: f64) -> Vec<Vector2<f64>> {
    let centre = Vector2::new(0.5 * (x.start + x.end), 0.5 * (y.start + y.end));
    let samples = 600.0;
    let along = |p0: Vector2<f64>, t: Vector2<f64>| {
        let s0 = (centre - p0).dot(&t);
        (0..=600)
            .map(|i| p0 + t * (s0 - diagonal + 2.0 * diagonal * f64::from(i) / samples))
            .collect::<Vec<_>>()
    };
    match &wall.shape {
        WallShape::Line(line) => {
            let (sin, cos) = line.angle_rad().sin_cos();
            along(line.point_m(), Vector2::new(cos, sin))
        }
        WallShape::Polyline(polyline) => {
            let v = polyline.vertices_m();
            if v.len() < 2 {
                return Vec::new();
            }
            let reach = diagonal + v.iter().map(|p| (p - centre).norm()).fold(0.0, f64::max);
            let first = (v[1] - v[0]).normalize();
            let last = (v[v.len() - 1] - v[v.len() - 2]).normalize();
            let mut corners = vec![v[0] - first * reach];
            corners.extend_from_slice(v);
            corners.push(v[v.len() - 1] + last * reach);
            let piece = diagonal / samples;
            let mut out = Vec::new();
            for pair in corners.windows(2) {
                let pieces = ((pair[1] - pair[0]).norm() / piece).ceil().clamp(1.0, 1e5) as usize;
                out.extend(
                    (0..pieces).map(|i| pair[0] + (pair[1] - pair[0]) * (i as f64 / pieces as f64)),
                );
            }
            out.push(corners[corners.len() - 1]);
            out
        }
        WallShape::Sinusoid(sinusoid) => {
            let (sin, cos) = sinusoid.direction_rad().sin_cos();
            let u = Vector2::new(cos, sin);
            let t0 = (centre - sinusoid.baseline_point_m()).dot(&u);
            let step = (sinusoid.wavelength_m() / 32.0)
                .min(diagonal / samples)
                .max(diagonal / 2e4);
            let count = (2.0 * diagonal / step).ceil() as usize;
            (0..=count)
                .map(|i| sinusoid.point_at_m(t0 - diagonal + step * i as f64))
                .collect()
        }
    }
}

/// The runs of consecutive points inside the view.
fn inside_runs<'p>(
    points: &'p [Vector2<f64>],
    x: &Range<f64>,
    y: &Range<f64>,
) -> Vec<&'p [Vector2<f64>]> {
    let inside = |p: &Vector2<f64>| x.contains(&p.x) && y.contains(&p.y);
    let mut out = Vec::new();
    let mut start = None;
    for (i, p) in points.iter().enumerate() {
        match (inside(p), start) {
            (true, None) => start = Some(i),
            (false, Some(s)) => {
                out.push(&points[s..i]);
                start = None;
            }
            _ => {}
        }
    }
    if let Some(s) = start {
        out.push(&points[s..]);
    }
    out.retain(|r| r.len() >= 2);
    out
}

/// Splits a run of wall points where the surface changes between smooth and rough; `true`
/// marks a rough piece.
fn surface_runs(wall: &Wall, run: &[Vector2<f64>]) -> Vec<(bool, Vec<Vector2<f64>>)> {
    let mut out: Vec<(bool, Vec<Vector2<f64>>)> = Vec::new();
    for p in run {
        let rough = matches!(
            wall.surface_at(&wall.signed_distance(p)),
            Surface::Rough { .. }
        );
        match out.last_mut() {
            Some((kind, points)) if *kind == rough => points.push(*p),
            Some((_, points)) => {
                let joint = *points.last().unwrap_or(p);
                out.push((rough, vec![joint, *p]));
            }
            None => out.push((rough, vec![*p])),
        }
    }
    out
}
