//! Oversampling the 10-bit ADC to a 12-bit angle, and the rail check on the same conversions.

/// Conversions summed into one angle sample.
pub const OVERSAMPLE_COUNT: usize = 16;

/// The bits of one conversion: the ADC has 10.
pub const ADC_MASK: u16 = 0x03FF;

/// The 12-bit angle from 16 consecutive conversions: each masked to 10 bits, summed, and the
/// sum shifted right by 2, giving 0..=4092.
///
/// ```
/// use firmware_segment::oversample;
/// assert_eq!(oversample(&[512; 16]), 2048);
/// assert_eq!(oversample(&[1023; 16]), 4092);
/// // Bits above the 10 of the ADC are ignored.
/// assert_eq!(oversample(&[0xFC00 | 512; 16]), 2048);
/// ```
pub fn oversample(samples: &[u16; OVERSAMPLE_COUNT]) -> u16 {
    // 16 * 1023 = 16368 fits a u16: no overflow is possible.
    let sum: u16 = samples.iter().map(|&s| s & ADC_MASK).sum();
    sum >> 2
}

/// Whether any of the 16 conversions (masked to 10 bits) sits on a rail, 0 or 1023: the Hall
/// sensor's diagnostic clamp or a broken wire.
///
/// ```
/// use firmware_segment::adc_fault;
/// let mut samples = [512; 16];
/// assert!(!adc_fault(&samples));
/// samples[7] = 1023;
/// assert!(adc_fault(&samples));
/// ```
pub fn adc_fault(samples: &[u16; OVERSAMPLE_COUNT]) -> bool {
    samples
        .iter()
        .any(|&s| matches!(s & ADC_MASK, 0 | ADC_MASK))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sum_of_sixteen_shifted_by_two() {
        let mut samples = [0u16; 16];
        for (i, s) in samples.iter_mut().enumerate() {
            *s = 100 + i as u16;
        }
        // sum = 1600 + 120 = 1720, >> 2 = 430
        assert_eq!(oversample(&samples), 430);
        assert_eq!(oversample(&[0; 16]), 0);
        assert_eq!(oversample(&[0xFFFF; 16]), 4092);
    }

    #[test]
    fn rails_after_masking_are_faults() {
        assert!(adc_fault(&[0; 16]));
        let mut samples = [1; 16];
        assert!(!adc_fault(&samples));
        samples[15] = 0x0400; // masks to 0
        assert!(adc_fault(&samples));
        samples[15] = 0xFBFF; // masks to 1023
        assert!(adc_fault(&samples));
        samples[15] = 1022;
        assert!(!adc_fault(&samples));
    }
}
