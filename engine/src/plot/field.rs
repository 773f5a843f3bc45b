//! A scalar field on triangles: filled with viridis by an in-tree rasterizer (100k triangles in a
//! few milliseconds), with axes in mm, a colour bar and optional edge and segment overlays drawn
//! on top; frame and text by plotters.

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::canvas::{Image, finite_range, font_family, font_px, plot_error, tick_label, widen};
use crate::error::EngineError;

/// The scalar to colour: one value per point (interpolated linearly on each triangle) or one per
/// triangle (flat). Non-finite values leave their triangles unpainted.
#[derive(Clone, Copy, Debug)]
pub enum Values<'a> {
    /// One value per point.
    Points(&'a [f64]),
    /// One value per triangle.
    Cells(&'a [f64]),
}

/// Pixel rectangles of a field picture: columns `x0..x1`, rows `y0..y1` (from the top).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FieldLayout {
    /// The field's plotting area, with the data's aspect ratio (1 mm is as wide as it is high).
    pub field: [u32; 4],
    /// The colour bar, lowest value at the bottom.
    pub colorbar: [u32; 4],
    /// The picture's size (width, height) in pixels: the requested width, and the requested
    /// height less what a wide field leaves empty below its axis labels.
    pub size: (u32, u32),
}

/// A picture of a scalar field on triangles (points in metres, drawn in mm).
///
/// ```no_run
/// # use sdg_engine::plot::{FieldPlot, Values};
/// let points = [[0.0, 0.0], [1e-3, 0.0], [0.0, 1e-3]];
/// let image = FieldPlot::new(&points, &[[0, 1, 2]], Values::Points(&[0.0, 1.0, 2.0]))
///     .title("velocity magnitude (m/s)")
///     .time(Some(1e-6))
///     .render((800, 600))?;
/// # Ok::<(), sdg_engine::EngineError>(())
/// ```
#[derive(Clone, Debug)]
pub struct FieldPlot<'a> {
    points: &'a [[f64; 2]],
    triangles: &'a [[u32; 3]],
    values: Values<'a>,
    title: String,
    time: Option<f64>,
    edges: bool,
    segments: &'a [[[f64; 2]; 2]],
    markers: &'a [[f64; 2]],
    window: Option<[f64; 4]>,
}

/// Line colour of the extra segments (interfaces, cracks): red, absent from viridis.
const SEGMENT_RGB: [u8; 3] = [228, 26, 28];
/// Mesh edges: black at this opacity, visible on both ends of viridis.
const EDGE_ALPHA: f64 = 0.45;
/// Radius of the circles around marked points, pixels (drawn 2 pixels wide, in black).
const MARKER_RADIUS: f64 = 12.0;

impl<'a> FieldPlot<'a> {
    /// The field `values` on `triangles` (indices into `points`, any orientation).
    pub fn new(points: &'a [[f64; 2]], triangles: &'a [[u32; 3]], values: Values<'a>) -> Self {
        Self {
            points,
            triangles,
            values,
            title: String::new(),
            time: None,
            edges: false,
            segments: &[],
            markers: &[],
            window: None,
        }
    }

    /// The title (field name and unit); the time is appended by [`Self::time`].
    pub fn title(mut self, title: &str) -> Self {
        self.title = title.to_string();
        self
    }

    /// The time of the slice, s, shown in us in the title (`None`: no time).
    pub fn time(mut self, time: Option<f64>) -> Self {
        self.time = time.filter(|t| t.is_finite());
        self
    }

    /// Overlay the triangles' edges.
    pub fn edges(mut self, edges: bool) -> Self {
        self.edges = edges;
        self
    }

    /// Segments (ends in m) drawn on top in red, e.g. interfaces or crack faces.
    pub fn segments(mut self, segments: &'a [[[f64; 2]; 2]]) -> Self {
        self.segments = segments;
        self
    }

    /// Points (m) circled in black on top, e.g. where a crack forks.
    pub fn markers(mut self, markers: &'a [[f64; 2]]) -> Self {
        self.markers = markers;
        self
    }

    /// Draw only the part `[xmin, xmax, ymin, ymax]` (m) of the triangles' bounding box
    /// (`None`: all of it); whatever lies outside is clipped.
    pub fn window(mut self, window: Option<[f64; 4]>) -> Self {
        self.window = window;
        self
    }

