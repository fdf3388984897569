//! Nitinol joint springs: wire radius to joint stiffness, and a wire choice per joint
//! (docs/model.md section 5; thesis 2.3.2, 6.2).
//!
//! A joint's stiffness is a Nitinol wire of radius `r` (m) in parallel with the flat-flex
//! cable:
//!
//! ```text
//! k = C r^4 + k_cable,   C = 2.0614e12 N m/rad per m^4,   k_cable = 0.0016 N m/rad
//! ```
//!
//! (thesis 6.2.0.33-34 and Table 6.3; thesis 2.3.2.1 prints the rounded `2.06e12 r^4 + 1.56e-3`.)
//! Available diameters are 0.010 to 0.022 inch and 0.024 to 0.030 inch in steps of 0.001 inch,
//! kept as integer thousandths of an inch so that no float stepping is involved.
//!
//! [`WireModel::design`] maps each target stiffness to the available wire whose realized
//! stiffness is nearest (absolute difference in N m/rad; a tie goes to the softer wire).
//! A target outside the achievable range is not an error: it gets the softest or stiffest
//! wire and a [`RangeFlag`] saying so. Note that the thesis's `k_max = 0.082 N m/rad`
//! (thesis 4.2.1.1) lies above the stiffest listed wire (0.030 inch, 0.0450 N m/rad).

/// `C` in `k = C r^4 + k_cable` (thesis 6.2.0.33), N m/rad per m^4.
pub const WIRE_CONSTANT_N_M_PER_RAD_PER_M4: f64 = 2.0614e12;
/// Flat-flex cable stiffness in parallel with every wire (thesis Table 6.3), N m/rad.
pub const CABLE_STIFFNESS_N_M_PER_RAD: f64 = 0.0016;
/// Metres per inch (exact).
pub const M_PER_INCH: f64 = 0.0254;
/// Available wire diameters, thousandths of an inch: 10..=22 and 24..=30.
pub const AVAILABLE_DIAMETERS_THOUSANDTHS_IN: [u16; 20] = [
    10, 11, 12, 13, 14, 15, 16, 17, 18, 19, 20, 21, 22, 24, 25, 26, 27, 28, 29, 30,
];

/// Errors from the wire model and wire design.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum NitinolError {
    /// A target stiffness is NaN, infinite, zero or negative (its relative error would be
    /// undefined).
    #[error("target stiffness [{index}] = {value_n_m_per_rad} N m/rad is not finite and positive")]
    InvalidTarget {
        /// Index into the targets (joint `index + 1`).
        index: usize,
        /// The offending value, N m/rad.
        value_n_m_per_rad: f64,
    },
    /// A wire radius is NaN, infinite or negative.
    #[error("radius_m = {value_m} m is not finite and non-negative")]
    InvalidRadius {
        /// The offending radius, m.
        value_m: f64,
    },
    /// A [`WireModel`] field is not finite, or negative.
    #[error("wire model field {field} = {value} is not finite and non-negative")]
    InvalidModel {
        /// Field name.
        field: &'static str,
        /// The offending value.
        value: f64,
    },
    /// A wire model with an empty wire list.
    #[error("wire model has no available wires")]
    NoWires,
}

/// A wire diameter, stored as integer thousandths of an inch.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct WireDiameter {
    thousandths_in: u16,
}

impl WireDiameter {
    /// A wire of `thousandths_in` thousandths of an inch (e.g. 16 for 0.016 inch).
    pub const fn from_thousandths_in(thousandths_in: u16) -> Self {
        Self { thousandths_in }
    }

    /// Diameter in thousandths of an inch.
    pub const fn thousandths_in(self) -> u16 {
        self.thousandths_in
    }

    /// Diameter, inch.
    pub fn diameter_in(self) -> f64 {
        f64::from(self.thousandths_in) / 1000.0
    }

    /// Diameter, m.
    pub fn diameter_m(self) -> f64 {
        f64::from(self.thousandths_in) * (M_PER_INCH / 1000.0)
    }

    /// Radius, m.
    pub fn radius_m(self) -> f64 {
        0.5 * self.diameter_m()
    }
}

