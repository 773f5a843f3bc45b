//! What every picture shares: the bundled font, the PNG image, tick labels and ranges.

use std::path::Path;
use std::sync::OnceLock;

use plotters::style::FontStyle;

use crate::error::EngineError;
use crate::output::write_output;

/// The font family name under which the bundled font is registered with plotters.
const FAMILY: &str = "sdg-sans";
/// DejaVu Sans (Bitstream Vera license, `engine/assets/DejaVuSans-LICENSE.txt`).
const FONT: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");

/// Registers the bundled font with plotters (once per process).
pub(super) fn font_family() -> Result<&'static str, EngineError> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED
        .get_or_init(|| plotters::style::register_font(FAMILY, FontStyle::Normal, FONT).is_ok());
    if ok {
        Ok(FAMILY)
    } else {
        Err(EngineError::Plot("the bundled font does not parse".into()))
    }
}

/// Font size in pixels for an image of `size` (width, height): readable from 300 to 3000 px.
pub(super) fn font_px(size: (u32, u32)) -> f64 {
    (f64::from(size.0.min(size.1)) / 45.0).clamp(10.0, 40.0)
}

/// A plotters error as a plot error.
pub(super) fn plot_error(e: impl std::fmt::Display) -> EngineError {
    EngineError::Plot(e.to_string())
}

/// An RGB image, 8 bits per channel, rows top to bottom.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Image {
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// `3 * width * height` bytes.
    pub rgb: Vec<u8>,
}

impl Image {
    /// A white image; `Err` when a side is zero or the buffer would not fit in memory.
    pub(super) fn white(size: (u32, u32)) -> Result<Self, EngineError> {
        let (width, height) = size;
        let len = (width as usize)
            .checked_mul(height as usize)
            .and_then(|n| n.checked_mul(3))
            .filter(|&n| n > 0)
            .ok_or_else(|| EngineError::Plot(format!("cannot draw a {width}x{height} image")))?;
        Ok(Self {
            width,
            height,
            rgb: vec![255; len],
        })
    }

    /// This image with `below` under it; `below` must be as wide.
    pub fn above(mut self, below: Image) -> Image {
        assert_eq!(self.width, below.width, "stacked images are equally wide");
        self.height += below.height;
        self.rgb.extend_from_slice(&below.rgb);
        self
    }

    /// The pixel at column `x`, row `y` (from the top).
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 3] {
        let i = 3 * (y as usize * self.width as usize + x as usize);
        [self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]]
    }

    /// The image encoded as PNG.
    pub fn to_png(&self) -> Result<Vec<u8>, EngineError> {
        let mut bytes = Vec::new();
        let mut encoder = png::Encoder::new(&mut bytes, self.width, self.height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().map_err(plot_error)?;
        writer.write_image_data(&self.rgb).map_err(plot_error)?;
        writer.finish().map_err(plot_error)?;
        Ok(bytes)
    }

    /// Writes the image as PNG to `path` through a temporary file and a rename; the folder must
    /// exist (a run's folder removed under it is an error, not made again).
    pub fn write_png(&self, path: &Path) -> Result<(), EngineError> {
        let name = path
            .file_name()
            .and_then(|n| n.to_str())
            .ok_or_else(|| EngineError::Plot(format!("{}: not a file name", path.display())))?;
        let dir = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        write_output(dir, name, &self.to_png()?).map(drop)
    }
}

/// Makes the folder of `path`, a picture `sdg plot` is asked to write (`--out`).
pub(super) fn make_folder(path: &Path) -> Result<(), EngineError> {
    match path.parent().filter(|p| !p.as_os_str().is_empty()) {
        Some(dir) => std::fs::create_dir_all(dir).map_err(|e| EngineError::io(dir, e)),
        None => Ok(()),
    }
}

