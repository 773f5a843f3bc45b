//! Line charts: named `(x, y)` series with a legend, e.g. energies against time.

use std::path::Path;

use plotters::prelude::*;

use super::canvas::{
    Image, finite_range, font_family, font_px, plot_error, tick_label_within, widen,
};
use crate::error::EngineError;

/// How a series is drawn.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LineStyle {
    /// A solid line (computed results).
    #[default]
    Solid,
    /// A dashed line (references).
    Dashed,
    /// A thin grey line that takes no colour of the palette: context behind the coloured series
    /// (e.g. the many short branches of a crack network).
    Faint,
    /// A dot at each point, no line (values of separate runs).
    Markers,
}

/// The colour of [`LineStyle::Faint`] series.
const FAINT: RGBColor = RGBColor(170, 170, 170);

/// Series colours, in order (Tableau 10).
const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

#[derive(Clone, Debug)]
struct Series {
    name: String,
    points: Vec<(f64, f64)>,
    style: LineStyle,
}

/// A line chart built series by series.
///
/// ```no_run
/// # use sdg_engine::plot::{LineChart, LineStyle};
/// LineChart::new("crack tip", "time (us)", "position (mm)")
///     .series("computed", &[(0.0, 0.0), (1.0, 2.0)], LineStyle::Solid)
///     .series("LEFM", &[(0.0, 0.0), (1.0, 2.1)], LineStyle::Dashed)
///     .write_png(std::path::Path::new("tip.png"), (900, 600))?;
/// # Ok::<(), sdg_engine::EngineError>(())
/// ```
///
/// Non-finite points are skipped and break the line there. A chart without any finite point
/// still renders its axes (ranges 0 to 1).
#[derive(Clone, Debug)]
pub struct LineChart {
    title: String,
    x_label: String,
    y_label: String,
    series: Vec<Series>,
    x_range: Option<(f64, f64)>,
    y_range: Option<(f64, f64)>,
}

impl LineChart {
    /// An empty chart with a title and axis labels (units included by the caller).
    pub fn new(title: &str, x_label: &str, y_label: &str) -> Self {
        Self {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            series: Vec::new(),
            x_range: None,
            y_range: None,
        }
    }

    /// Fixes the x axis to `[lo, hi]` (`lo < hi`, both finite) instead of the range of the
    /// points (e.g. with a margin, so that dots at the ends are not on the frame).
    pub fn x_range(mut self, lo: f64, hi: f64) -> Self {
        self.x_range = (lo.is_finite() && hi.is_finite() && lo < hi).then_some((lo, hi));
        self
    }

    /// Fixes the y axis to `[lo, hi]` (`lo < hi`, both finite) instead of the range of the
    /// points; lines are cut where they leave it.
    pub fn y_range(mut self, lo: f64, hi: f64) -> Self {
        self.y_range = (lo.is_finite() && hi.is_finite() && lo < hi).then_some((lo, hi));
        self
    }

    /// Adds a series named `name` (shown in the legend unless empty), coloured in turn from a
    /// palette ([`LineStyle::Faint`] series in grey).
    pub fn series(mut self, name: &str, points: &[(f64, f64)], style: LineStyle) -> Self {
        self.series.push(Series {
            name: name.into(),
            points: points.to_vec(),
            style,
        });
        self
    }

