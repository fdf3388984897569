//! `antenna design`: joint stiffness targets to the nearest available Nitinol wire per joint
//! (docs/model.md 5: `k = 2.0614e12 r^4 + 0.0016` N m/rad), as a table or JSON.

use std::fmt::Write as _;

use serde::{Deserialize, Serialize};
use sim_core::design::nitinol::{CABLE_STIFFNESS_N_M_PER_RAD, WIRE_CONSTANT_N_M_PER_RAD_PER_M4};
use sim_core::{NitinolError, RangeFlag, design_wires};

/// One joint of a design.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct JointDesign {
    /// Joint index `1..=n` (joint 1 is the most proximal flexible joint).
    pub joint: usize,
    /// The stiffness asked for, N m/rad.
    pub target_n_m_per_rad: f64,
    /// The chosen wire's diameter, inches.
    pub wire_diameter_in: f64,
    /// The chosen wire's radius, metres.
    pub wire_radius_m: f64,
    /// The stiffness that wire gives with the cable, N m/rad.
    pub realized_n_m_per_rad: f64,
    /// `realized - target`, N m/rad.
    pub error_n_m_per_rad: f64,
    /// `100 (realized - target) / target`.
    pub error_percent: f64,
    /// Where the target lies relative to what the wires can give (see [`range_name`]).
    pub range: String,
}

/// A design: one wire per joint.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DesignReport {
    /// The wire constant `C` of the law, N m/rad per m^4.
    pub wire_constant_n_m_per_rad_per_m4: f64,
    /// The cable stiffness in parallel with every wire, N m/rad.
    pub cable_stiffness_n_m_per_rad: f64,
    /// One entry per joint, proximal first.
    pub joints: Vec<JointDesign>,
    /// The largest `|error_percent|`.
    pub max_abs_error_percent: f64,
    /// Whether every target lies between the softest and the stiffest available wire.
    pub all_in_range: bool,
}

/// The kebab-case name of a range flag, as printed and in JSON.
pub fn range_name(flag: RangeFlag) -> &'static str {
    match flag {
        RangeFlag::InRange => "in-range",
        RangeFlag::BelowCableOnly => "below-cable-only",
        RangeFlag::BelowSoftestWire => "below-softest-wire",
        RangeFlag::AboveStiffestWire => "above-stiffest-wire",
    }
}

/// Designs one wire per joint for `targets_n_m_per_rad` (joint 1 first).
///
/// # Errors
/// [`NitinolError`] for a target that is not finite and positive.
pub fn design_report(targets_n_m_per_rad: &[f64]) -> Result<DesignReport, NitinolError> {
    let design = design_wires(targets_n_m_per_rad)?;
    let joints: Vec<JointDesign> = design
        .joints
        .iter()
        .enumerate()
        .map(|(i, j)| JointDesign {
            joint: i + 1,
            target_n_m_per_rad: j.target_n_m_per_rad,
            wire_diameter_in: j.wire.diameter_in(),
            wire_radius_m: j.wire.radius_m(),
            realized_n_m_per_rad: j.realized_n_m_per_rad,
            error_n_m_per_rad: j.error_n_m_per_rad,
            error_percent: 100.0 * j.relative_error,
            range: range_name(j.flag).to_string(),
        })
        .collect();
    Ok(DesignReport {
        wire_constant_n_m_per_rad_per_m4: WIRE_CONSTANT_N_M_PER_RAD_PER_M4,
        cable_stiffness_n_m_per_rad: CABLE_STIFFNESS_N_M_PER_RAD,
        max_abs_error_percent: 100.0 * design.max_abs_relative_error(),
        all_in_range: design.all_in_range(),
        joints,
    })
}

/// The design as an aligned text table with a one-line summary.
pub fn design_table(report: &DesignReport) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{:>5}  {:>14}  {:>9}  {:>16}  {:>13}  {:>8}  range",
        "joint", "target N m/rad", "wire in", "realized N m/rad", "error N m/rad", "error %"
    );
    for j in &report.joints {
        let _ = writeln!(
            out,
            "{:>5}  {:>14.6}  {:>9.3}  {:>16.6}  {:>+13.6}  {:>+8.2}  {}",
            j.joint,
            j.target_n_m_per_rad,
            j.wire_diameter_in,
            j.realized_n_m_per_rad,
            j.error_n_m_per_rad,
            j.error_percent,
            j.range
        );
    }
    let out_of_range = report
        .joints
        .iter()
        .filter(|j| j.range != "in-range")
        .count();
    let _ = writeln!(
        out,
        "max |error| {:.2} %; {} of {} joint(s) outside the available wires \
         (k = {:e} r^4 + {} N m/rad)",
        report.max_abs_error_percent,
        out_of_range,
        report.joints.len(),
        report.wire_constant_n_m_per_rad_per_m4,
        report.cable_stiffness_n_m_per_rad
    );
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_wire_stiffness_maps_to_its_wire_exactly() {
        // 0.016 in: r = 2.032e-4 m, k = 2.0614e12 r^4 + 0.0016.
        let r: f64 = 0.016 * 0.0254 / 2.0;
        let k = 2.0614e12 * r.powi(4) + 0.0016;
        let report = design_report(&[k, 0.082]).unwrap();
        let j = &report.joints[0];
        assert!((j.wire_diameter_in - 0.016).abs() < 1e-12);
        assert!(j.error_percent.abs() < 1e-9);
        assert_eq!(j.range, "in-range");
        assert_eq!(report.joints[1].range, "above-stiffest-wire");
        assert!(!report.all_in_range);
        let table = design_table(&report);
        assert_eq!(table.lines().count(), 4, "{table}");
    }
}
