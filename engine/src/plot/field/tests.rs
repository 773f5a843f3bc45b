use super::*;

/// A structured `n x n` grid of the unit square (metres scaled by `h`), two triangles per
/// cell.
fn grid(n: u32, h: f64) -> (Vec<[f64; 2]>, Vec<[u32; 3]>) {
    let points = (0..=n)
        .flat_map(|j| {
            (0..=n).map(move |i| {
                [
                    h * f64::from(i) / f64::from(n),
                    h * f64::from(j) / f64::from(n),
                ]
            })
        })
        .collect();
    let id = |i: u32, j: u32| j * (n + 1) + i;
    let triangles = (0..n)
        .flat_map(|j| {
            (0..n).flat_map(move |i| {
                [
                    [id(i, j), id(i + 1, j), id(i + 1, j + 1)],
                    [id(i, j), id(i + 1, j + 1), id(i, j + 1)],
                ]
            })
        })
        .collect();
    (points, triangles)
}

fn luminance(p: [u8; 3]) -> f64 {
    0.299 * f64::from(p[0]) + 0.587 * f64::from(p[1]) + 0.114 * f64::from(p[2])
}

#[test]
fn round_ticks() {
    assert_eq!(
        nice_ticks(0.0, 1.0),
        [0.0, 0.2, 0.4, 0.6000000000000001, 0.8, 1.0]
    );
    assert_eq!(nice_ticks(-3.0e6, 7.0e6), [-2e6, 0.0, 2e6, 4e6, 6e6]);
    assert_eq!(nice_ticks(0.013, 0.018).len(), 6);
}

#[test]
fn viridis_lightness_increases() {
    let l: Vec<f64> = (0..=100)
        .map(|i| luminance(viridis(f64::from(i) / 100.0)))
        .collect();
    assert!(l.windows(2).all(|w| w[1] > w[0]), "{l:?}");
    assert_eq!(viridis(f64::NAN), viridis(0.0));
}

#[test]
fn a_linear_field_fills_the_plotting_area_and_increases_along_x() {
    let (points, triangles) = grid(20, 0.01);
    let values: Vec<f64> = points.iter().map(|p| p[0]).collect();
    let plot = FieldPlot::new(&points, &triangles, Values::Points(&values))
        .title("x")
        .time(Some(2.5e-6))
        .edges(true)
        .segments(&[[[0.0, 0.005], [0.01, 0.005]]]);
    assert_eq!(plot.full_title(), "x, t = 2.5 us");
    let image = plot.render((800, 600)).unwrap();
    let lay = plot.layout((800, 600)).unwrap();
    let [x0, y0, x1, y1] = lay.field;
    assert_eq!(x1 - x0, y1 - y0, "square domain, square picture");
    // Every pixel of the field is painted (no white gaps between triangles).
    for y in y0..y1 {
        for x in x0..x1 {
            assert_ne!(image.pixel(x, y), [255, 255, 255], "({x}, {y})");
        }
    }
    // Lightness increases from left to right (away from edges and the red segment).
    let row = y0 + (y1 - y0) / 4 + 3;
    let left = luminance(image.pixel(x0 + 5, row));
    let right = luminance(image.pixel(x1 - 5, row));
    assert!(right > left + 100.0, "{left} {right}");
    // The red segment across the middle.
    let mid = (y0 + y1) / 2;
    let reds = (y0..y1)
        .filter(|&y| image.pixel((x0 + x1) / 2, y) == SEGMENT_RGB)
        .count();
    assert!((1..=3).contains(&reds), "{reds} red pixels near row {mid}");
    // The colour bar: bright at the top, dark at the bottom.
    let [bx0, by0, bx1, by1] = lay.colorbar;
    let cx = (bx0 + bx1) / 2;
    assert!(luminance(image.pixel(cx, by0 + 2)) > luminance(image.pixel(cx, by1 - 3)) + 100.0);
}

