//! Exports: the samples of the visible time range to CSV, and the view (the chain at the
//! cursor, with antennad's estimated wall when the chain panel shows it, beside the joint
//! angles of the visible range) to SVG or PNG with plotters.
//!
//! # CSV
//! One header line, then one row per sample with `t0_s <= t_s <= t1_s`:
//! `t_s,seq,stage_position_m,servo_angle_deg`, then per segment `k` (1-based, base to tip)
//! `s<k>_angle_rad,s<k>_touch,s<k>_health` (`touch` the four bits as a number 0..=15,
//! `health` one of `ok`, `stale`, `nack`, `pec`, `bus`). A missing value is an empty field.

use std::io::Write;
use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::error::MonitorError;
use crate::frame::ChainFrame;
use crate::history::History;
use antenna_figure::{register_font, write_png};

/// Writes the samples of `t0_s..=t1_s` as CSV (see the module documentation); returns the
/// number of rows.
pub fn write_csv(
    history: &History,
    t0_s: f64,
    t1_s: f64,
    out: &mut impl Write,
) -> std::io::Result<usize> {
    let n = history.segment_count();
    let mut csv = csv::WriterBuilder::new()
        .terminator(csv::Terminator::Any(b'\n'))
        .from_writer(out);
    let mut header: Vec<String> = ["t_s", "seq", "stage_position_m", "servo_angle_deg"]
        .map(str::to_owned)
        .to_vec();
    for k in 1..=n {
        header.extend([
            format!("s{k}_angle_rad"),
            format!("s{k}_touch"),
            format!("s{k}_health"),
        ]);
    }
    csv.write_record(&header)?;
    let range = history.index_range(t0_s, t1_s);
    let rows = range.len();
    let opt = |v: Option<f64>| v.map_or_else(String::new, |v| v.to_string());
    let mut record: Vec<String> = Vec::with_capacity(4 + 3 * n);
    for i in range {
        let Some(sample) = history.sample(i) else {
            continue;
        };
        record.clear();
        record.extend([
            sample.t_s.to_string(),
            sample.seq.map_or_else(String::new, |s| s.to_string()),
            opt(sample.stage_position_m),
            opt(sample.servo_angle_rad.map(f64::to_degrees)),
        ]);
        for s in &sample.segments {
            record.extend([
                opt(s.angle_rad),
                s.touch_bits.map_or_else(String::new, |t| t.to_string()),
                s.health.as_str().to_owned(),
            ]);
        }
        csv.write_record(&record)?;
    }
    csv.flush()?;
    Ok(rows)
}

/// Writes the samples of `t0_s..=t1_s` to a CSV file; returns the number of rows. An empty
/// range is refused (nothing is written).
pub fn export_csv(
    history: &History,
    t0_s: f64,
    t1_s: f64,
    path: &Path,
) -> Result<usize, MonitorError> {
    if history.index_range(t0_s, t1_s).is_empty() {
        return Err(MonitorError::NothingToExport { t0_s, t1_s });
    }
    let write_error = |source| MonitorError::Write {
        path: path.to_path_buf(),
        source,
    };
    let file = std::fs::File::create(path).map_err(write_error)?;
    let mut out = std::io::BufWriter::new(file);
    let rows = write_csv(history, t0_s, t1_s, &mut out).map_err(write_error)?;
    out.flush().map_err(write_error)?;
    Ok(rows)
}

/// What an exported figure shows.
#[derive(Debug, Clone, Copy)]
pub struct FigureInput<'a> {
    /// The samples.
    pub history: &'a History,
    /// The visible range, seconds.
    pub t0_s: f64,
    /// See `t0_s`.
    pub t1_s: f64,
    /// The joints whose angles are plotted (0-based segment indices).
    pub joints: &'a [usize],
    /// The measured chain at the cursor.
    pub measured: Option<&'a ChainFrame>,
    /// The predicted chain for the same pose.
    pub predicted: Option<&'a ChainFrame>,
}

/// Figure size, pixels (PNG) or user units (SVG).
const FIGURE_SIZE: (u32, u32) = (1400, 600);
/// Columns the joint angles are reduced to.
const FIGURE_COLUMNS: usize = 1000;