    /// The full title: the given one with `t = ... us` appended when the time is known.
    fn full_title(&self) -> String {
        match (self.time, self.title.is_empty()) {
            (Some(t), true) => format!("t = {} us", tick_label(t * 1e6)),
            (Some(t), false) => format!("{}, t = {} us", self.title, tick_label(t * 1e6)),
            (None, _) => self.title.clone(),
        }
    }

    /// Checks indices and lengths; returns the bounding box `[xmin, xmax, ymin, ymax]` (m) of
    /// the triangles with finite corners, within the window if one is set.
    fn bounds(&self) -> Result<[f64; 4], EngineError> {
        let n = self.points.len();
        if let Some(t) = self
            .triangles
            .iter()
            .find(|t| t.iter().any(|&i| i as usize >= n))
        {
            return Err(EngineError::Plot(format!(
                "triangle {t:?} refers to a point beyond the {n} given"
            )));
        }
        let (len, want, what) = match self.values {
            Values::Points(v) => (v.len(), n, "points"),
            Values::Cells(v) => (v.len(), self.triangles.len(), "triangles"),
        };
        if len != want {
            return Err(EngineError::Plot(format!("{len} values for {want} {what}")));
        }
        let corners = || {
            self.triangles
                .iter()
                .map(|t| t.map(|i| self.points[i as usize]))
                .filter(|c| c.iter().flatten().all(|x| x.is_finite()))
                .flatten()
        };
        match (
            finite_range(corners().map(|p| p[0])),
            finite_range(corners().map(|p| p[1])),
        ) {
            (Some((x0, x1)), Some((y0, y1))) if x1 > x0 && y1 > y0 => {
                let Some([wx0, wx1, wy0, wy1]) = self.window else {
                    return Ok([x0, x1, y0, y1]);
                };
                let view = [x0.max(wx0), x1.min(wx1), y0.max(wy0), y1.min(wy1)];
                if view[1] > view[0] && view[3] > view[2] {
                    Ok(view)
                } else {
                    Err(EngineError::Plot(format!(
                        "the window {:?} m misses the triangles",
                        [wx0, wx1, wy0, wy1]
                    )))
                }
            }
            (Some(_), Some(_)) => Err(EngineError::Plot(
                "the triangles have no area to draw (all on a line or a point)".into(),
            )),
            _ => Err(EngineError::Plot(
                "nothing to draw: no triangle with finite corners".into(),
            )),
        }
    }

    /// Where the field and the colour bar go in an image of `size` (width, height) pixels.
    pub fn layout(&self, size: (u32, u32)) -> Result<FieldLayout, EngineError> {
        layout(self.bounds()?, size)
    }

    /// The value range of the colour bar: the finite values on drawable triangles.
    fn value_range(&self) -> (f64, f64) {
        let range = match self.values {
            Values::Points(v) => {
                finite_range(self.triangles.iter().flatten().map(|&i| v[i as usize]))
            }
            Values::Cells(v) => finite_range(v.iter().copied()),
        };
        widen(range.unwrap_or((0.0, 1.0)))
    }

