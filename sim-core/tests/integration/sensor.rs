//! Sensors as they are (`sim_core::Sensors`, issue #18): the touch debouncer works as the
//! segment firmware's (a bit changes only after N agreeing raw reads), the force threshold
//! closes a switch at the threshold and not below, the sample clock samples at `k / rate`,
//! the Hall noise has the standard deviation set, per-joint calibration errors are applied
//! as given and spreads are drawn from the seed, and ideal sensors read exactly what
//! `sensed_theta_rad` and `touch_bits_from_contacts` give (property-tested).
#![allow(clippy::unwrap_used)]

use antenna_protocol::RAD_PER_COUNT;
use nalgebra::Vector2;
use proptest::prelude::*;
use sim_core::contact::{Contact, Feature, FrictionLaw, Slip};
use sim_core::{
    CalibrationError, ChainContact, FIRMWARE_DEBOUNCE_SAMPLES, SensorError, SensorField,
    SensorSettings, Sensors, sensed_theta_rad, touch_bits_from_contacts,
};

/// A contact on `link` at fraction `s`, pressed with `normal_force_n` (no shear).
fn contact(link: usize, s: f64, normal_force_n: f64) -> Contact {
    Contact {
        feature: Feature::Link { link },
        wall: 0,
        s,
        point_m: Vector2::zeros(),
        normal: Vector2::new(0.0, -1.0),
        tangent: Vector2::new(1.0, 0.0),
        normal_force_n,
        shear_force_n: 0.0,
        law: FrictionLaw::Coulomb { mu: 0.3 },
        slip: Slip::Stuck,
        slip_m: 0.0,
        relaxed_shear_bound_n: None,
    }
}

fn settings(f: impl FnOnce(&mut SensorSettings)) -> SensorSettings {
    let mut s = SensorSettings::IDEAL;
    f(&mut s);
    s
}

/// The reported angle of `theta_rad` in counts.
fn counts(theta_rad: f64) -> i64 {
    (theta_rad / RAD_PER_COUNT).round() as i64
}

#[test]
fn debounce_changes_a_bit_only_after_n_agreeing_reads() {
    assert_eq!(FIRMWARE_DEBOUNCE_SAMPLES, 3);
    let mut sensors = Sensors::new(
        &settings(|s| s.touch_debounce_samples = FIRMWARE_DEBOUNCE_SAMPLES),
        2,
    )
    .unwrap();
    let touching = [contact(2, 0.1, 1.0)];
    let raw = [1, 1, 1, 1, 0, 1, 0, 0, 1, 0, 0, 0];
    let want = [0, 0, 1, 1, 1, 1, 1, 1, 1, 1, 1, 0];
    let mut out = [0_u8; 3];
    for (k, (&r, &w)) in raw.iter().zip(&want).enumerate() {
        let contacts: &[Contact] = if r == 1 { &touching } else { &[] };
        sensors.sense_touch(contacts, &mut out).unwrap();
        assert_eq!(out, [0, 0, w], "read {k}");
    }
    // Each switch is debounced on its own: switch 0 closed, then switch 3 as well.
    let mut sensors = Sensors::new(&settings(|s| s.touch_debounce_samples = 2), 1).unwrap();
    let both = [contact(1, 0.1, 1.0), contact(1, 0.9, 1.0)];
    sensors.sense_touch(&both[..1], &mut [0; 2]).unwrap();
    sensors.sense_touch(&both[..1], &mut [0; 2]).unwrap();
    let mut out = [0_u8; 2];
    sensors.sense_touch(&both, &mut out).unwrap();
    assert_eq!(out, [0, 0b0001]);
    sensors.sense_touch(&both, &mut out).unwrap();
    assert_eq!(out, [0, 0b1001]);
}

#[test]
fn a_switch_closes_at_the_threshold_force_and_not_below() {
    let mut sensors = Sensors::new(&settings(|s| s.touch_threshold_n = 0.01), 3).unwrap();
    let mut out = [0_u8; 4];
    let contacts = [
        contact(1, 0.3, 0.0099),
        contact(2, 0.6, 0.01),
        contact(3, 1.0, 0.5),
    ];
    sensors.sense_touch(&contacts, &mut out).unwrap();
    assert_eq!(out, [0, 0, 1 << 2, 1 << 3]);
    // The force is the whole force: shear counts too.
    let mut sheared = contact(1, 0.3, 0.006);
    sheared.shear_force_n = 0.009;
    sensors.sense_touch(&[sheared], &mut out).unwrap();
    assert_eq!(out, [0, 1 << 1, 0, 0]);
}