/// Writes the view as SVG (`.svg`) or PNG (any other extension is refused).
pub fn export_figure(input: &FigureInput<'_>, path: &Path) -> Result<(), MonitorError> {
    let extension = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    let draw_error = |message: String| MonitorError::Draw {
        path: path.to_path_buf(),
        message,
    };
    register_font().map_err(|e| draw_error(e.to_string()))?;
    match extension.as_deref() {
        Some("svg") => {
            let root = SVGBackend::new(path, FIGURE_SIZE).into_drawing_area();
            draw_figure(&root, input).map_err(draw_error)?;
            root.present().map_err(|e| draw_error(e.to_string()))
        }
        Some("png") => {
            let (w, h) = FIGURE_SIZE;
            let mut rgb = vec![0u8; (w * h * 3) as usize];
            {
                let root = BitMapBackend::with_buffer(&mut rgb, FIGURE_SIZE).into_drawing_area();
                draw_figure(&root, input).map_err(draw_error)?;
                root.present().map_err(|e| draw_error(e.to_string()))?;
            }
            write_png(path, w, h, &rgb).map_err(MonitorError::from)
        }
        _ => Err(draw_error(
            "the file name must end in .svg or .png".to_owned(),
        )),
    }
}

const MEASURED: RGBColor = RGBColor(0, 90, 200);
const PREDICTED: RGBColor = RGBColor(230, 120, 0);
const TOUCHED: RGBColor = RGBColor(220, 0, 60);
const WALL: RGBColor = RGBColor(90, 90, 90);
/// A follow run's body and path.
const BODY: RGBColor = RGBColor(60, 60, 60);
/// antennad's estimated wall (the chain panel's bluish green).
const ESTIMATED_WALL: RGBColor = RGBColor(0, 158, 115);

fn draw_figure<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    input: &FigureInput<'_>,
) -> Result<(), String> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(e)?;
    let (left, right) = root.split_horizontally(FIGURE_SIZE.0 * 2 / 5);
    if let Some(measured) = input.measured {
        draw_chain(&left, measured, input.predicted)?;
    }
    draw_angles(&right, input)
}

