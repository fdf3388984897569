//! The antenna's own estimators fed sample by sample: from sensed joint angles and touch
//! bits to the wall, the one implementation behind `antenna follow`'s loop ([`super::Follow`])
//! and antennad's live estimate.
//!
//! A sample maps the touched switches to contact points ([`estimate_contacts`]) in the body
//! frame (x ahead, y toward the wall; the antenna's base pivot at `mount_m`, `theta[0]` the
//! base link's angle to the body's x axis). The contact-line estimator keeps them, carried by
//! the odometry, for its window; the bend estimator reads the point of bend of the newest
//! sample through its calibration table.
//!
//! ```
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! use nalgebra::Vector2;
//! use sim_core::follow::estimate::Odometry;
//! use sim_core::follow::sensed::SensedWall;
//! use sim_core::{Chain, TouchLayout};
//!
//! // Two links of 0.1 m along the x axis; the tip link touches at its two distal switches.
//! let chain = Chain::builder(1).link_length_m(0.1).build()?;
//! let mut wall = SensedWall::contact_line(0.5, TouchLayout::default());
//! let mut odometry = Odometry::default();
//! wall.add_sample(0.0, &odometry, &chain, &Vector2::zeros(), &[0.3, 0.0], &[0, 0b1100])?;
//! odometry.advance(0.2, 0.0, 0.1); // 2 cm on
//! wall.add_sample(0.1, &odometry, &chain, &Vector2::zeros(), &[0.3, 0.0], &[0, 0b1100])?;
//! let estimate = wall.estimate(&odometry).map_err(|why| why.reason())?;
//! assert!(estimate.angle_rad.is_some());
//! # Ok(())
//! # }
//! ```

use nalgebra::Vector2;

use super::estimate::{BendTable, ContactWindow, Estimate, NoEstimate, Odometry, bend_coordinate};
use crate::{Chain, EstimatedContact, MappingError, TouchLayout, estimate_contacts};

/// Which estimator, with its state.
#[derive(Clone, Debug)]
enum Method {
    /// The contact points of a time window and the line through them.
    ContactLine(ContactWindow),
    /// The newest sample's point of bend through the table.
    Bend {
        table: BendTable,
        last: Result<Estimate, NoEstimate>,
    },
}

/// The wall as the antenna senses it (see the [module documentation](self)).
#[derive(Clone, Debug)]
pub struct SensedWall {
    method: Method,
    layout: TouchLayout,
    contacts: Vec<EstimatedContact>,
    points_m: Vec<Vector2<f64>>,
}

impl SensedWall {
    /// The contact-line estimator over the last `window_s` seconds, placing touched switches
    /// by `layout`.
    pub fn contact_line(window_s: f64, layout: TouchLayout) -> SensedWall {
        SensedWall::with(Method::ContactLine(ContactWindow::new(window_s)), layout)
    }

    /// The bend estimator with its calibration table.
    pub fn bend(table: BendTable, layout: TouchLayout) -> SensedWall {
        SensedWall::with(
            Method::Bend {
                table,
                last: Err(NoEstimate::NoTouch),
            },
            layout,
        )
    }

    fn with(method: Method, layout: TouchLayout) -> SensedWall {
        SensedWall {
            method,
            layout,
            contacts: Vec::new(),
            points_m: Vec::new(),
        }
    }

