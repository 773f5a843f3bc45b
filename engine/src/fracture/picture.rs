//! `crack_path.png` and `crack_zoom.png`: the crack edges on the final mesh.

use super::records::CrackEdge;
use crate::plot::{FieldPlot, Values};
use sdg_mesh::Mesh;

/// `crack_path.png`: the final mesh's domain with the crack edges in red and the triangles
/// beside them coloured by their damage (the largest of a triangle's crack edges); and
/// `crack_zoom.png`: the same around the edges the run added (`grown` tag), when there are
/// any, with the mesh's edges unless they would hide the triangles.
pub(crate) fn write_crack_path_png(
    dir: &std::path::Path,
    mesh: &Mesh,
    cracks: &[CrackEdge],
    grown: sdg_mesh::TagId,
    time: f64,
    fork: Option<[f64; 2]>,
) {
    let mut damage = vec![f64::NAN; mesh.triangles().len()];
    for c in cracks {
        for t in mesh.edges()[c.edge as usize]
            .triangles
            .into_iter()
            .flatten()
        {
            let d = &mut damage[t as usize];
            *d = if d.is_nan() {
                c.damage
            } else {
                d.max(c.damage)
            };
        }
    }
    let segments: Vec<[[f64; 2]; 2]> = cracks.iter().map(|c| c.ends).collect();
    let markers: Vec<[f64; 2]> = fork.into_iter().collect();
    let title = match fork {
        Some(_) => "cracks (red), damage D beside them, first macro fork circled",
        None => "cracks (red), damage D beside them",
    };
    let plot = FieldPlot::new(mesh.vertices(), mesh.triangles(), Values::Cells(&damage))
        .title(title)
        .time(Some(time))
        .segments(&segments)
        .markers(&markers);
    let new_ends = cracks
        .iter()
        .filter(|c| mesh.edges()[c.edge as usize].tag == Some(grown))
        .flat_map(|c| c.ends);
    let zoom = zoom_window(new_ends, mesh.vertices()).map(|w| {
        // The mesh's edges only where they leave the triangles visible.
        let inside = |p: &&[f64; 2]| (w[0]..=w[1]).contains(&p[0]) && (w[2]..=w[3]).contains(&p[1]);
        let shown = mesh.vertices().iter().filter(inside).count();
        plot.clone()
            .window(Some(w))
            .edges(shown <= ZOOM_MAX_EDGED_VERTICES)
    });
    for (name, plot) in [("crack_path.png", Some(plot)), ("crack_zoom.png", zoom)] {
        let Some(plot) = plot else { continue };
        let path = dir.join(name);
        let image = plot.render(CRACK_PATH_PNG_SIZE);
        if let Err(e) = image.and_then(|image| image.write_png(&path)) {
            tracing::warn!("{}: {e}", path.display());
        }
    }
}

/// The window `[xmin, xmax, ymin, ymax]` (m) of `crack_zoom.png` around `points`: centred on
/// their bounding box, 1.2 times as large (at least 1% of the domain's diagonal) and with the
/// picture's aspect ratio; `None` for no points.
fn zoom_window(points: impl Iterator<Item = [f64; 2]>, domain: &[[f64; 2]]) -> Option<[f64; 4]> {
    let [x0, x1, y0, y1] = bounding_box(points)?;
    let [dx0, dx1, dy0, dy1] = bounding_box(domain.iter().copied())?;
    let (w, h) = CRACK_PATH_PNG_SIZE;
    let aspect = f64::from(h) / f64::from(w);
    let least = 0.01 * (dx1 - dx0).hypot(dy1 - dy0);
    let half_width = 0.6 * (x1 - x0).max((y1 - y0) / aspect).max(least);
    let half_height = aspect * half_width;
    let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
    Some([
        cx - half_width,
        cx + half_width,
        cy - half_height,
        cy + half_height,
    ])
}

/// `[xmin, xmax, ymin, ymax]` of `points`; `None` for none.
fn bounding_box(points: impl Iterator<Item = [f64; 2]>) -> Option<[f64; 4]> {
    points.fold(None, |b, p| {
        let [x0, x1, y0, y1] = b.unwrap_or([p[0], p[0], p[1], p[1]]);
        Some([x0.min(p[0]), x1.max(p[0]), y0.min(p[1]), y1.max(p[1])])
    })
}

/// Most mesh vertices in `crack_zoom.png`'s window for which it draws the mesh's edges.
const ZOOM_MAX_EDGED_VERTICES: usize = 1500;

/// Size of `crack_path.png`, pixels.
const CRACK_PATH_PNG_SIZE: (u32, u32) = (1200, 900);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_zoom_frames_the_grown_cracks() {
        let domain = [[0.0, 0.0], [16e-3, 10e-3]];
        // A 1 mm crack along x: 1.2 mm wide, with the picture's aspect ratio.
        let crack = [[2e-3, 5e-3], [3e-3, 5e-3]];
        let [x0, x1, y0, y1] = zoom_window(crack.into_iter(), &domain).unwrap();
        assert!((x1 - x0 - 1.2e-3).abs() < 1e-12 && (x0 + x1 - 5e-3).abs() < 1e-12);
        let (w, h) = CRACK_PATH_PNG_SIZE;
        assert!(((y1 - y0) / (x1 - x0) - f64::from(h) / f64::from(w)).abs() < 1e-12);
        assert!((y0 + y1 - 10e-3).abs() < 1e-12);
        // A tiny one gets 1.2% of the domain's diagonal; none gets no picture.
        let [x0, x1, ..] = zoom_window([[2e-3, 5e-3]].into_iter(), &domain).unwrap();
        assert!((x1 - x0 - 0.012 * 16e-3f64.hypot(10e-3)).abs() < 1e-12);
        assert_eq!(zoom_window(std::iter::empty(), &domain), None);
    }
}