    /// Renders the picture into an image of `size` (width, height) pixels, less the empty band
    /// a wide field leaves at the bottom ([`FieldLayout::size`]).
    pub fn render(&self, size: (u32, u32)) -> Result<Image, EngineError> {
        let bounds = self.bounds()?;
        let lay = layout(bounds, size)?;
        let (lo, hi) = self.value_range();
        let mut image = Image::white(size)?;
        let lut = viridis_table();
        let [fx0, _, fx1, fy1] = lay.field;
        let scale = f64::from(fx1 - fx0) / (bounds[1] - bounds[0]);
        let to_px = |p: [f64; 2]| {
            [
                f64::from(fx0) + (p[0] - bounds[0]) * scale,
                f64::from(fy1) - (p[1] - bounds[2]) * scale,
            ]
        };
        let pixels: Vec<[f64; 2]> = self.points.iter().map(|&p| to_px(p)).collect();
        let colour = |v: f64| {
            let t = ((v - lo) / (hi - lo)).clamp(0.0, 1.0);
            lut[(t * 255.0).round() as usize]
        };
        let mut canvas = Canvas {
            image: &mut image,
            clip: lay.field,
        };
        for (k, t) in self.triangles.iter().enumerate() {
            let corners = t.map(|i| pixels[i as usize]);
            match self.values {
                Values::Points(v) => {
                    let vals = t.map(|i| v[i as usize]);
                    if vals.iter().all(|v| v.is_finite()) {
                        canvas.fill_triangle(corners, |w| {
                            colour(w[0] * vals[0] + w[1] * vals[1] + w[2] * vals[2])
                        });
                    }
                }
                Values::Cells(v) if v[k].is_finite() => {
                    let c = colour(v[k]);
                    canvas.fill_triangle(corners, |_| c);
                }
                Values::Cells(_) => {}
            }
        }
        if self.edges {
            for t in self.triangles {
                let c = t.map(|i| pixels[i as usize]);
                for (a, b) in [(c[0], c[1]), (c[1], c[2]), (c[2], c[0])] {
                    canvas.line(a, b, [0, 0, 0], EDGE_ALPHA);
                }
            }
        }
        for s in self.segments {
            let (a, b) = (to_px(s[0]), to_px(s[1]));
            // Two pixels wide: the second line one pixel off across the segment's main axis.
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let off = if dx.abs() >= dy.abs() {
                [0.0, 1.0]
            } else {
                [1.0, 0.0]
            };
            canvas.line(a, b, SEGMENT_RGB, 1.0);
            let shift = |p: [f64; 2]| [p[0] + off[0], p[1] + off[1]];
            canvas.line(shift(a), shift(b), SEGMENT_RGB, 1.0);
        }
        for &m in self.markers {
            let c = to_px(m);
            for radius in [MARKER_RADIUS, MARKER_RADIUS + 1.0] {
                let at = |k: usize| {
                    let phi = std::f64::consts::TAU * k as f64 / 48.0;
                    [c[0] + radius * phi.cos(), c[1] + radius * phi.sin()]
                };
                for k in 0..48 {
                    canvas.line(at(k), at(k + 1), [0, 0, 0], 1.0);
                }
            }
        }
        let [bx0, by0, bx1, by1] = lay.colorbar;
        for y in by0..by1 {
            let t = 1.0 - (f64::from(y - by0) + 0.5) / f64::from(by1 - by0);
            let c = lut[(t * 255.0).round() as usize];
            for x in bx0..bx1 {
                let i = 3 * (y as usize * size.0 as usize + x as usize);
                image.rgb[i..i + 3].copy_from_slice(&c);
            }
        }
        self.draw_frame(&mut image, &lay, bounds, (lo, hi))?;
        // Drawn at the requested size (which sets the font), then cut below the axis labels.
        image.height = lay.size.1;
        image
            .rgb
            .truncate(3 * lay.size.0 as usize * lay.size.1 as usize);
        Ok(image)
    }

    /// Axes, tick labels, colour bar scale and title, drawn by plotters over the pixels.
    fn draw_frame(
        &self,
        image: &mut Image,
        lay: &FieldLayout,
        bounds: [f64; 4],
        (lo, hi): (f64, f64),
    ) -> Result<(), EngineError> {
        let family = font_family()?;
        let size = (image.width, image.height);
        let f = font_px(size);
        let label_area = |x: f64| (x * f).round() as u32;
        let root = BitMapBackend::with_buffer(&mut image.rgb, size).into_drawing_area();
        let [fx0, fy0, fx1, fy1] = lay.field;
        let (x_area, y_area) = (label_area(X_AREA), label_area(Y_AREA));
        let mm = |v: f64| v * 1e3;
        let mut chart = ChartBuilder::on(&root)
            .margin_top(fy0)
            .margin_left(fx0 - y_area)
            .margin_right(size.0 - fx1)
            .margin_bottom(size.1 - fy1 - x_area)
            .x_label_area_size(x_area)
            .y_label_area_size(y_area)
            .build_cartesian_2d(mm(bounds[0])..mm(bounds[1]), mm(bounds[2])..mm(bounds[3]))
            .map_err(plot_error)?;
        let formatter = |v: &f64| tick_label(*v);
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc("x (mm)")
            .y_desc("y (mm)")
            .label_style((family, f))
            .axis_desc_style((family, f))
            .x_label_formatter(&formatter)
            .y_label_formatter(&formatter)
            .draw()
            .map_err(plot_error)?;
        // The colour bar's frame, tick marks and labels (drawn here: plotters' right-hand label
        // alignment estimates text widths and can clip them).
        let [bx0, by0, bx1, by1] = lay.colorbar.map(|v| v as i32);
        root.draw(&Rectangle::new(
            [(bx0 - 1, by0 - 1), (bx1, by1)],
            BLACK.stroke_width(1),
        ))
        .map_err(plot_error)?;
        let style =
            TextStyle::from((family, f).into_font()).pos(Pos::new(HPos::Left, VPos::Center));
        let tick = (0.4 * f).round() as i32;
        for v in nice_ticks(lo, hi) {
            let y = by1 - ((v - lo) / (hi - lo) * f64::from(by1 - by0)).round() as i32;
            root.draw(&PathElement::new([(bx1, y), (bx1 + tick, y)], BLACK))
                .map_err(plot_error)?;
            root.draw_text(&tick_label(v), &style, (bx1 + 2 * tick, y))
                .map_err(plot_error)?;
        }
        let title = self.full_title();
        if !title.is_empty() {
            let style = TextStyle::from((family, 1.2 * f).into_font())
                .pos(Pos::new(HPos::Center, VPos::Center));
            let centre = ((fx0 + fx1) / 2) as i32;
            root.draw_text(&title, &style, (centre, (fy0 / 2) as i32))
                .map_err(plot_error)?;
        }
        root.present().map_err(plot_error)
    }
}