    /// `"contact-line"` or `"bend"`.
    pub fn name(&self) -> &'static str {
        match self.method {
            Method::ContactLine(_) => "contact-line",
            Method::Bend { .. } => "bend",
        }
    }

    /// The bend estimator's calibration table.
    pub fn bend_table(&self) -> Option<&BendTable> {
        match &self.method {
            Method::Bend { table, .. } => Some(table),
            Method::ContactLine(_) => None,
        }
    }

    /// One sample at `t_s`: the sensed angles (`n + 1`, `theta[0]` the base link's angle to
    /// the body's x axis) and touch bits (`n + 1`, entry `i` for link `i`) of `chain`, its
    /// base pivot at `mount_m` in the body frame, the body at `odometry`.
    ///
    /// # Errors
    /// What [`estimate_contacts`] refuses (lengths, touch bits beyond four switches, values
    /// that are not finite); the estimator's state is then unchanged.
    pub fn add_sample(
        &mut self,
        t_s: f64,
        odometry: &Odometry,
        chain: &Chain,
        mount_m: &Vector2<f64>,
        sensed_theta_rad: &[f64],
        touch_bits: &[u8],
    ) -> Result<(), MappingError> {
        self.contacts.clear();
        estimate_contacts(
            chain,
            mount_m,
            sensed_theta_rad,
            touch_bits,
            &self.layout,
            &mut self.contacts,
        )?;
        self.points_m.clear();
        self.points_m
            .extend(self.contacts.iter().map(|c| c.point_m));
        match &mut self.method {
            Method::ContactLine(window) => window.add(t_s, odometry, &self.points_m),
            Method::Bend { table, last } => {
                *last = if touch_bits.iter().all(|&b| b == 0) {
                    Err(NoEstimate::NoTouch)
                } else {
                    bend_coordinate(sensed_theta_rad)
                        .ok_or(NoEstimate::NoTouch)
                        .and_then(|b| table.distance_m(b))
                        .map(|distance_m| Estimate {
                            distance_m,
                            angle_rad: None,
                            preview_m: 0.0,
                        })
                };
            }
        }
        Ok(())
    }

    /// The estimate with the body at `odometry`: the contact line through the window's
    /// points carried into the current body frame, or the newest sample's bend.
    ///
    /// # Errors
    /// Why there is none ([`NoEstimate`]).
    pub fn estimate(&mut self, odometry: &Odometry) -> Result<Estimate, NoEstimate> {
        match &mut self.method {
            Method::ContactLine(window) => window.estimate(odometry),
            Method::Bend { last, .. } => *last,
        }
    }

    /// The newest sample's mapped contact points, body frame at its time, m.
    pub fn sample_points_m(&self) -> &[Vector2<f64>] {
        &self.points_m
    }

    /// The contact-line estimator's points of its last estimate, body frame at its time, m
    /// (empty for the bend estimator).
    pub fn window_points_m(&self) -> &[Vector2<f64>] {
        match &self.method {
            Method::ContactLine(window) => window.body_points_m(),
            Method::Bend { .. } => &[],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn straight_chain() -> Chain {
        Chain::builder(3)
            .link_length_m(0.05)
            .build()
            .expect("a valid chain")
    }

    #[test]
    fn the_contact_line_sees_a_wall_its_switches_trace() {
        // A straight antenna at 0.2 rad to the body axis, the distal switch of its tip link
        // touching while the body moves 5 cm: the points lie on a parallel to the body
        // axis, the fitted line is that parallel.
        let chain = straight_chain();
        let mut wall = SensedWall::contact_line(1.0, TouchLayout::default());
        let mut odometry = Odometry::default();
        let theta = [0.2, 0.0, 0.0, 0.0];
        let touch = [0, 0, 0, 0b1000];
        for k in 0..6 {
            wall.add_sample(
                k as f64 * 0.1,
                &odometry,
                &chain,
                &Vector2::zeros(),
                &theta,
                &touch,
            )
            .expect("valid input");
            if k < 5 {
                odometry.advance(0.1, 0.0, 0.1);
            }
        }
        let estimate = wall.estimate(&odometry).expect("an estimate");
        // The switch at 7/8 of link 3: 0.15 + 0.04375 m from the base pivot.
        let y_m = 0.19375 * 0.2f64.sin();
        assert!((estimate.distance_m - y_m).abs() < 1e-12);
        assert!(estimate.angle_rad.expect("an angle").abs() < 1e-12);
        // The points' mean: half the 5 cm travel behind the newest point.
        let x_m = 0.19375 * 0.2f64.cos() - 0.025;
        assert!((estimate.preview_m - x_m).abs() < 1e-12);
        assert_eq!(wall.sample_points_m().len(), 1);
        assert_eq!(wall.window_points_m().len(), 6);
    }

    #[test]
    fn the_bend_estimator_reads_the_newest_sample_through_its_table() {
        let chain = straight_chain();
        let table = BendTable::from_measurements(vec![(1.0, 0.10), (3.0, 0.02)]);
        let mut wall = SensedWall::bend(table, TouchLayout::default());
        let odometry = Odometry::default();
        assert_eq!(wall.estimate(&odometry), Err(NoEstimate::NoTouch));
        // Bent at joint 2 (the largest |theta|), its neighbours equal: bend = 2.
        let theta = [0.3, 0.05, 0.2, 0.05];
        wall.add_sample(
            0.0,
            &odometry,
            &chain,
            &Vector2::zeros(),
            &theta,
            &[0, 0, 0, 8],
        )
        .expect("valid input");
        let estimate = wall.estimate(&odometry).expect("an estimate");
        assert!((estimate.distance_m - 0.06).abs() < 1e-12);
        assert_eq!(estimate.angle_rad, None);
        // No switch closed: no estimate, whatever the bend.
        wall.add_sample(0.1, &odometry, &chain, &Vector2::zeros(), &theta, &[0; 4])
            .expect("valid input");
        assert_eq!(wall.estimate(&odometry), Err(NoEstimate::NoTouch));
        assert!(wall.window_points_m().is_empty());
    }

    #[test]
    fn bad_input_is_refused_and_changes_nothing() {
        let chain = straight_chain();
        let mut wall = SensedWall::contact_line(1.0, TouchLayout::default());
        let odometry = Odometry::default();
        assert!(
            wall.add_sample(
                0.0,
                &odometry,
                &chain,
                &Vector2::zeros(),
                &[0.0; 3],
                &[0; 4]
            )
            .is_err()
        );
        assert!(
            wall.add_sample(
                0.0,
                &odometry,
                &chain,
                &Vector2::zeros(),
                &[0.0; 4],
                &[0, 0, 0, 16]
            )
            .is_err()
        );
        assert_eq!(wall.estimate(&odometry), Err(NoEstimate::NoContact));
    }
}