/// A compact label for a tick value: four significant digits at most, scientific notation
/// outside `[1e-3, 1e5)`, no float noise (`0.30000000000000004` is `0.3`).
pub fn tick_label(v: f64) -> String {
    label_with_digits(v, 4)
}

/// [`tick_label`] with enough significant digits to tell apart ticks about a tenth of `span`
/// apart (an axis from 2.9011 to 2.9013 needs six), at most twelve.
pub fn tick_label_within(v: f64, span: f64) -> String {
    let digits = if span > 0.0 && span.is_finite() && v.is_finite() {
        ((v.abs().max(span) / span).log10().ceil() as i32 + 2).clamp(4, 12) as usize
    } else {
        4
    };
    label_with_digits(v, digits)
}

/// `v` with `digits` significant digits at most (trailing zeros dropped).
pub(super) fn label_with_digits(v: f64, digits: usize) -> String {
    if !v.is_finite() {
        return String::new();
    }
    let a = v.abs();
    if a < 1e-300 {
        return "0".into();
    }
    if (1e-3..1e5).contains(&a) {
        let decimals = (digits as i32 - 1 - a.log10().floor() as i32).max(0) as usize;
        let s = format!("{v:.decimals$}");
        let s = if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        };
        if s == "-0" { "0".into() } else { s }
    } else {
        let s = format!("{v:.prec$e}", prec = digits - 1);
        let (mantissa, exponent) = s.split_once('e').unwrap_or((&s, "0"));
        let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
        format!("{mantissa}e{exponent}")
    }
}

/// The smallest and largest finite value of `values`, or `None` when there is none.
pub(super) fn finite_range(values: impl IntoIterator<Item = f64>) -> Option<(f64, f64)> {
    values
        .into_iter()
        .filter(|v| v.is_finite())
        .fold(None, |acc, v| match acc {
            None => Some((v, v)),
            Some((lo, hi)) => Some((lo.min(v), hi.max(v))),
        })
}

/// `(lo, hi)` widened to a non-empty interval when `lo == hi`.
pub(super) fn widen(range: (f64, f64)) -> (f64, f64) {
    let (lo, hi) = range;
    if hi > lo {
        return range;
    }
    let d = if lo == 0.0 { 1.0 } else { 0.01 * lo.abs() };
    (lo - d, hi + d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_labels_are_compact() {
        assert_eq!(tick_label(0.30000000000000004), "0.3");
        assert_eq!(tick_label(2.0), "2");
        assert_eq!(tick_label(-0.0), "0");
        assert_eq!(tick_label(12.5), "12.5");
        assert_eq!(tick_label(1.5e6), "1.5e6");
        assert_eq!(tick_label(-2.0e-7), "-2e-7");
        assert_eq!(tick_label(0.00123456), "0.001235");
        assert_eq!(tick_label(f64::NAN), "");
        // Ticks a tenth of the span apart stay apart.
        assert_eq!(tick_label(2.9012), "2.901");
        assert_eq!(tick_label_within(2.9012, 4e-4), "2.9012");
        assert_eq!(tick_label_within(2.90125, 4e-4), "2.90125");
        assert_eq!(tick_label_within(12.5, 10.0), "12.5");
        assert_eq!(tick_label_within(1.5e6, 1e6), "1.5e6");
        assert_eq!(tick_label_within(1.000001e6, 1.0), "1.000001e6");
    }

    #[test]
    fn the_bundled_font_registers() {
        assert_eq!(font_family().unwrap(), FAMILY);
    }

    #[test]
    fn ranges_skip_non_finite_values_and_widen() {
        assert_eq!(
            finite_range([f64::NAN, 2.0, -1.0, f64::INFINITY]),
            Some((-1.0, 2.0))
        );
        assert_eq!(finite_range([f64::NAN]), None);
        assert_eq!(widen((0.0, 0.0)), (-1.0, 1.0));
        assert_eq!(widen((2.0, 2.0)), (1.98, 2.02));
    }
}