#[test]
fn the_sample_clock_samples_at_k_over_the_rate() {
    let step_s = 0.01;
    let mut sensors = Sensors::new(&settings(|s| s.sample_rate_hz = Some(30.0)), 2).unwrap();
    let due: Vec<u64> = (0..=200_u64)
        .filter(|&k| sensors.is_sample_due(k as f64 * step_s))
        .collect();
    // The first step at or after m / 30 s: ceil(10 m / 3).
    let want: Vec<u64> = (0..=60_u64).map(|m| (10 * m).div_ceil(3)).collect();
    assert_eq!(due, want);
    assert_eq!(sensors.samples(), 61);
    // Faster than the steps: every step, once.
    let mut fast = Sensors::new(&settings(|s| s.sample_rate_hz = Some(1000.0)), 2).unwrap();
    assert!((0..=50).all(|k| fast.is_sample_due(f64::from(k) * step_s)));
    assert_eq!(fast.samples(), 51);
    // Without a rate: every step.
    let mut every = Sensors::new(&SensorSettings::IDEAL, 2).unwrap();
    assert!((0..=50).all(|k| every.is_sample_due(f64::from(k) * step_s)));
    assert_eq!(every.samples(), 51);
}

#[test]
fn the_angle_noise_has_the_standard_deviation_set() {
    let n = 4;
    let noise_counts = 3.0;
    let mut sensors = Sensors::new(
        &settings(|s| {
            s.angle_noise_counts = noise_counts;
            s.seed = 11;
        }),
        n,
    )
    .unwrap();
    // Angles on whole counts, so that the rounding of the reading adds no bias.
    let theta: Vec<f64> = (0..=n).map(|j| j as f64 * 40.0 * RAD_PER_COUNT).collect();
    let mut out = vec![0.0; n + 1];
    let mut errors = Vec::new();
    for _ in 0..20_000 {
        sensors.sense_angles_rad(&theta, &mut out).unwrap();
        assert_eq!(out[0], theta[0], "the base angle is known exactly");
        for j in 1..=n {
            errors.push((counts(out[j]) - counts(theta[j])) as f64);
        }
    }
    let mean = errors.iter().sum::<f64>() / errors.len() as f64;
    let sd = (errors.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / errors.len() as f64).sqrt();
    // Rounding a Gaussian of sd 3 to whole counts adds a variance of about 1/12.
    let want = (noise_counts * noise_counts + 1.0 / 12.0).sqrt();
    assert!(mean.abs() < 0.05, "mean {mean} counts");
    assert!((sd - want).abs() < 0.05, "sd {sd} counts, want {want}");
}

#[test]
fn per_joint_calibration_is_applied_as_given() {
    let s = settings(|s| {
        s.offset_counts = CalibrationError::PerJoint(vec![1.0, -2.0, 0.0]);
        s.gain_error = CalibrationError::PerJoint(vec![0.0, 0.0, 0.5]);
    });
    let mut sensors = Sensors::new(&s, 3).unwrap();
    assert_eq!(sensors.offset_counts(), &[0.0, 1.0, -2.0, 0.0]);
    assert_eq!(sensors.gain_error(), &[0.0, 0.0, 0.0, 0.5]);
    let theta = [
        0.7,
        100.0 * RAD_PER_COUNT,
        -50.0 * RAD_PER_COUNT,
        40.0 * RAD_PER_COUNT,
    ];
    let mut out = [0.0; 4];
    sensors.sense_angles_rad(&theta, &mut out).unwrap();
    assert_eq!(out[0], 0.7);
    assert_eq!(
        [counts(out[1]), counts(out[2]), counts(out[3])],
        [101, -52, 60]
    );
}

#[test]
fn calibration_spreads_are_drawn_from_the_seed() {
    let spread = |seed| {
        settings(|s| {
            s.offset_counts = CalibrationError::Spread(4.0);
            s.gain_error = CalibrationError::Spread(0.01);
            s.seed = seed;
        })
    };
    let n = 4000;
    let a = Sensors::new(&spread(5), n).unwrap();
    let b = Sensors::new(&spread(5), n).unwrap();
    let c = Sensors::new(&spread(6), n).unwrap();
    assert_eq!(a.offset_counts(), b.offset_counts());
    assert_eq!(a.gain_error(), b.gain_error());
    assert_ne!(a.offset_counts(), c.offset_counts());
    assert_eq!(a.offset_counts()[0], 0.0);
    let sd = |v: &[f64]| (v[1..].iter().map(|x| x * x).sum::<f64>() / (v.len() - 1) as f64).sqrt();
    assert!(
        (sd(a.offset_counts()) - 4.0).abs() < 0.2,
        "{}",
        sd(a.offset_counts())
    );
    assert!(
        (sd(a.gain_error()) - 0.01).abs() < 0.0005,
        "{}",
        sd(a.gain_error())
    );
    // The calibration does not depend on the noise level.
    let noisy = Sensors::new(
        &SensorSettings {
            angle_noise_counts: 2.0,
            ..spread(5)
        },
        n,
    )
    .unwrap();
    assert_eq!(noisy.offset_counts(), a.offset_counts());
}