/// Four to eight round values (steps of 1, 2, 2.5 or 5 times a power of ten) in `[lo, hi]`.
fn nice_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let raw = (hi - lo) / 6.0;
    let power = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 2.5, 5.0, 10.0]
        .into_iter()
        .map(|m| m * power)
        .find(|&s| s >= raw)
        .unwrap_or(10.0 * power);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last).map(|k| k as f64 * step).collect()
}

/// Layout sizes in font heights: title band, x-axis labels, y-axis labels, gap to the colour
/// bar, colour bar width, its labels, right margin.
const TITLE: f64 = 2.6;
const X_AREA: f64 = 3.2;
const Y_AREA: f64 = 4.8;
const BAR_GAP: f64 = 1.2;
const BAR_WIDTH: f64 = 1.2;
const BAR_LABELS: f64 = 5.0;
const RIGHT: f64 = 0.5;

fn layout(bounds: [f64; 4], size: (u32, u32)) -> Result<FieldLayout, EngineError> {
    let f = font_px(size);
    let px = |x: f64| (x * f).round();
    let (w, h) = (f64::from(size.0), f64::from(size.1));
    let left = px(Y_AREA) + px(0.6);
    let right = px(BAR_GAP) + px(BAR_WIDTH) + px(BAR_LABELS) + px(RIGHT);
    let (top, bottom) = (px(TITLE), px(X_AREA) + px(0.4));
    let (avail_w, avail_h) = (w - left - right, h - top - bottom);
    if avail_w < 16.0 || avail_h < 16.0 {
        return Err(EngineError::Plot(format!(
            "a {}x{} image leaves no room for the field",
            size.0, size.1
        )));
    }
    let (dx, dy) = (bounds[1] - bounds[0], bounds[3] - bounds[2]);
    let scale = (avail_w / dx).min(avail_h / dy);
    let (fw, fh) = ((dx * scale).floor().max(1.0), (dy * scale).floor().max(1.0));
    let field = [left, top, left + fw, top + fh].map(|v| v as u32);
    let bar_x0 = field[2] + px(BAR_GAP) as u32;
    let colorbar = [bar_x0, field[1], bar_x0 + px(BAR_WIDTH) as u32, field[3]];
    let used = (f64::from(field[3]) + bottom) as u32;
    Ok(FieldLayout {
        field,
        colorbar,
        size: (size.0, used.min(size.1)),
    })
}

/// Pixels drawn into an image, clipped to a rectangle `[x0, y0, x1, y1]`.
struct Canvas<'i> {
    image: &'i mut Image,
    clip: [u32; 4],
}