/// The available wires of docs/model.md section 5, softest first.
pub fn available_wires() -> Vec<WireDiameter> {
    AVAILABLE_DIAMETERS_THOUSANDTHS_IN
        .iter()
        .map(|&t| WireDiameter::from_thousandths_in(t))
        .collect()
}

/// Where a target lies relative to what the wires can realize.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RangeFlag {
    /// Between the softest and the stiffest wire: the nearest wire was chosen.
    InRange,
    /// Below the cable alone (`k_cable`): unreachable even without a wire; clamped to the
    /// softest wire.
    BelowCableOnly,
    /// At or above `k_cable` but below the softest wire; clamped to the softest wire.
    BelowSoftestWire,
    /// Above the stiffest wire; clamped to the stiffest wire.
    AboveStiffestWire,
}

/// The wire chosen for one joint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointWire {
    /// The requested stiffness, N m/rad.
    pub target_n_m_per_rad: f64,
    /// The chosen wire.
    pub wire: WireDiameter,
    /// The stiffness the chosen wire gives with the cable, N m/rad.
    pub realized_n_m_per_rad: f64,
    /// `realized - target`, N m/rad.
    pub error_n_m_per_rad: f64,
    /// `(realized - target) / target`, dimensionless.
    pub relative_error: f64,
    /// Whether the target was reachable or clamped.
    pub flag: RangeFlag,
}

/// A wire per joint (element `j - 1` is joint `j`).
#[derive(Debug, Clone, PartialEq)]
pub struct Design {
    /// One entry per target, in input order.
    pub joints: Vec<JointWire>,
}

impl Design {
    /// Largest `|relative_error|` over the joints (0 for an empty design).
    pub fn max_abs_relative_error(&self) -> f64 {
        self.joints
            .iter()
            .map(|j| j.relative_error.abs())
            .fold(0.0, f64::max)
    }

    /// `true` when no joint was clamped.
    pub fn all_in_range(&self) -> bool {
        self.joints.iter().all(|j| j.flag == RangeFlag::InRange)
    }

    /// The realized stiffnesses, N m/rad, in joint order.
    pub fn realized_n_m_per_rad(&self) -> Vec<f64> {
        self.joints.iter().map(|j| j.realized_n_m_per_rad).collect()
    }
}

/// The wire law `k = C r^4 + k_cable` with its list of available wires.
#[derive(Debug, Clone, PartialEq)]
pub struct WireModel {
    /// `C`, N m/rad per m^4.
    pub wire_constant_n_m_per_rad_per_m4: f64,
    /// `k_cable`, N m/rad.
    pub cable_stiffness_n_m_per_rad: f64,
    /// Available wires, any order.
    pub wires: Vec<WireDiameter>,
}

impl Default for WireModel {
    /// The thesis's law and wire list.
    fn default() -> Self {
        Self {
            wire_constant_n_m_per_rad_per_m4: WIRE_CONSTANT_N_M_PER_RAD_PER_M4,
            cable_stiffness_n_m_per_rad: CABLE_STIFFNESS_N_M_PER_RAD,
            wires: available_wires(),
        }
    }
}