fn draw_chain<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    measured: &ChainFrame,
    predicted: Option<&ChainFrame>,
) -> Result<(), String> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    // A follow run's figure shows the robot and its antenna, not the whole path.
    let (min, max) = if measured.body.is_some() {
        measured.local_bounds_m()
    } else {
        measured.bounds_m()
    };
    let mm = |v: f64| v * 1e3;
    let span = (max[0] - min[0]).max(max[1] - min[1]).max(0.05) * 0.55;
    let centre = [(min[0] + max[0]) / 2.0, (min[1] + max[1]) / 2.0];
    let x = mm(centre[0] - span)..mm(centre[0] + span);
    let y = mm(centre[1] - span)..mm(centre[1] + span);
    let mut chart = ChartBuilder::on(area)
        .caption(
            format!("chain at t = {:.3} s", measured.t_s),
            ("sans-serif", 20),
        )
        .margin(10)
        .x_label_area_size(30)
        .y_label_area_size(45)
        .build_cartesian_2d(x, y)
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc("x, mm (track)")
        .y_desc("y, mm")
        .draw()
        .map_err(e)?;
    for wall in &measured.walls_m {
        chart
            .draw_series(LineSeries::new(
                wall.iter().map(|p| (mm(p[0]), mm(p[1]))),
                WALL.stroke_width(3),
            ))
            .map_err(e)?;
    }
    if let Some(wall) = &measured.estimated_wall {
        let ends = wall.ends_m.map(|p| (mm(p[0]), mm(p[1])));
        let label = format!(
            "estimated wall ({}{})",
            wall.estimator,
            if wall.angle_known { "" } else { ", no angle" }
        );
        chart
            .draw_series(LineSeries::new(ends, ESTIMATED_WALL.stroke_width(2)))
            .map_err(e)?
            .label(label)
            .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], ESTIMATED_WALL));
        chart
            .draw_series([Cross::new(
                (mm(wall.at_m[0]), mm(wall.at_m[1])),
                5,
                ESTIMATED_WALL.stroke_width(2),
            )])
            .map_err(e)?;
    }
    if measured.body.is_some() && measured.path_m.len() >= 2 {
        chart
            .draw_series(LineSeries::new(
                measured.path_m.iter().map(|p| (mm(p[0]), mm(p[1]))),
                BODY.mix(0.5).stroke_width(1),
            ))
            .map_err(e)?;
    }
    if let Some(body) = &measured.body {
        let colour = if body.collided { TOUCHED } else { BODY };
        let mut outline: Vec<(f64, f64)> = body
            .corners_m
            .iter()
            .map(|p| (mm(p[0]), mm(p[1])))
            .collect();
        outline.extend(outline.first().copied());
        chart
            .draw_series(LineSeries::new(outline, colour.stroke_width(2)))
            .map_err(e)?
            .label("body")
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], colour));
    }
    if let Some(p) = predicted {
        chart
            .draw_series(LineSeries::new(
                p.joints_m.iter().map(|q| (mm(q[0]), mm(q[1]))),
                PREDICTED.stroke_width(2),
            ))
            .map_err(e)?
            .label("predicted")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], PREDICTED));
    }
    chart
        .draw_series(LineSeries::new(
            measured.joints_m.iter().map(|q| (mm(q[0]), mm(q[1]))),
            MEASURED.stroke_width(3),
        ))
        .map_err(e)?
        .label("measured")
        .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], MEASURED));
    let touched = measured
        .segments
        .iter()
        .enumerate()
        .filter(|(_, s)| s.touched())
        .filter_map(|(k, _)| measured.link_m(k + 1));
    for (a, b) in touched {
        chart
            .draw_series(LineSeries::new(
                [(mm(a[0]), mm(a[1])), (mm(b[0]), mm(b[1]))],
                TOUCHED.stroke_width(5),
            ))
            .map_err(e)?;
    }
    // The switches that fire, at their places along their links, as in the chain panel.
    chart
        .draw_series(measured.lit_switches().iter().map(|lit| {
            Circle::new(
                (mm(lit.point_m[0]), mm(lit.point_m[1])),
                4,
                TOUCHED.filled(),
            )
        }))
        .map_err(e)?;
    chart
        .configure_series_labels()
        .border_style(BLACK)
        .background_style(WHITE.mix(0.8))
        .draw()
        .map_err(e)
}

