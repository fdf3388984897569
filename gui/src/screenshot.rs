//! The check CI runs on a screenshot of the running app (`scripts/monitor-screenshot`): is
//! the chain drawn, or is the window blank?
//!
//! It counts the pixels of the measured chain's colour ([`CHAIN_COLOUR`], within a small
//! tolerance for anti-aliasing) in the chain panel's part of the window: right of the side
//! panel (the left quarter) and above the plots (the top 60 %). A drawn chain of nine 40 mm
//! links covers thousands of them along a stretch hundreds of pixels long; a blank or
//! half-drawn window has none.

use crate::panels::chain::CHAIN_COLOUR;

/// Chain-coloured pixels required.
pub const MIN_CHAIN_PIXELS: usize = 400;
/// The chain-coloured pixels must span at least this many pixels (width or height).
pub const MIN_CHAIN_EXTENT_PX: u32 = 100;
/// Per-channel tolerance around [`CHAIN_COLOUR`].
const TOLERANCE: i32 = 40;

/// What the check found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ScreenshotReport {
    /// The image's size, pixels.
    pub size_px: (u32, u32),
    /// Chain-coloured pixels in the chain panel's area.
    pub chain_pixels: usize,
    /// Their bounding box `(x0, y0, x1, y1)`, if any.
    pub chain_box_px: Option<(u32, u32, u32, u32)>,
}

impl ScreenshotReport {
    /// Whether the chain is drawn: enough pixels of its colour, spread along a chain's length.
    pub fn chain_drawn(&self) -> bool {
        self.chain_pixels >= MIN_CHAIN_PIXELS
            && self
                .chain_box_px
                .is_some_and(|(x0, y0, x1, y1)| (x1 - x0).max(y1 - y0) >= MIN_CHAIN_EXTENT_PX)
    }
}

/// Decodes a PNG (8-bit RGB or RGBA) and looks for the chain.
pub fn check_png(bytes: &[u8]) -> Result<ScreenshotReport, String> {
    let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    let mut reader = decoder.read_info().map_err(|e| format!("not a PNG: {e}"))?;
    let size = reader
        .output_buffer_size()
        .ok_or("the PNG is too large to decode")?;
    let mut buffer = vec![0; size];
    let info = reader
        .next_frame(&mut buffer)
        .map_err(|e| format!("the PNG does not decode: {e}"))?;
    let channels = match (info.color_type, info.bit_depth) {
        (png::ColorType::Rgba, png::BitDepth::Eight) => 4,
        (png::ColorType::Rgb, png::BitDepth::Eight) => 3,
        other => {
            return Err(format!(
                "unsupported PNG format {other:?}; expected 8-bit RGB(A)"
            ));
        }
    };
    Ok(scan(
        &buffer,
        info.width,
        info.height,
        info.line_size,
        channels,
    ))
}

fn scan(
    buffer: &[u8],
    width: u32,
    height: u32,
    stride: usize,
    channels: usize,
) -> ScreenshotReport {
    let [r, g, b, _] = CHAIN_COLOUR.to_array();
    let target = [i32::from(r), i32::from(g), i32::from(b)];
    let (x_from, y_to) = (width / 4, height * 3 / 5);
    let mut count = 0;
    let mut bbox: Option<(u32, u32, u32, u32)> = None;
    for y in 0..y_to {
        let row = &buffer[y as usize * stride..];
        for x in x_from..width {
            let p = &row[x as usize * channels..x as usize * channels + 3];
            let close = p
                .iter()
                .zip(target)
                .all(|(&c, t)| (i32::from(c) - t).abs() <= TOLERANCE);
            if close {
                count += 1;
                bbox = Some(match bbox {
                    None => (x, y, x, y),
                    Some((x0, y0, x1, y1)) => (x0.min(x), y0.min(y), x1.max(x), y1.max(y)),
                });
            }
        }
    }
    ScreenshotReport {
        size_px: (width, height),
        chain_pixels: count,
        chain_box_px: bbox,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(width: u32, height: u32, draw: impl Fn(u32, u32) -> bool) -> Vec<u8> {
        let mut rgb = Vec::new();
        let [r, g, b, _] = CHAIN_COLOUR.to_array();
        for y in 0..height {
            for x in 0..width {
                rgb.extend(if draw(x, y) { [r, g, b] } else { [27, 27, 27] });
            }
        }
        let mut out = Vec::new();
        let mut encoder = png::Encoder::new(&mut out, width, height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().unwrap();
        writer.write_image_data(&rgb).unwrap();
        writer.finish().unwrap();
        out
    }

    #[test]
    fn a_drawn_chain_passes_a_blank_window_fails() {
        // A 4 px thick diagonal in the chain panel's area.
        let chain = image(1280, 800, |x, y| {
            (400..900).contains(&x) && (i64::from(y) - (400 - i64::from(x - 400) / 2)).abs() < 2
        });
        let report = check_png(&chain).unwrap();
        assert!(report.chain_drawn(), "{report:?}");
        let blank = check_png(&image(1280, 800, |_, _| false)).unwrap();
        assert_eq!(blank.chain_pixels, 0);
        assert!(!blank.chain_drawn());
        // The same colour only in the side panel (a button, say) does not count.
        let side = check_png(&image(1280, 800, |x, y| x < 300 && y < 100)).unwrap();
        assert!(!side.chain_drawn(), "{side:?}");
        assert!(check_png(b"not a png").is_err());
    }
}