    /// Renders the chart into an image of `size` (width, height) pixels.
    pub fn render(&self, size: (u32, u32)) -> Result<Image, EngineError> {
        let family = font_family()?;
        let mut image = Image::white(size)?;
        let f = font_px(size);
        let finite = || {
            self.series
                .iter()
                .flat_map(|s| &s.points)
                .filter(|p| p.0.is_finite() && p.1.is_finite())
        };
        let (x0, x1) = self
            .x_range
            .unwrap_or_else(|| widen(finite_range(finite().map(|p| p.0)).unwrap_or((0.0, 1.0))));
        let (y0, y1) = self
            .y_range
            .unwrap_or_else(|| widen(finite_range(finite().map(|p| p.1)).unwrap_or((0.0, 1.0))));
        let pad = 0.05 * (y1 - y0);
        if f64::from(size.0) < 12.0 * f || f64::from(size.1) < 8.0 * f {
            return Err(EngineError::Plot(format!(
                "a {}x{} image is too small for a chart",
                size.0, size.1
            )));
        }
        {
            let root = BitMapBackend::with_buffer(&mut image.rgb, size).into_drawing_area();
            let mut chart = ChartBuilder::on(&root)
                .caption(&self.title, (family, 1.2 * f))
                .margin((0.8 * f) as u32)
                .x_label_area_size((2.8 * f) as u32)
                .y_label_area_size((5.0 * f) as u32)
                .build_cartesian_2d(x0..x1, (y0 - pad)..(y1 + pad))
                .map_err(plot_error)?;
            let x_label = |v: &f64| tick_label_within(*v, x1 - x0);
            let y_label = |v: &f64| tick_label_within(*v, y1 - y0 + 2.0 * pad);
            chart
                .configure_mesh()
                .x_desc(self.x_label.as_str())
                .y_desc(self.y_label.as_str())
                .label_style((family, f))
                .axis_desc_style((family, f))
                .x_label_formatter(&x_label)
                .y_label_formatter(&y_label)
                .light_line_style(WHITE)
                .bold_line_style(RGBColor(225, 225, 225))
                .draw()
                .map_err(plot_error)?;
            let width = (f / 8.0).round().max(2.0) as u32;
            let mut coloured = 0;
            for s in &self.series {
                let style = if s.style == LineStyle::Faint {
                    FAINT.stroke_width(1)
                } else {
                    coloured += 1;
                    PALETTE[(coloured - 1) % PALETTE.len()].stroke_width(width)
                };
                let mut labelled = s.name.is_empty();
                for run in self.runs(&s.points) {
                    let drawn = match s.style {
                        // Segment by segment: a polyline wider than a pixel is joined with
                        // unbounded miters, which draw spikes past the points at sharp turns
                        // (a noisy tip speed seemed to cross `c_R` where no point did).
                        LineStyle::Solid | LineStyle::Faint => chart.draw_series(
                            run.windows(2)
                                .map(|w| PathElement::new([w[0], w[1]], style)),
                        ),
                        LineStyle::Markers => chart.draw_series(
                            run.iter()
                                .map(|&p| Circle::new(p, width + 2, style.filled())),
                        ),
                        LineStyle::Dashed => chart.draw_series(DashedLineSeries::new(
                            run,
                            (0.8 * f) as u32,
                            (0.5 * f) as u32,
                            style,
                        )),
                    }
                    .map_err(plot_error)?;
                    if !labelled {
                        labelled = true;
                        let kind = s.style;
                        drawn
                            .label(s.name.as_str())
                            .legend(move |(x, y)| match kind {
                                LineStyle::Markers => {
                                    Circle::new((x + 10, y), width + 2, style.filled()).into_dyn()
                                }
                                LineStyle::Dashed => {
                                    PathElement::new([(x, y), (x + 8, y)], style).into_dyn()
                                }
                                _ => PathElement::new([(x, y), (x + 20, y)], style).into_dyn(),
                            });
                    }
                }
            }
            let legend = |s: &Series| !(s.name.is_empty() || self.runs(&s.points).is_empty());
            if self.series.iter().any(legend) {
                chart
                    .configure_series_labels()
                    .label_font((family, 0.9 * f))
                    .background_style(WHITE.mix(0.85))
                    .border_style(BLACK)
                    .position(self.legend_corner((x0, x1), (y0 - pad, y1 + pad)))
                    .draw()
                    .map_err(plot_error)?;
            }
            root.present().map_err(plot_error)?;
        }
        Ok(image)
    }

    /// The corner of the plot whose third in x and y holds the fewest points, for the legend.
    fn legend_corner(&self, x: (f64, f64), y: (f64, f64)) -> SeriesLabelPosition {
        let corners = [
            (SeriesLabelPosition::UpperRight, true, true),
            (SeriesLabelPosition::UpperLeft, false, true),
            (SeriesLabelPosition::LowerRight, true, false),
            (SeriesLabelPosition::LowerLeft, false, false),
        ];
        let near = |v: f64, (lo, hi): (f64, f64), high: bool| {
            let t = (v - lo) / (hi - lo);
            if high { t > 0.6 } else { t < 0.4 }
        };
        let count = |right: bool, top: bool| {
            self.series
                .iter()
                .flat_map(|s| &s.points)
                .filter(|p| near(p.0, x, right) && near(p.1, y, top))
                .count()
        };
        corners
            .into_iter()
            .min_by_key(|&(_, right, top)| count(right, top))
            .map_or(SeriesLabelPosition::UpperRight, |c| c.0)
    }