#[test]
fn bad_settings_name_the_field() {
    let cases = [
        (
            settings(|s| s.angle_noise_counts = -1.0),
            SensorField::AngleNoise,
        ),
        (
            settings(|s| s.touch_threshold_n = -0.1),
            SensorField::TouchThreshold,
        ),
        (
            settings(|s| s.touch_debounce_samples = 0),
            SensorField::TouchDebounce,
        ),
        (
            settings(|s| s.sample_rate_hz = Some(0.0)),
            SensorField::SampleRate,
        ),
        (
            settings(|s| s.gain_error = CalibrationError::PerJoint(vec![0.0, -1.0])),
            SensorField::Gain,
        ),
        (
            settings(|s| s.offset_counts = CalibrationError::Spread(f64::NAN)),
            SensorField::Offset,
        ),
    ];
    for (s, field) in cases {
        match Sensors::new(&s, 2) {
            Err(SensorError::OutOfRange { field: f, .. }) => assert_eq!(f, field),
            other => panic!("{field}: {other:?}"),
        }
    }
    let wrong = settings(|s| s.offset_counts = CalibrationError::PerJoint(vec![0.0]));
    assert_eq!(
        wrong.validate(2),
        Err(SensorError::WrongLength {
            field: SensorField::Offset,
            expected: 2,
            actual: 1
        })
    );
    assert!(SensorSettings::IDEAL.is_ideal());
    assert!(settings(|s| s.seed = 99).is_ideal());
    assert!(!settings(|s| s.sample_rate_hz = Some(100.0)).is_ideal());
}

proptest! {
    /// Ideal sensors report exactly the 12-bit angles of `sensed_theta_rad`, and exactly the
    /// touch bits of `touch_bits_from_contacts`, sample after sample.
    #[test]
    fn ideal_sensors_read_the_ideal_values_exactly(
        theta in prop::collection::vec(-3.2_f64..3.2, 2..12),
        touches in prop::collection::vec((0_usize..12, 0.0_f64..=1.0, 0.0_f64..1.0), 0..8),
    ) {
        let n = theta.len() - 1;
        let mut sensors = Sensors::new(&SensorSettings::IDEAL, n).unwrap();
        let (mut got, mut want) = (vec![0.0; n + 1], vec![0.0; n + 1]);
        let contacts: Vec<Contact> = touches
            .iter()
            .map(|&(link, s, f)| contact(link % (n + 1), s, f))
            .collect();
        let chain: Vec<ChainContact> = contacts.iter().map(Contact::chain_contact).collect();
        let (mut bits, mut want_bits) = (vec![0_u8; n + 1], vec![0_u8; n + 1]);
        for _ in 0..3 {
            prop_assert!(sensors.is_sample_due(0.0));
            sensors.sense_angles_rad(&theta, &mut got).unwrap();
            sensed_theta_rad(&theta, &mut want).unwrap();
            prop_assert_eq!(
                got.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                want.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
            );
            sensors.sense_touch(&contacts, &mut bits).unwrap();
            touch_bits_from_contacts(&chain, &mut want_bits).unwrap();
            prop_assert_eq!(&bits, &want_bits);
        }
    }
}

#[test]
fn a_wide_gain_spread_draws_only_gains_above_minus_one() {
    // A spread of 2 would put a third of plain Gaussian draws at or below -1 (a reading that
    // shrinks as the angle grows); the draws are truncated above -1.
    let wide = settings(|s| {
        s.gain_error = CalibrationError::Spread(2.0);
        s.seed = 11;
    });
    let sensors = Sensors::new(&wide, 3000).unwrap();
    let gains = &sensors.gain_error()[1..];
    assert!(gains.iter().all(|&g| g > -1.0));
    // Still spread out: many beyond +1.
    assert!(gains.iter().filter(|&&g| g > 1.0).count() > 500);
}