impl Canvas<'_> {
    /// Fills the pixels whose centres lie in the triangle `c` (pixel coordinates), coloured by
    /// `colour` of their barycentric weights. Shared edges are covered by both triangles, so no
    /// gap shows between neighbours.
    fn fill_triangle(&mut self, c: [[f64; 2]; 3], mut colour: impl FnMut([f64; 3]) -> [u8; 3]) {
        let area =
            (c[1][0] - c[0][0]) * (c[2][1] - c[0][1]) - (c[1][1] - c[0][1]) * (c[2][0] - c[0][0]);
        if area == 0.0 || !area.is_finite() {
            return;
        }
        let [x0, y0, x1, y1] = self.clip.map(f64::from);
        let min = |k: usize| c[0][k].min(c[1][k]).min(c[2][k]);
        let max = |k: usize| c[0][k].max(c[1][k]).max(c[2][k]);
        let (lo_x, hi_x) = (
            (min(0) - 0.5).ceil().max(x0),
            (max(0) - 0.5).floor().min(x1 - 1.0),
        );
        let (lo_y, hi_y) = (
            (min(1) - 0.5).ceil().max(y0),
            (max(1) - 0.5).floor().min(y1 - 1.0),
        );
        if lo_x > hi_x || lo_y > hi_y {
            return;
        }
        // Edge function of the edge opposite corner k, normalized: the barycentric weight.
        let edge = |k: usize, p: [f64; 2]| {
            let (a, b) = (c[(k + 1) % 3], c[(k + 2) % 3]);
            ((b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])) / area
        };
        let eps = -1e-9;
        let width = self.image.width as usize;
        for y in lo_y as u32..=hi_y as u32 {
            for x in lo_x as u32..=hi_x as u32 {
                let p = [f64::from(x) + 0.5, f64::from(y) + 0.5];
                let w = [edge(0, p), edge(1, p), edge(2, p)];
                if w.iter().all(|&w| w >= eps) {
                    let i = 3 * (y as usize * width + x as usize);
                    self.image.rgb[i..i + 3].copy_from_slice(&colour(w));
                }
            }
        }
    }

    /// A one-pixel line from `a` to `b` (pixel coordinates) in `rgb` at opacity `alpha`.
    fn line(&mut self, a: [f64; 2], b: [f64; 2], rgb: [u8; 3], alpha: f64) {
        if !a.iter().chain(&b).all(|v| v.is_finite()) {
            return;
        }
        let steps = (b[0] - a[0])
            .abs()
            .max((b[1] - a[1]).abs())
            .ceil()
            .clamp(1.0, 1e5);
        let [x0, y0, x1, y1] = self.clip.map(f64::from);
        let width = self.image.width as usize;
        for k in 0..=steps as u32 {
            let s = f64::from(k) / steps;
            let (x, y) = (
                (a[0] + s * (b[0] - a[0])).floor(),
                (a[1] + s * (b[1] - a[1])).floor(),
            );
            if x >= x0 && x < x1 && y >= y0 && y < y1 {
                let i = 3 * (y as usize * width + x as usize);
                for (p, &c) in self.image.rgb[i..i + 3].iter_mut().zip(&rgb) {
                    *p = (f64::from(*p) * (1.0 - alpha) + f64::from(c) * alpha).round() as u8;
                }
            }
        }
    }
}

/// Matplotlib's viridis at eleven equally spaced points of [0, 1].
const VIRIDIS: [[u8; 3]; 11] = [
    [68, 1, 84],
    [72, 36, 117],
    [65, 68, 135],
    [53, 95, 141],
    [42, 120, 142],
    [33, 145, 140],
    [34, 168, 132],
    [68, 191, 112],
    [122, 209, 81],
    [189, 223, 38],
    [253, 231, 37],
];

/// Viridis at `t` in [0, 1] (clamped; NaN gives the low end): dark blue-purple to yellow, with
/// monotonically increasing lightness.
pub fn viridis(t: f64) -> [u8; 3] {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let s = t * 10.0;
    let k = (s.floor() as usize).min(9);
    let w = s - k as f64;
    let (a, b) = (VIRIDIS[k], VIRIDIS[k + 1]);
    [0, 1, 2].map(|i| (f64::from(a[i]) + w * (f64::from(b[i]) - f64::from(a[i]))).round() as u8)
}

/// [`viridis`] at 256 levels.
fn viridis_table() -> [[u8; 3]; 256] {
    std::array::from_fn(|i| viridis(i as f64 / 255.0))
}

#[cfg(test)]
mod tests;