#[test]
fn a_marker_is_a_black_circle_around_its_point() {
    let (points, triangles) = grid(20, 0.01);
    let values = vec![0.5; points.len()];
    let plain = FieldPlot::new(&points, &triangles, Values::Points(&values));
    let marked = plain.clone().markers(&[[0.005, 0.005]]);
    let (a, b) = (
        plain.render((800, 600)).unwrap(),
        marked.render((800, 600)).unwrap(),
    );
    let [x0, y0, x1, y1] = marked.layout((800, 600)).unwrap().field;
    let (cx, cy) = ((x0 + x1) / 2, (y0 + y1) / 2);
    let r = MARKER_RADIUS as u32;
    for (x, y) in [(cx + r, cy), (cx - r, cy), (cx, cy + r), (cx, cy - r)] {
        assert_eq!(b.pixel(x, y), [0, 0, 0], "({x}, {y})");
    }
    // Inside and outside the ring the field shows as without the marker.
    for (x, y) in [(cx, cy), (cx + r / 2, cy), (cx + 2 * r, cy)] {
        assert_eq!(a.pixel(x, y), b.pixel(x, y), "({x}, {y})");
    }
}

#[test]
fn a_window_shows_its_part_of_the_field() {
    // x from 0 to 10 mm; the window is the right half's lower part, 5 x 2.5 mm.
    let (points, triangles) = grid(20, 0.01);
    let values: Vec<f64> = points.iter().map(|p| p[0]).collect();
    let whole = FieldPlot::new(&points, &triangles, Values::Points(&values));
    let part = whole.clone().window(Some([0.005, 0.02, -1.0, 0.0025]));
    let lay = part.layout((800, 600)).unwrap();
    let [x0, y0, x1, y1] = lay.field;
    assert_eq!(
        x1 - x0,
        2 * (y1 - y0),
        "the window's aspect ratio, clipped to the data"
    );
    // The window's left edge is the field's middle: as light as the whole picture's middle.
    let image = part.render((800, 600)).unwrap();
    let [wx0, wy0, wx1, wy1] = whole.layout((800, 600)).unwrap().field;
    let middle = whole.render((800, 600)).unwrap();
    let left = luminance(image.pixel(x0 + 1, (y0 + y1) / 2));
    let centre = luminance(middle.pixel((wx0 + wx1) / 2, (wy0 + wy1) / 2));
    assert!((left - centre).abs() < 15.0, "{left} {centre}");
    assert!(
        whole
            .window(Some([0.02, 0.03, 0.0, 0.01]))
            .layout((800, 600))
            .is_err(),
        "a window beside the triangles"
    );
}

#[test]
fn plotters_frame_matches_the_layout() {
    // The chart built by `draw_frame` maps data corners to the field's pixel corners: a
    // black axis line is drawn just outside the field's left and bottom edges.
    let (points, triangles) = grid(4, 0.002);
    let values = vec![1.0; points.len()];
    let plot = FieldPlot::new(&points, &triangles, Values::Points(&values));
    let image = plot.render((600, 500)).unwrap();
    let [x0, y0, x1, y1] = plot.layout((600, 500)).unwrap().field;
    let dark = |x: u32, y: u32| luminance(image.pixel(x, y)) < 60.0;
    let mid_y = (y0 + y1) / 2;
    let mid_x = (x0 + x1) / 2;
    assert!(
        (x0.saturating_sub(2)..=x0).any(|x| dark(x, mid_y)),
        "left axis"
    );
    assert!((y1 - 1..=y1 + 1).any(|y| dark(mid_x, y)), "bottom axis");
}