impl WireModel {
    fn validate(&self) -> Result<(), NitinolError> {
        for (field, value) in [
            (
                "wire_constant_n_m_per_rad_per_m4",
                self.wire_constant_n_m_per_rad_per_m4,
            ),
            (
                "cable_stiffness_n_m_per_rad",
                self.cable_stiffness_n_m_per_rad,
            ),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(NitinolError::InvalidModel { field, value });
            }
        }
        if self.wires.is_empty() {
            return Err(NitinolError::NoWires);
        }
        Ok(())
    }

    /// Joint stiffness `C r^4 + k_cable` for a wire of radius `radius_m`, N m/rad.
    ///
    /// # Errors
    /// [`NitinolError::InvalidRadius`] for a NaN, infinite or negative radius;
    /// [`NitinolError::InvalidModel`] for a bad model constant.
    pub fn stiffness_n_m_per_rad(&self, radius_m: f64) -> Result<f64, NitinolError> {
        self.validate_constants()?;
        if !(radius_m.is_finite() && radius_m >= 0.0) {
            return Err(NitinolError::InvalidRadius { value_m: radius_m });
        }
        Ok(self.law(radius_m))
    }

    /// The wire radius, m, that realizes `target_n_m_per_rad` exactly (ignoring the wire
    /// list); `None` when the target is at or below the cable alone.
    ///
    /// # Errors
    /// [`NitinolError::InvalidTarget`] (index 0) for a non-finite or non-positive target;
    /// [`NitinolError::InvalidModel`] for a bad model constant.
    pub fn ideal_radius_m(&self, target_n_m_per_rad: f64) -> Result<Option<f64>, NitinolError> {
        self.validate_constants()?;
        if !(target_n_m_per_rad.is_finite() && target_n_m_per_rad > 0.0) {
            return Err(NitinolError::InvalidTarget {
                index: 0,
                value_n_m_per_rad: target_n_m_per_rad,
            });
        }
        let wire_part = target_n_m_per_rad - self.cable_stiffness_n_m_per_rad;
        if wire_part <= 0.0 || self.wire_constant_n_m_per_rad_per_m4 == 0.0 {
            return Ok(None);
        }
        Ok(Some(
            (wire_part / self.wire_constant_n_m_per_rad_per_m4).powf(0.25),
        ))
    }

    /// Maps each target to the available wire nearest in stiffness (ties to the softer wire)
    /// and reports realized stiffness, errors and a range flag per joint.
    ///
    /// # Errors
    /// [`NitinolError::InvalidTarget`] naming the first NaN, infinite, zero or negative target;
    /// [`NitinolError::InvalidModel`] / [`NitinolError::NoWires`] for a bad model.
    pub fn design(&self, targets_n_m_per_rad: &[f64]) -> Result<Design, NitinolError> {
        self.validate()?;
        for (index, &value) in targets_n_m_per_rad.iter().enumerate() {
            if !(value.is_finite() && value > 0.0) {
                return Err(NitinolError::InvalidTarget {
                    index,
                    value_n_m_per_rad: value,
                });
            }
        }
        let mut wires = self.wires.clone();
        wires.sort_unstable();
        wires.dedup();
        let realized: Vec<f64> = wires.iter().map(|w| self.law(w.radius_m())).collect();
        let (softest_k, stiffest_k) = match (realized.first(), realized.last()) {
            (Some(&a), Some(&b)) => (a, b),
            _ => return Err(NitinolError::NoWires),
        };
        let joints = targets_n_m_per_rad
            .iter()
            .map(|&target| {
                let mut best = 0;
                for (i, &k) in realized.iter().enumerate() {
                    // Strictly nearer only: a tie keeps the softer (earlier) wire.
                    if (k - target).abs() < (realized[best] - target).abs() {
                        best = i;
                    }
                }
                let flag = if target < self.cable_stiffness_n_m_per_rad {
                    RangeFlag::BelowCableOnly
                } else if target < softest_k {
                    RangeFlag::BelowSoftestWire
                } else if target > stiffest_k {
                    RangeFlag::AboveStiffestWire
                } else {
                    RangeFlag::InRange
                };
                let error = realized[best] - target;
                JointWire {
                    target_n_m_per_rad: target,
                    wire: wires[best],
                    realized_n_m_per_rad: realized[best],
                    error_n_m_per_rad: error,
                    relative_error: error / target,
                    flag,
                }
            })
            .collect();
        Ok(Design { joints })
    }

    fn validate_constants(&self) -> Result<(), NitinolError> {
        match self.validate() {
            Err(NitinolError::NoWires) | Ok(()) => Ok(()),
            Err(e) => Err(e),
        }
    }

    fn law(&self, radius_m: f64) -> f64 {
        self.wire_constant_n_m_per_rad_per_m4 * radius_m.powi(4) + self.cable_stiffness_n_m_per_rad
    }
}

/// The thesis's law for one wire: `2.0614e12 r^4 + 0.0016` N m/rad.
pub fn wire_stiffness_n_m_per_rad(wire: WireDiameter) -> f64 {
    WIRE_CONSTANT_N_M_PER_RAD_PER_M4 * wire.radius_m().powi(4) + CABLE_STIFFNESS_N_M_PER_RAD
}

