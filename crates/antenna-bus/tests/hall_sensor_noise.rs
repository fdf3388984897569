//! The simulated segments' Hall sensors as they are (issue #18), read over the bus as the host
//! reads them: the noise on each conversion comes out of the firmware's oversampling with the
//! configured standard deviation in twelve-bit counts, the calibration offset and gain move
//! the mean as specified, and one seed gives one run.
#![allow(clippy::unwrap_used)]

use antenna_bus::{HallErrors, HallSensor, SimBus, SimSegment};
use antenna_protocol::{Calibration, Direction, RAD_PER_COUNT, SampleWord};
use embedded_hal::i2c::I2c;

const ADDRESS: u8 = 0x21;

/// Samples read for each statistic.
const SAMPLES: usize = 20_000;

/// The truncation of the firmware's `sum >> 2`: a noisy reading's mean lies this far below
/// the noise-free count (the mean of the two bits dropped, 0, 1/4, 1/2 and 3/4 alike).
const TRUNCATION_BIAS_COUNTS: f64 = 0.375;

/// The variance the rounding of the conversions (1/12) and of the shift (5/64, the variance
/// of the bits dropped) adds to the reading's, counts squared.
const ROUNDING_VARIANCE_COUNTS2: f64 = 1.0 / 12.0 + 5.0 / 64.0;

fn segment(calibration: Calibration, errors: HallErrors, seed: u64, stream: u64) -> SimSegment {
    segment_at(ADDRESS, calibration, errors, seed, stream)
}

fn segment_at(
    address: u8,
    calibration: Calibration,
    errors: HallErrors,
    seed: u64,
    stream: u64,
) -> SimSegment {
    SimSegment::new(address, calibration)
        .with_hall_sensor(HallSensor::new(errors, seed, stream).unwrap())
}

fn noisy(noise_counts: f64) -> HallErrors {
    HallErrors {
        noise_counts,
        ..HallErrors::IDEAL
    }
}

/// `samples` words of segment `index` with its joint at `angle_rad`, each a new sampling
/// period, read over the bus.
fn words(bus: &mut SimBus, index: usize, angle_rad: f64, samples: usize) -> Vec<SampleWord> {
    let address = bus.segments()[index].address();
    bus.segment_mut(index).unwrap().set_angle_rad(angle_rad);
    (0..samples)
        .map(|_| {
            bus.sample_all();
            let mut bytes = [0u8; 3];
            bus.read(address, &mut bytes).unwrap();
            SampleWord::from_read_with_pec(address, bytes).unwrap()
        })
        .collect()
}