#[test]
fn cell_values_and_non_finite_values() {
    let (points, triangles) = grid(2, 1.0);
    let mut cells: Vec<f64> = (0..triangles.len()).map(|k| k as f64).collect();
    cells[0] = f64::NAN;
    let plot = FieldPlot::new(&points, &triangles, Values::Cells(&cells));
    let image = plot.render((400, 300)).unwrap();
    assert_eq!((image.width, image.height), (400, 300));
    // The share of the field left white (unfilled), inside its frame.
    let [x0, y0, x1, y1] = plot.layout((400, 300)).unwrap().field;
    let white = |image: &Image| {
        let inside = (y0 + 2..y1 - 2).flat_map(|y| (x0 + 2..x1 - 2).map(move |x| (x, y)));
        let (mut all, mut blank) = (0, 0);
        for (x, y) in inside {
            all += 1;
            blank += usize::from(image.pixel(x, y) == [255, 255, 255]);
        }
        blank as f64 / all as f64
    };
    // The NaN cell is one of eight equal triangles: it alone stays white.
    let share = white(&image);
    assert!((0.10..0.15).contains(&share), "{share}");
    // All values non-finite: nothing filled, axes still drawn.
    let nan = vec![f64::NAN; points.len()];
    let blank = FieldPlot::new(&points, &triangles, Values::Points(&nan))
        .render((400, 300))
        .unwrap();
    assert_eq!(white(&blank), 1.0);
    let left_axis =
        (x0.saturating_sub(2)..=x0).any(|x| luminance(blank.pixel(x, (y0 + y1) / 2)) < 60.0);
    assert!(left_axis, "the left axis");
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let (points, triangles) = grid(2, 1.0);
    let short = vec![0.0; 3];
    let err = |p: FieldPlot, size| p.render(size).unwrap_err().to_string();
    assert!(
        err(
            FieldPlot::new(&points, &triangles, Values::Points(&short)),
            (400, 300)
        )
        .contains("3 values for 9 points")
    );
    assert!(
        err(
            FieldPlot::new(&points, &[[0, 1, 99]], Values::Cells(&[1.0])),
            (400, 300)
        )
        .contains("beyond")
    );
    assert!(
        err(FieldPlot::new(&points, &[], Values::Cells(&[])), (400, 300))
            .contains("nothing to draw")
    );
    assert!(
        err(
            FieldPlot::new(&points, &[[0, 1, 2]], Values::Cells(&[1.0])),
            (400, 300)
        )
        .contains("no area")
    );
    let ok = vec![0.0; points.len()];
    assert!(
        err(
            FieldPlot::new(&points, &triangles, Values::Points(&ok)),
            (60, 40)
        )
        .contains("no room")
    );
}

/// A field wider than the picture's shape leaves no empty band below its axis labels; a
/// square one fills the requested height.
#[test]
fn a_wide_field_s_picture_is_cut_below_its_axis_labels() {
    let picture = |w: f64, h: f64| {
        let corners = [[0.0, 0.0], [w, 0.0], [w, h], [0.0, h]];
        let values = Values::Points(&[0.0, 1.0, 2.0, 3.0]);
        let plot = FieldPlot::new(&corners, &[[0, 1, 2], [0, 2, 3]], values);
        (
            plot.render((1000, 800)).unwrap(),
            plot.layout((1000, 800)).unwrap(),
        )
    };
    let (square, lay) = picture(1e-3, 1e-3);
    assert_eq!(
        (square.width, square.height, lay.size),
        (1000, 800, (1000, 800))
    );
    let (wide, lay) = picture(4e-3, 1e-3);
    assert_eq!((wide.width, wide.height), lay.size);
    assert_eq!(wide.rgb.len(), 3 * 1000 * wide.height as usize);
    // The field keeps its place and shape; the picture ends a label band below it.
    let [_, y0, _, y1] = lay.field;
    assert!(
        wide.height < 500 && wide.height > y1 + (y1 - y0) / 10,
        "{lay:?}"
    );
    // The x-axis title sits in the band: the lowest third of it has dark pixels.
    let band = (y1 + 2 * (wide.height - y1) / 3) as usize..wide.height as usize;
    let dark = band
        .flat_map(|y| (0..1000).map(move |x| 3 * (y * 1000 + x)))
        .filter(|&i| wide.rgb[i] < 128)
        .count();
    assert!(
        dark > 20,
        "{dark} dark pixels in the lowest third of the label band"
    );
}

/// 100k triangles render in well under a second (release build).
#[test]
fn hundred_thousand_triangles_render_fast() {
    let (points, triangles) = grid(224, 0.01);
    assert!(triangles.len() >= 100_000);
    let values: Vec<f64> = points.iter().map(|p| (p[0] * 900.0).sin() * p[1]).collect();
    let plot = FieldPlot::new(&points, &triangles, Values::Points(&values)).title("bench");
    let start = std::time::Instant::now();
    let image = plot.render((1000, 800)).unwrap();
    let render = start.elapsed().as_secs_f64();
    let png = image.to_png().unwrap();
    let total = start.elapsed().as_secs_f64();
    eprintln!(
        "{} triangles: render {:.1} ms, with PNG encoding {:.1} ms ({} bytes)",
        triangles.len(),
        render * 1e3,
        total * 1e3,
        png.len()
    );
    if !cfg!(debug_assertions) {
        assert!(total < 0.5, "{total} s");
    }
}
