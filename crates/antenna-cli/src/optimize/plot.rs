//! `antenna optimize --plot FILE.svg|FILE.png`: the convergence (each evaluation's objective
//! and the best so far, the best named profile's level) beside the profile found among the
//! seven named ones (stiffness per joint, logarithmic).

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{Objective, OptimizeReport};
use crate::sweep::plot::{Drawing, PlotError, write_drawing};

/// Figure size, pixels (PNG) or user units (SVG).
pub const FIGURE_SIZE: (u32, u32) = (1400, 600);

const FOUND: RGBColor = RGBColor(0, 90, 200);
const NAMED: RGBColor = RGBColor(150, 150, 150);
const BEST_NAMED: RGBColor = RGBColor(230, 120, 0);
const FAILED: RGBColor = RGBColor(220, 0, 60);

/// Draws `report` to `path` (`.svg` or `.png`).
///
/// # Errors
/// [`PlotError`] for another extension, a drawing failure or a file that cannot be written.
pub fn write_plot(report: &OptimizeReport, path: &Path) -> Result<(), PlotError> {
    write_drawing(path, FIGURE_SIZE, &Figure(report))
}

struct Figure<'a>(&'a OptimizeReport);

impl Drawing for Figure<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        let text = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
        root.fill(&WHITE).map_err(text)?;
        let (left, right) = root.split_horizontally(FIGURE_SIZE.0 as i32 / 2);
        self.draw_convergence(&left).map_err(text)?;
        self.draw_profiles(&right).map_err(text)?;
        Ok(())
    }
}

impl Figure<'_> {
    fn draw_convergence<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
    ) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
        let r = self.0;
        let (unit, factor) = Objective::by_name(&r.objective)
            .unwrap_or(Objective::PreviewMean)
            .display_unit();
        let mm: Vec<(f64, f64)> = r
            .objective_values
            .iter()
            .enumerate()
            .filter_map(|(i, v)| v.map(|v| (i as f64, v * factor)))
            .collect();
        let (lo, hi) = mm
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p.1), hi.max(p.1))
            });
        let (lo, hi) = if lo.is_finite() { (lo, hi) } else { (0.0, 1.0) };
        let pad = ((hi - lo) * 0.05).max(1e-3);
        let evaluations = r.history.len().max(2) as f64;
        let mut chart = ChartBuilder::on(area)
            .caption(
                format!("{}: each evaluation and the best so far", r.objective),
                ("sans-serif", 20),
            )
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(0.0..evaluations, (lo - pad)..(hi + pad))?;
        chart
            .configure_mesh()
            .x_desc("evaluation")
            .x_label_formatter(&|v| format!("{v:.0}"))
            .y_desc(format!("objective ({unit})"))
            .draw()?;
        chart.draw_series(
            mm.iter()
                .map(|&(x, y)| Circle::new((x, y), 2, NAMED.mix(0.8).filled())),
        )?;
        if r.failed_evaluations > 0 {
            let failed = r
                .objective_values
                .iter()
                .enumerate()
                .filter(|(_, v)| v.is_none())
                .map(|(i, _)| Cross::new((i as f64, lo - pad * 0.5), 4, FAILED));
            chart
                .draw_series(failed)?
                .label(format!("infeasible ({})", r.failed_evaluations))
                .legend(|(x, y)| Cross::new((x + 8, y), 4, FAILED));
        }
        if let Some(named) = r
            .best_named_profile
            .as_ref()
            .and_then(|n| n.objective_value)
        {
            chart
                .draw_series(LineSeries::new(
                    [(0.0, named * factor), (evaluations, named * factor)],
                    BEST_NAMED.stroke_width(2),
                ))?
                .label(format!(
                    "best named ({})",
                    r.best_named_profile
                        .as_ref()
                        .map_or("", |n| n.name.as_str())
                ))
                .legend(|(x, y)| PathElement::new([(x, y), (x + 16, y)], BEST_NAMED));
        }
        let best: Vec<(f64, f64)> = r
            .history
            .iter()
            .enumerate()
            .filter_map(|(i, v)| v.map(|v| (i as f64, v * factor)))
            .collect();
        chart
            .draw_series(LineSeries::new(best, FOUND.stroke_width(3)))?
            .label("best so far")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 16, y)], FOUND.stroke_width(3)));
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .position(SeriesLabelPosition::LowerRight)
            .draw()?;
        Ok(())
    }

    fn draw_profiles<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
    ) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
        let r = self.0;
        let [lo, hi] = r.stiffness_bounds_n_m_per_rad;
        let joints = r.values_n_m_per_rad.len().max(1);
        let mut chart = ChartBuilder::on(area)
            .caption(
                "stiffness per joint: found and the named profiles",
                ("sans-serif", 20),
            )
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(0.5..joints as f64 + 0.5, (lo * 0.9..hi * 1.1).log_scale())?;
        chart
            .configure_mesh()
            .x_desc("joint (1 = proximal)")
            .x_labels(joints)
            .x_label_formatter(&|v| format!("{v:.0}"))
            .y_desc("k (N m/rad)")
            .y_label_formatter(&|v| format!("{v:.3}"))
            .draw()?;
        let line = |values: &[f64]| -> Vec<(f64, f64)> {
            values
                .iter()
                .enumerate()
                .map(|(j, &k)| ((j + 1) as f64, k))
                .collect()
        };
        for (i, named) in r.named_profiles.iter().enumerate() {
            let best = r
                .best_named_profile
                .as_ref()
                .is_some_and(|b| b.name == named.name);
            let style = if best {
                BEST_NAMED.stroke_width(2)
            } else {
                NAMED.stroke_width(1)
            };
            let series =
                chart.draw_series(LineSeries::new(line(&named.values_n_m_per_rad), style))?;
            if best {
                series
                    .label(format!("{} (best named)", named.name))
                    .legend(|(x, y)| PathElement::new([(x, y), (x + 16, y)], BEST_NAMED));
            } else if i == 0 {
                series
                    .label("the other named profiles")
                    .legend(|(x, y)| PathElement::new([(x, y), (x + 16, y)], NAMED));
            }
        }
        chart
            .draw_series(LineSeries::new(
                line(&r.values_n_m_per_rad),
                FOUND.stroke_width(3),
            ))?
            .label(format!("found ({})", r.found_by))
            .legend(|(x, y)| PathElement::new([(x, y), (x + 16, y)], FOUND.stroke_width(3)));
        chart.draw_series(
            line(&r.values_n_m_per_rad)
                .into_iter()
                .map(|p| Circle::new(p, 4, FOUND.filled())),
        )?;
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperRight)
            .draw()?;
        Ok(())
    }
}
