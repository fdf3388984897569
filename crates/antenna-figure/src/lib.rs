//! What every figure in the workspace shares: the font plotters writes text with (the
//! sans-serif egui ships, drawn by ab_glyph, so no system font library is needed) and the PNG
//! encoding of a drawn bitmap. `antenna sweep --plot`, the monitor's exports and the
//! reproductions' figures use it.
//!
//! ```no_run
//! use plotters::prelude::*;
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! antenna_figure::register_font()?;
//! let (w, h) = (320, 200);
//! let mut rgb = vec![0u8; (w * h * 3) as usize];
//! {
//!     let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
//!     root.fill(&WHITE)?;
//!     root.draw(&Text::new("hello", (10, 10), ("sans-serif", 20).into_font()))?;
//!     root.present()?;
//! }
//! antenna_figure::write_png(std::path::Path::new("hello.png"), w, h, &rgb)?;
//! # Ok(())
//! # }
//! ```

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use plotters::style::FontStyle;

/// Why a figure could not be written.
#[derive(Debug, thiserror::Error)]
pub enum FigureError {
    /// plotters has no font to write text with.
    #[error("the figures' font did not load into plotters")]
    Font,
    /// The file could not be written.
    #[error("{}: {source}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The PNG encoder failed.
    #[error("{}: {message}", path.display())]
    Encode {
        /// The file.
        path: PathBuf,
        /// The encoder's message.
        message: String,
    },
}

/// Registers the sans-serif font with plotters (once per process; later calls return the
/// first call's outcome).
///
/// # Errors
/// [`FigureError::Font`] if plotters refuses the font.
pub fn register_font() -> Result<(), FigureError> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let registered = *REGISTERED.get_or_init(|| {
        plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            epaint_default_fonts::UBUNTU_LIGHT,
        )
        .is_ok()
    });
    if registered {
        Ok(())
    } else {
        Err(FigureError::Font)
    }
}

/// Writes `rgb` (`width x height` pixels, 3 bytes each, row by row) to `path` as an 8-bit RGB
/// PNG.
///
/// # Errors
/// [`FigureError::Write`] if the file cannot be created or written, [`FigureError::Encode`]
/// if the encoder fails (e.g. `rgb` is not `width * height * 3` bytes).
pub fn write_png(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<(), FigureError> {
    let encode = |e: png::EncodingError| FigureError::Encode {
        path: path.to_path_buf(),
        message: e.to_string(),
    };
    let file = std::fs::File::create(path).map_err(|source| FigureError::Write {
        path: path.to_path_buf(),
        source,
    })?;
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(encode)?;
    writer.write_image_data(rgb).map_err(encode)?;
    writer.finish().map_err(encode)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    #[test]
    fn a_png_round_trips_and_a_short_buffer_is_an_encode_error() {
        register_font().unwrap();
        let dir = std::env::temp_dir().join(format!("antenna-figure-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("two.png");
        write_png(&path, 2, 1, &[255, 0, 0, 0, 0, 255]).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        assert!(bytes.starts_with(b"\x89PNG\r\n\x1a\n"));
        let err = write_png(&path, 2, 2, &[0; 6]).unwrap_err();
        assert!(matches!(err, FigureError::Encode { .. }), "{err}");
        let missing = dir.join("no-such-dir").join("x.png");
        let err = write_png(&missing, 1, 1, &[0; 3]).unwrap_err();
        assert!(matches!(err, FigureError::Write { .. }), "{err}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