fn draw_angles<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    input: &FigureInput<'_>,
) -> Result<(), String> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let envelopes: Vec<(usize, Vec<_>)> = input
        .joints
        .iter()
        .map(|&k| {
            (
                k,
                input
                    .history
                    .envelope(k, input.t0_s, input.t1_s, FIGURE_COLUMNS),
            )
        })
        .collect();
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for c in envelopes.iter().flat_map(|(_, v)| v) {
        lo = lo.min(c.min_rad.to_degrees());
        hi = hi.max(c.max_rad.to_degrees());
    }
    if lo > hi {
        (lo, hi) = (-1.0, 1.0);
    }
    let pad = ((hi - lo) * 0.05).max(0.5);
    let mut chart = ChartBuilder::on(area)
        .caption(
            format!("joint angles, {:.3} s to {:.3} s", input.t0_s, input.t1_s),
            ("sans-serif", 20),
        )
        .margin(10)
        .x_label_area_size(30)
        .y_label_area_size(50)
        .build_cartesian_2d(input.t0_s..input.t1_s, (lo - pad)..(hi + pad))
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc("t, s")
        .y_desc("angle, deg")
        .draw()
        .map_err(e)?;
    for (i, (k, columns)) in envelopes.iter().enumerate() {
        let color = Palette99::pick(i).to_rgba();
        chart
            .draw_series(LineSeries::new(
                columns.iter().flat_map(|c| {
                    [
                        (c.t_s, c.min_rad.to_degrees()),
                        (c.t_s, c.max_rad.to_degrees()),
                    ]
                }),
                color.stroke_width(2),
            ))
            .map_err(e)?
            .label(format!("joint {}", k + 1))
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], color));
    }
    chart
        .configure_series_labels()
        .border_style(BLACK)
        .background_style(WHITE.mix(0.8))
        .draw()
        .map_err(e)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::history::{Health, Sample, SegmentReading};

    fn history() -> History {
        let mut h = History::new(2, 1000);
        for i in 0..1000u64 {
            h.push(&Sample {
                seq: Some(i),
                t_s: i as f64 * 1e-3,
                segments: vec![
                    SegmentReading {
                        angle_rad: Some(0.25),
                        touch_bits: Some(8),
                        health: Health::Ok,
                    },
                    SegmentReading {
                        angle_rad: None,
                        touch_bits: None,
                        health: Health::Nack,
                    },
                ],
                stage_position_m: Some(0.5),
                servo_angle_rad: None,
            })
            .unwrap();
        }
        h
    }

    #[test]
    fn csv_holds_exactly_the_range() {
        let mut out = Vec::new();
        let rows = write_csv(&history(), 0.1, 0.2, &mut out).unwrap();
        let text = String::from_utf8(out).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(rows, 101);
        assert_eq!(lines.len(), 102);
        assert_eq!(
            lines[0],
            "t_s,seq,stage_position_m,servo_angle_deg,s1_angle_rad,s1_touch,s1_health,\
             s2_angle_rad,s2_touch,s2_health"
        );
        assert_eq!(lines[1], "0.1,100,0.5,,0.25,8,ok,,,nack");
        assert!(lines[101].starts_with("0.2,200,"));
        // Lines end in a bare newline, the last one too; nothing is quoted.
        assert!(text.ends_with("nack\n") && !text.contains('\r') && !text.contains('"'));
    }

    /// A frame with antennad's estimated wall draws it, labelled with its estimator.
    #[test]
    fn the_estimated_wall_is_in_the_figure() {
        let h = history();
        let frame = ChainFrame {
            joints_m: vec![[0.0, 0.0], [0.04, 0.0], [0.08, 0.02], [0.1, 0.05]],
            segments: vec![crate::frame::SegmentState::QUIET; 2],
            estimated_wall: Some(crate::estimate::EstimatedWall {
                ends_m: [[-0.02, 0.1], [0.15, 0.08]],
                at_m: [0.05, 0.09],
                angle_known: true,
                estimator: "contact-line".to_owned(),
            }),
            ..ChainFrame::default()
        };
        let input = FigureInput {
            history: &h,
            t0_s: 0.0,
            t1_s: 1.0,
            joints: &[0, 1],
            measured: Some(&frame),
            predicted: None,
        };
        let svg = std::env::temp_dir().join(format!("monitor-fig-est-{}.svg", std::process::id()));
        export_figure(&input, &svg).unwrap();
        let text = std::fs::read_to_string(&svg).unwrap();
        std::fs::remove_file(&svg).ok();
        assert!(text.contains("estimated wall (contact-line)"), "{text}");
    }

    #[test]
    fn figures_in_both_formats() {
        let h = history();
        let dir = std::env::temp_dir();
        let input = FigureInput {
            history: &h,
            t0_s: 0.0,
            t1_s: 1.0,
            joints: &[0, 1],
            measured: None,
            predicted: None,
        };
        let svg = dir.join(format!("monitor-fig-{}.svg", std::process::id()));
        export_figure(&input, &svg).unwrap();
        let text = std::fs::read_to_string(&svg).unwrap();
        assert!(text.contains("<svg") && text.contains("joint 1"), "{text}");
        let png = dir.join(format!("monitor-fig-{}.png", std::process::id()));
        export_figure(&input, &png).unwrap();
        let bytes = std::fs::read(&png).unwrap();
        assert!(bytes.starts_with(b"\x89PNG"));
        std::fs::remove_file(&svg).ok();
        std::fs::remove_file(&png).ok();
        let bad = dir.join("monitor-fig.gif");
        let err = export_figure(&input, &bad).unwrap_err().to_string();
        assert!(err.contains(".svg or .png"), "{err}");
    }
}