/// Mean and standard deviation of the words' counts.
fn statistics(words: &[SampleWord]) -> (f64, f64) {
    let counts: Vec<f64> = words.iter().map(|w| f64::from(w.angle_counts())).collect();
    let n = counts.len() as f64;
    let mean = counts.iter().sum::<f64>() / n;
    let variance = counts.iter().map(|c| (c - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, variance.sqrt())
}

#[test]
fn the_oversampled_reading_has_the_noise_of_each_conversion_in_twelve_bit_counts() {
    let calibration = Calibration::new(1500, Direction::CounterClockwise);
    let angle_rad = 0.4;
    let true_counts = f64::from(calibration.counts_for_angle(angle_rad));
    for noise_counts in [0.5, 2.0, 5.0] {
        let mut bus = SimBus::new(vec![segment(calibration, noisy(noise_counts), 11, 0)]);
        let (mean, sd) = statistics(&words(&mut bus, 0, angle_rad, SAMPLES));
        // The noise itself, and what the rounding adds to it.
        let expected_sd = (noise_counts * noise_counts + ROUNDING_VARIANCE_COUNTS2).sqrt();
        eprintln!(
            "noise {noise_counts} counts: sd {sd:.4} (expected {expected_sd:.4}), mean - true \
             count {:.4}",
            mean - true_counts
        );
        assert!(
            (sd - expected_sd).abs() <= 0.03 * expected_sd,
            "noise {noise_counts}: sd {sd}, expected {expected_sd}"
        );
        // Against the setting alone: within 0.15 counts plus 2 %.
        assert!(
            (sd - noise_counts).abs() <= 0.15 + 0.02 * noise_counts,
            "noise {noise_counts}: sd {sd}"
        );
        // The mean: the true count less the truncation of the shift, to four standard
        // errors and 0.02 counts.
        let tolerance = 0.02 + 4.0 * expected_sd / (SAMPLES as f64).sqrt();
        assert!(
            (mean - (true_counts - TRUNCATION_BIAS_COUNTS)).abs() <= tolerance,
            "noise {noise_counts}: mean {mean}, true count {true_counts}"
        );
    }
}

#[test]
fn without_noise_every_reading_is_the_count() {
    let calibration = Calibration::new(100, Direction::Clockwise);
    let mut bus = SimBus::new(vec![segment(calibration, HallErrors::IDEAL, 5, 0)]);
    for angle_rad in [-0.7, -0.01, 0.0, 0.3, 1.2] {
        let expected = calibration.counts_for_angle(angle_rad);
        assert!(
            words(&mut bus, 0, angle_rad, 5)
                .iter()
                .all(|w| w.angle_counts() == expected)
        );
    }
}

#[test]
fn the_offset_and_the_gain_move_the_mean_as_specified() {
    let angle_rad = 0.5;
    for direction in [Direction::CounterClockwise, Direction::Clockwise] {
        let calibration = Calibration::new(2000, direction);
        for (offset_counts, gain_error) in [(10.0, 0.0), (-25.0, 0.0), (0.0, 0.05), (7.0, -0.1)] {
            let errors = HallErrors {
                noise_counts: 0.0,
                offset_counts,
                gain_error,
            };
            // The angle the host decodes is theta (1 + g) + o q, to a count.
            let sensed_rad = angle_rad * (1.0 + gain_error) + offset_counts * RAD_PER_COUNT;
            let expected = calibration.counts_for_angle(sensed_rad);
            let mut bus = SimBus::new(vec![segment(calibration, errors, 1, 0)]);
            let word = words(&mut bus, 0, angle_rad, 1)[0];
            assert_eq!(word.angle_counts(), expected, "{errors:?} {direction:?}");
            let decoded_rad = calibration.angle_rad(word.angle_counts());
            assert!((decoded_rad - sensed_rad).abs() <= RAD_PER_COUNT / 2.0 + 1e-12);
            if gain_error == 0.0 {
                let ideal = calibration.angle_rad(calibration.counts_for_angle(angle_rad));
                let moved = (decoded_rad - ideal) / RAD_PER_COUNT;
                assert!((moved - offset_counts).abs() < 1e-9, "{moved}");
            }
            // With noise, the mean is the moved count (less the shift's truncation).
            let mut bus = SimBus::new(vec![segment(
                calibration,
                HallErrors {
                    noise_counts: 2.0,
                    ..errors
                },
                2,
                0,
            )]);
            let (mean, _) = statistics(&words(&mut bus, 0, angle_rad, 5_000));
            let shifted = f64::from(expected) - TRUNCATION_BIAS_COUNTS;
            assert!(
                (mean - shifted).abs() < 0.15,
                "{errors:?} {direction:?}: mean {mean}, expected {shifted}"
            );
        }
    }
}

#[test]
fn one_seed_gives_one_run_another_seed_another_and_each_segment_its_own_stream() {
    let calibration = Calibration::new(1700, Direction::CounterClockwise);
    let run = |seed: u64| {
        let mut bus = SimBus::new(vec![segment(calibration, noisy(2.0), seed, 0)]);
        words(&mut bus, 0, 0.2, 200)
    };
    assert_eq!(run(7), run(7));
    assert_ne!(run(7), run(8));
    // Segment 0's readings do not depend on the segments after it (nor on their number).
    let alone = run(7);
    let mut crowded = SimBus::new(vec![
        segment(calibration, noisy(2.0), 7, 0),
        segment_at(0x22, calibration, noisy(2.0), 7, 1),
        segment_at(0x23, calibration, noisy(2.0), 7, 2),
    ]);
    assert_eq!(words(&mut crowded, 0, 0.2, 200), alone);
    // Two streams of one seed are two runs.
    assert_ne!(words(&mut crowded, 1, 0.2, 200), alone);
}