    /// The pieces of `points` to draw: runs of finite points, cut to the fixed y range.
    fn runs(&self, points: &[(f64, f64)]) -> Vec<Vec<(f64, f64)>> {
        match self.y_range {
            Some(band) => runs(points).iter().flat_map(|r| clip(r, band)).collect(),
            None => runs(points),
        }
    }

    /// Renders the chart and writes it as PNG to `path` (atomically).
    pub fn write_png(&self, path: &Path, size: (u32, u32)) -> Result<(), EngineError> {
        self.render(size)?.write_png(path)
    }
}

/// The maximal runs of finite points of `points`.
fn runs(points: &[(f64, f64)]) -> Vec<Vec<(f64, f64)>> {
    points
        .split(|p| !(p.0.is_finite() && p.1.is_finite()))
        .filter(|r| !r.is_empty())
        .map(<[(f64, f64)]>::to_vec)
        .collect()
}

/// The pieces of the polyline `run` (finite points) inside `lo <= y <= hi`, cut where its
/// segments cross the bounds.
fn clip(run: &[(f64, f64)], (lo, hi): (f64, f64)) -> Vec<Vec<(f64, f64)>> {
    let inside = |p: (f64, f64)| (lo..=hi).contains(&p.1);
    let mut pieces: Vec<Vec<(f64, f64)>> = Vec::new();
    if let [p] = run {
        if inside(*p) {
            pieces.push(vec![*p]);
        }
        return pieces;
    }
    // Whether the last piece ends at the end of the previous segment (so the next joins it).
    let mut open = false;
    for w in run.windows(2) {
        let (p, q) = (w[0], w[1]);
        let dy = q.1 - p.1;
        let (t0, t1) = if dy == 0.0 {
            if inside(p) { (0.0, 1.0) } else { (1.0, 0.0) }
        } else {
            let (a, b) = ((lo - p.1) / dy, (hi - p.1) / dy);
            (a.min(b).max(0.0), a.max(b).min(1.0))
        };
        if t0 > t1 {
            open = false;
            continue;
        }
        let at = |t: f64| (p.0 + t * (q.0 - p.0), p.1 + t * dy);
        if !(open && t0 == 0.0) {
            pieces.push(vec![at(t0)]);
        }
        pieces.last_mut().expect("pushed").push(at(t1));
        open = t1 == 1.0;
    }
    pieces
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Pixels of exactly `colour` in the image.
    fn count(image: &Image, colour: RGBColor) -> usize {
        image
            .rgb
            .chunks(3)
            .filter(|p| p == &[colour.0, colour.1, colour.2])
            .count()
    }

    #[test]
    fn series_are_drawn_in_their_colours() {
        let sine: Vec<(f64, f64)> = (0..200)
            .map(|i| (f64::from(i) * 0.05, (f64::from(i) * 0.05).sin()))
            .collect();
        let mut gappy = sine.iter().map(|p| (p.0, 0.5 * p.1)).collect::<Vec<_>>();
        gappy[50].1 = f64::NAN;
        let image = LineChart::new("sines", "t (us)", "y (J)")
            .series("sin", &sine, LineStyle::Solid)
            .series("half", &gappy, LineStyle::Dashed)
            .render((900, 600))
            .unwrap();
        assert_eq!((image.width, image.height), (900, 600));
        let (a, b) = (count(&image, PALETTE[0]), count(&image, PALETTE[1]));
        assert!(a > 1000, "{a}");
        // Dashed: fewer pixels than a solid line of the same length would have.
        assert!(b > 300 && b < a, "{b} {a}");
    }

    #[test]
    fn markers_are_dots_even_alone() {
        let image = LineChart::new("draws", "seed", "t (us)")
            .series(
                "draws",
                &[(1.0, 2.0), (2.0, 2.5), (3.0, f64::NAN)],
                LineStyle::Markers,
            )
            .series("one", &[(2.0, 2.2)], LineStyle::Markers)
            .render((600, 400))
            .unwrap();
        let (a, b) = (count(&image, PALETTE[0]), count(&image, PALETTE[1]));
        assert!(a > 40 && a < 400, "{a}");
        assert!(b > 20 && b < 200, "{b}");
    }

    #[test]
    fn lines_are_cut_at_a_fixed_y_range() {
        // Up through the top, back in, along the bottom bound, out below and back.
        let run = [
            (0.0, 0.0),
            (1.0, 4.0),
            (2.0, 0.0),
            (3.0, -1.0),
            (4.0, -1.0),
            (5.0, 1.0),
        ];
        assert_eq!(
            clip(&run, (-1.0, 2.0)),
            [
                vec![(0.0, 0.0), (0.5, 2.0)],
                vec![(1.5, 2.0), (2.0, 0.0), (3.0, -1.0), (4.0, -1.0), (5.0, 1.0)],
            ]
        );
        assert_eq!(
            clip(&run, (-0.5, 2.0))[1..],
            [
                vec![(1.5, 2.0), (2.0, 0.0), (2.5, -0.5)],
                vec![(4.25, -0.5), (5.0, 1.0)]
            ]
        );
        assert_eq!(clip(&[(0.0, 3.0)], (0.0, 2.0)), Vec::<Vec<_>>::new());
        assert_eq!(clip(&[(0.0, 1.0)], (0.0, 2.0)), [vec![(0.0, 1.0)]]);
        let image = LineChart::new("cut", "x", "y")
            .y_range(-1.0, 2.0)
            .series("run", &run, LineStyle::Solid)
            .series("", &[(0.0, 1.0), (5.0, 1.0)], LineStyle::Faint)
            .render((600, 400))
            .unwrap();
        assert!(count(&image, PALETTE[0]) > 300);
        assert!(count(&image, FAINT) > 300);
        // The faint series takes no palette colour.
        assert_eq!(count(&image, PALETTE[1]), 0);
    }

    /// The topmost row holding a pixel of exactly `colour`.
    fn top_row(image: &Image, colour: RGBColor) -> Option<usize> {
        let width = image.width as usize;
        image
            .rgb
            .chunks(3)
            .position(|p| p == [colour.0, colour.1, colour.2])
            .map(|i| i / width)
    }

    #[test]
    fn sharp_turns_draw_nothing_past_their_points() {
        // Tip speeds (m/s) against time (us) of a branch of the main job: a steep drop and
        // rise within a pixel, which a mitered line would draw as a spike past `c_R` (938.9 m/s)
        // that no point reaches.
        let speeds = [
            (1.75, 400.0),
            (2.899965, 797.346),
            (2.902192, 785.998),
            (2.903786, 601.860),
            (2.904457, 651.448),
            (3.6, 400.0),
        ];
        let image = LineChart::new("tip speed", "t (us)", "v (m/s)")
            .series("", &speeds, LineStyle::Solid)
            .series("", &[(1.75, 938.9), (3.6, 938.9)], LineStyle::Solid)
            .render((1000, 600))
            .unwrap();
        let (top, c_r) = (top_row(&image, PALETTE[0]), top_row(&image, PALETTE[1]));
        let (Some(top), Some(c_r)) = (top, c_r) else {
            panic!("both series are drawn: {top:?} {c_r:?}");
        };
        // No names, no legend: the rows are the lines'.
        assert!(
            top > c_r + 20,
            "speeds drawn up to row {top}, c_R at row {c_r}"
        );
    }

    #[test]
    fn empty_or_non_finite_charts_still_render() {
        let image = LineChart::new("empty", "x", "y")
            .render((600, 400))
            .unwrap();
        let dark = image.rgb.chunks(3).filter(|p| p[0] < 50).count();
        assert!(dark > 100, "axes and labels are drawn");
        LineChart::new("nan", "x", "y")
            .series(
                "nan",
                &[(f64::NAN, 1.0), (2.0, f64::INFINITY)],
                LineStyle::Solid,
            )
            .series("one", &[(1.0, 1.0)], LineStyle::Solid)
            .render((600, 400))
            .unwrap();
        let err = LineChart::new("tiny", "x", "y")
            .render((50, 40))
            .unwrap_err();
        assert!(err.to_string().contains("too small"), "{err}");
    }
}
