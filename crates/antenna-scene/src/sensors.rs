//! `[sensors]`: the robot's sensors as they are (thesis 2.3.1, 4.2.2; issue #18): Hall angle
//! noise, per-joint calibration offset and gain errors, the touch switches' force threshold
//! and debounce, and the rate at which the robot samples, seeded. Unset keys take
//! [`SensorSettings::IDEAL`]'s values; without the table the sensors are ideal and a sweep's
//! mapping is the 12-bit angles and the touch bits of every step.
//!
//! Every value is checked by sim-core's own [`SensorSettings::validate`], and its error is
//! put at the value that caused it.

use std::fmt;
use std::ops::Range;

use serde::de::{self, Deserializer, SeqAccess, Visitor};
use serde::{Deserialize, Serialize, Serializer};
use sim_core::{CalibrationError, SensorError, SensorField, SensorSettings};
use toml::Spanned;

use super::source::{Source, count};
use crate::error::SceneError;

const SENSORS: &str = "[sensors]";

/// Most agreeing raw reads a touch switch's debouncer may ask for.
pub const MAX_DEBOUNCE_SAMPLES: usize = 1_000_000;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawSensors {
    angle_noise_counts: Option<Spanned<f64>>,
    offset_counts: Option<Spanned<CalibrationValue>>,
    gain_error: Option<Spanned<CalibrationValue>>,
    touch_threshold_n: Option<Spanned<f64>>,
    touch_debounce_samples: Option<Spanned<i64>>,
    sample_rate_hz: Option<Spanned<f64>>,
    seed: Option<Spanned<i64>>,
    hair_tip_points: Option<Spanned<bool>>,
}

/// `offset_counts`, `gain_error`: a number (the spread drawn per joint) or a list (one value
/// per joint), as sim-core's [`CalibrationError`]. The one "number or list" calibration value
/// of the toolkit: any configuration that carries a calibration error reads it with this type
/// (it serializes back to the same number or list).
///
/// ```
/// use antenna_scene::sensors::CalibrationValue;
/// use sim_core::CalibrationError;
///
/// #[derive(serde::Deserialize)]
/// struct T {
///     offset_counts: CalibrationValue,
///     gain_error: CalibrationValue,
/// }
/// let t: T = toml::from_str("offset_counts = 3\ngain_error = [0.01, -0.02]").unwrap();
/// assert_eq!(t.offset_counts.0, CalibrationError::Spread(3.0));
/// assert_eq!(t.gain_error.0, CalibrationError::PerJoint(vec![0.01, -0.02]));
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationValue(pub CalibrationError);

impl Serialize for CalibrationValue {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        match &self.0 {
            CalibrationError::Spread(spread) => serializer.serialize_f64(*spread),
            CalibrationError::PerJoint(values) => values.serialize(serializer),
        }
    }
}

impl<'de> Deserialize<'de> for CalibrationValue {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct CalibrationVisitor;
        impl<'de> Visitor<'de> for CalibrationVisitor {
            type Value = CalibrationValue;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                write!(
                    f,
                    "a number (the spread drawn per joint) or a list of one number per \
                     flexible joint"
                )
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<CalibrationValue, E> {
                Ok(CalibrationValue(CalibrationError::Spread(v)))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<CalibrationValue, E> {
                Ok(CalibrationValue(CalibrationError::Spread(v as f64)))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<CalibrationValue, E> {
                Ok(CalibrationValue(CalibrationError::Spread(v as f64)))
            }
            fn visit_seq<A: SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> Result<CalibrationValue, A::Error> {
                let mut values = Vec::new();
                while let Some(v) = seq.next_element::<f64>()? {
                    values.push(v);
                }
                Ok(CalibrationValue(CalibrationError::PerJoint(values)))
            }
        }
        deserializer.deserialize_any(CalibrationVisitor)
    }
}

impl RawSensors {
    /// The settings for a chain of `n` flexible joints; errors are put at the offending value
    /// (at the table for a setting that was not written, which the defaults never are).
    pub(crate) fn validate(
        &self,
        source: &Source<'_>,
        table_span: Range<usize>,
        n: usize,
    ) -> Result<SensorSettings, SceneError> {
        let mut settings = SensorSettings::IDEAL;
        if let Some(v) = &self.angle_noise_counts {
            settings.angle_noise_counts = *v.get_ref();
        }
        if let Some(v) = &self.offset_counts {
            settings.offset_counts = v.get_ref().0.clone();
        }
        if let Some(v) = &self.gain_error {
            settings.gain_error = v.get_ref().0.clone();
        }
        if let Some(v) = &self.touch_threshold_n {
            settings.touch_threshold_n = *v.get_ref();
        }
        if let Some(v) = &self.touch_debounce_samples {
            let samples = count(
                source,
                SENSORS,
                "touch_debounce_samples",
                v,
                1,
                MAX_DEBOUNCE_SAMPLES,
            )?;
            settings.touch_debounce_samples = u32::try_from(samples).unwrap_or(u32::MAX);
        }
        if let Some(v) = &self.sample_rate_hz {
            settings.sample_rate_hz = Some(*v.get_ref());
        }
        if let Some(v) = &self.seed {
            settings.seed = u64::try_from(*v.get_ref()).map_err(|_| {
                source.invalid(
                    v.span(),
                    SENSORS,
                    "seed",
                    format!("{} must be >= 0", v.get_ref()),
                )
            })?;
        }
        if let Some(v) = &self.hair_tip_points {
            settings.hair_tip_points = *v.get_ref();
        }
        settings
            .validate(n)
            .map_err(|e| self.located(source, table_span, &e))?;
        Ok(settings)
    }

    /// Where `field` is written in the file.
    fn span_of(&self, field: SensorField) -> Option<Range<usize>> {
        match field {
            SensorField::AngleNoise => self.angle_noise_counts.as_ref().map(Spanned::span),
            SensorField::Offset => self.offset_counts.as_ref().map(Spanned::span),
            SensorField::Gain => self.gain_error.as_ref().map(Spanned::span),
            SensorField::TouchThreshold => self.touch_threshold_n.as_ref().map(Spanned::span),
            SensorField::TouchDebounce => self.touch_debounce_samples.as_ref().map(Spanned::span),
            SensorField::SampleRate => self.sample_rate_hz.as_ref().map(Spanned::span),
        }
    }

    /// sim-core's error as a scene error at the value, naming the key.
    fn located(
        &self,
        source: &Source<'_>,
        table_span: Range<usize>,
        e: &SensorError,
    ) -> SceneError {
        let (field, reason) = match e {
            SensorError::OutOfRange {
                field,
                value,
                expected,
            } => {
                let reason = if expected.starts_with("every") {
                    format!("has {value}; {expected}")
                } else {
                    format!("{value} {expected}")
                };
                (*field, reason)
            }
            SensorError::WrongLength {
                field,
                expected,
                actual,
            } => (
                *field,
                format!(
                    "has {actual} value(s); expected {expected} (one per flexible joint, \
                     links - 1), or one number: the spread drawn per joint"
                ),
            ),
        };
        let span = self.span_of(field).unwrap_or(table_span);
        source.invalid(span, SENSORS, field.key(), reason)
    }
}