/// [`WireModel::design`] with the thesis's law and wire list.
///
/// # Errors
/// [`NitinolError::InvalidTarget`] naming the first NaN, infinite, zero or negative target.
pub fn design(targets_n_m_per_rad: &[f64]) -> Result<Design, NitinolError> {
    WireModel::default().design(targets_n_m_per_rad)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Golden `2.0614e12 r^4 + 0.0016` per wire, computed independently (Python, f64).
    const GOLDEN: [(u16, f64); 20] = [
        (10, 0.0021362621629574),
        (11, 0.002385141432785929),
        (12, 0.0027119932211084642),
        (13, 0.0031316183636226303),
        (14, 0.0036601047252171467),
        (15, 0.004314827199971837),
        (16, 0.0051144477111576166),
        (17, 0.006078915211236502),
        (18, 0.007229465681861605),
        (19, 0.00858862213387713),
        (20, 0.0101801946073184),
        (21, 0.012029280171411817),
        (22, 0.014162262924574865),
        (24, 0.01939189153773543),
        (25, 0.022547740740523445),
        (26, 0.02610589381796208),
        (27, 0.03009917001442436),
        (28, 0.03456167560347435),
        (29, 0.03952880388786728),
        (30, 0.04503723519954939),
    ];

    #[test]
    fn available_diameters_are_the_two_ranges() {
        let expected: Vec<u16> = (10..=22).chain(24..=30).collect();
        assert_eq!(AVAILABLE_DIAMETERS_THOUSANDTHS_IN.to_vec(), expected);
        assert_eq!(available_wires().len(), 20);
    }

    #[test]
    fn golden_stiffness_per_wire() {
        let model = WireModel::default();
        for (t, k) in GOLDEN {
            let w = WireDiameter::from_thousandths_in(t);
            let got = wire_stiffness_n_m_per_rad(w);
            assert!((got - k).abs() <= 1e-15 * k, "{t}: {got} vs {k}");
            assert_eq!(model.stiffness_n_m_per_rad(w.radius_m()).unwrap(), got);
        }
        // 0.016 inch: r = 0.2032 mm exactly.
        let w = WireDiameter::from_thousandths_in(16);
        assert!((w.radius_m() - 2.032e-4).abs() < 1e-18);
        assert!((w.diameter_in() - 0.016).abs() < 1e-18);
    }

    #[test]
    fn exact_targets_give_their_wire_with_zero_error() {
        let targets: Vec<f64> = available_wires()
            .into_iter()
            .map(wire_stiffness_n_m_per_rad)
            .collect();
        let d = design(&targets).unwrap();
        for (j, (t, _)) in d.joints.iter().zip(GOLDEN) {
            assert_eq!(j.wire.thousandths_in(), t);
            assert!(j.relative_error.abs() < 1e-14);
            assert_eq!(j.flag, RangeFlag::InRange);
        }
        assert!(d.all_in_range());
    }

    #[test]
    fn golden_design_of_mixed_targets() {
        // 0.005 lies between 0.015 in (0.0043148) and 0.016 in (0.0051144): nearer 0.016.
        // 0.0169 lies between 0.022 in (0.0141623, 0.0027377 away) and 0.024 in (0.0193919,
        // 0.0024919 away): nearer 0.024.
        let d = design(&[0.005, 0.0169, 0.001, 0.002, 0.082]).unwrap();
        let got: Vec<(u16, RangeFlag)> = d
            .joints
            .iter()
            .map(|j| (j.wire.thousandths_in(), j.flag))
            .collect();
        assert_eq!(
            got,
            vec![
                (16, RangeFlag::InRange),
                (24, RangeFlag::InRange),
                (10, RangeFlag::BelowCableOnly),
                (10, RangeFlag::BelowSoftestWire),
                (30, RangeFlag::AboveStiffestWire),
            ]
        );
        let j0 = d.joints[0];
        assert!((j0.realized_n_m_per_rad - 0.0051144477111576166).abs() < 1e-17);
        assert!((j0.error_n_m_per_rad - 0.0001144477111576166).abs() < 1e-15);
        assert!((j0.relative_error - 0.02288954223152332).abs() < 1e-12);
        let j4 = d.joints[4];
        assert!((j4.relative_error - (0.04503723519954939 / 0.082 - 1.0)).abs() < 1e-12);
        assert!(!d.all_in_range());
        // Worst joint: target 0.001 realized by the softest wire, 0.0021363 (+113.6 %).
        assert!((d.max_abs_relative_error() - (0.0021362621629574 / 0.001 - 1.0)).abs() < 1e-12);
    }

    #[test]
    fn tie_goes_to_softer_wire() {
        let mid = 0.5 * (GOLDEN[0].1 + GOLDEN[1].1);
        let model = WireModel::default();
        let j = model.design(&[mid]).unwrap().joints[0];
        // Rounding may put `mid` a hair off the exact midpoint; either way the choice must be
        // the nearer one, and at an exact tie the softer one.
        let d10 = (GOLDEN[0].1 - mid).abs();
        let d11 = (GOLDEN[1].1 - mid).abs();
        let want = if d11 < d10 { 11 } else { 10 };
        assert_eq!(j.wire.thousandths_in(), want);
    }

    #[test]
    fn ideal_radius_inverts_the_law() {
        let model = WireModel::default();
        let w = WireDiameter::from_thousandths_in(21);
        let r = model
            .ideal_radius_m(wire_stiffness_n_m_per_rad(w))
            .unwrap()
            .unwrap();
        assert!((r - w.radius_m()).abs() < 1e-15);
        assert_eq!(model.ideal_radius_m(0.0015).unwrap(), None);
        // The thesis's k_max needs a 0.035 inch wire, above the list.
        let r_max = model.ideal_radius_m(0.082).unwrap().unwrap();
        assert!((2.0 * r_max / M_PER_INCH - 0.035).abs() < 5e-4);
    }

    #[test]
    fn bad_inputs_are_typed_errors() {
        for bad in [f64::NAN, -0.01, 0.0, f64::INFINITY] {
            assert!(matches!(
                design(&[0.01, bad]),
                Err(NitinolError::InvalidTarget { index: 1, .. })
            ));
        }
        let model = WireModel::default();
        assert!(matches!(
            model.stiffness_n_m_per_rad(-1e-4),
            Err(NitinolError::InvalidRadius { .. })
        ));
        let no_wires = WireModel {
            wires: vec![],
            ..WireModel::default()
        };
        assert_eq!(no_wires.design(&[0.01]), Err(NitinolError::NoWires));
        let bad_c = WireModel {
            wire_constant_n_m_per_rad_per_m4: f64::NAN,
            ..WireModel::default()
        };
        assert!(matches!(
            bad_c.design(&[0.01]),
            Err(NitinolError::InvalidModel {
                field: "wire_constant_n_m_per_rad_per_m4",
                ..
            })
        ));
        assert_eq!(design(&[]).unwrap().joints.len(), 0);
    }

    proptest! {
        /// The chosen wire is nearest in stiffness among all wires, and the flags agree with
        /// the wire range.
        #[test]
        fn choice_is_nearest_and_flag_consistent(target in 1e-4f64..0.1) {
            let d = design(&[target]).unwrap();
            let j = d.joints[0];
            for (_, k) in GOLDEN {
                prop_assert!((j.realized_n_m_per_rad - target).abs() <= (k - target).abs() + 1e-15);
            }
            prop_assert!((j.error_n_m_per_rad - (j.realized_n_m_per_rad - target)).abs() < 1e-18);
            match j.flag {
                RangeFlag::InRange => prop_assert!(target >= GOLDEN[0].1 && target <= GOLDEN[19].1),
                RangeFlag::BelowCableOnly => {
                    prop_assert!(target < CABLE_STIFFNESS_N_M_PER_RAD);
                    prop_assert_eq!(j.wire.thousandths_in(), 10);
                }
                RangeFlag::BelowSoftestWire => prop_assert_eq!(j.wire.thousandths_in(), 10),
                RangeFlag::AboveStiffestWire => prop_assert_eq!(j.wire.thousandths_in(), 30),
            }
        }
    }
}
