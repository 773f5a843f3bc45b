//! Pictures: `output.png` writes a PNG per snapshot and `history.png`; the plane wave's picture
//! has its stripes at the wave's angle; `sdg plot` reads VTU files written by meshio and names
//! a missing field, and draws several runs' crack tips together.

use crate::common;

use std::path::Path;

use common::{sdg, stderr};
use sdg_engine::plot::{
    CRACK_PNG_SIZE, FIELD_PNG_SIZE, FieldLayout, FieldPlot, HISTORY_PNG_SIZE, Values,
};

/// A decoded 8-bit RGB PNG: width, height, pixels.
struct Decoded {
    width: u32,
    height: u32,
    rgb: Vec<u8>,
}

impl Decoded {
    fn read(path: &Path) -> Self {
        let file = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let mut reader = png::Decoder::new(std::io::BufReader::new(file))
            .read_info()
            .unwrap();
        let mut rgb = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut rgb).unwrap();
        assert_eq!(info.color_type, png::ColorType::Rgb, "{}", path.display());
        assert_eq!(info.bit_depth, png::BitDepth::Eight);
        rgb.truncate(info.buffer_size());
        Self {
            width: info.width,
            height: info.height,
            rgb,
        }
    }

    /// Luminance (0 to 255) at column `x`, row `y`.
    fn luminance(&self, x: u32, y: u32) -> f64 {
        let i = 3 * (y as usize * self.width as usize + x as usize);
        let p = &self.rgb[i..i + 3];
        0.299 * f64::from(p[0]) + 0.587 * f64::from(p[1]) + 0.114 * f64::from(p[2])
    }

    /// Variance of the luminance over the rectangle `[x0, y0, x1, y1]` shrunk by `margin`.
    fn variance(&self, rect: [u32; 4], margin: u32) -> f64 {
        let [x0, y0, x1, y1] = rect;
        let values: Vec<f64> = (y0 + margin..y1 - margin)
            .flat_map(|y| (x0 + margin..x1 - margin).map(move |x| (x, y)))
            .map(|(x, y)| self.luminance(x, y))
            .collect();
        let mean = values.iter().sum::<f64>() / values.len() as f64;
        values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / values.len() as f64
    }

    /// The dominant orientation (degrees in [0, 180), counter-clockwise from +x with y up) of
    /// the luminance gradient in `rect` shrunk by `margin`: the structure tensor's main axis.
    fn gradient_orientation(&self, rect: [u32; 4], margin: u32) -> f64 {
        let [x0, y0, x1, y1] = rect;
        let (mut jxx, mut jyy, mut jxy) = (0.0, 0.0, 0.0);
        for y in y0 + margin..y1 - margin {
            for x in x0 + margin..x1 - margin {
                let gx = self.luminance(x + 1, y) - self.luminance(x - 1, y);
                // Rows grow downwards: y up is minus the row direction.
                let gy = self.luminance(x, y - 1) - self.luminance(x, y + 1);
                jxx += gx * gx;
                jyy += gy * gy;
                jxy += gx * gy;
            }
        }
        (0.5 * f64::atan2(2.0 * jxy, jxx - jyy).to_degrees()).rem_euclid(180.0)
    }
}

/// The layout of a field picture of the rectangle `[0, w] x [0, h]` (m).
fn layout(w: f64, h: f64) -> FieldLayout {
    let corners = [[0.0, 0.0], [w, 0.0], [w, h], [0.0, h]];
    FieldPlot::new(
        &corners,
        &[[0, 1, 2], [0, 2, 3]],
        Values::Cells(&[0.0, 0.0]),
    )
    .layout(FIELD_PNG_SIZE)
    .unwrap()
}

/// Checks a snapshot picture: its size, and that its field and colour bar are not blank.
fn check_field_png(path: &Path, lay: &FieldLayout) -> Decoded {
    let image = Decoded::read(path);
    assert_eq!((image.width, image.height), lay.size);
    let field = image.variance(lay.field, 3);
    let bar = image.variance(lay.colorbar, 2);
    assert!(field > 50.0, "{}: field variance {field}", path.display());
    assert!(bar > 500.0, "{}: colour bar variance {bar}", path.display());
    image
}

fn check_history_png(path: &Path) {
    let image = Decoded::read(path);
    assert_eq!((image.width, image.height), HISTORY_PNG_SIZE);
    let all = [0, 0, image.width, image.height];
    assert!(image.variance(all, 0) > 100.0, "{}", path.display());
}

#[test]
fn plane_wave_picture_has_stripes_at_the_wave_angle() {
    let problem = common::shipped(
        "plane_wave.toml",
        &["time.end=5e-7", "output.snapshot_times=[0.0, 5e-7]"],
    );
    assert!(problem.loaded.config.output.png, "on in the shipped config");
    let angle = match &problem.loaded.config.exact {
        Some(e) => e.angle_deg,
        None => panic!("plane_wave.toml has an exact solution"),
    };
    let (_, dir) = common::solve(&problem, 2, true);
    let lay = layout(0.01, 0.01);
    for file in ["snapshot_0000.png", "snapshot_0001.png"] {
        let image = check_field_png(&dir.path().join(file), &lay);
        let orientation = image.gradient_orientation(lay.field, 4);
        let off = (orientation - angle).rem_euclid(180.0);
        let off = off.min(180.0 - off);
        eprintln!("{file}: gradient orientation {orientation:.2} deg, wave {angle} deg");
        assert!(off < 5.0, "{file}: {orientation} deg against {angle} deg");
    }
    // A smooth component (the magnitude has kinks where the velocity changes sign, which the
    // slice's triangles blur unevenly): the stripes' orientation within a degree.
    let vx = dir.path().join("vx.png");
    let snapshot = dir.path().join("snapshot_0001.vtu");
    let args = [
        "plot",
        snapshot.to_str().unwrap(),
        "--field",
        "velocity_x",
        "--out",
    ];
    let out = sdg(&[&args[..], &[vx.to_str().unwrap()]].concat());
    assert!(out.status.success(), "{}", stderr(&out));
    let orientation = check_field_png(&vx, &lay).gradient_orientation(lay.field, 4);
    eprintln!("velocity_x: gradient orientation {orientation:.2} deg");
    assert!((orientation - angle).abs() < 1.0, "{orientation} deg");
    check_history_png(&dir.path().join("history.png"));
}

#[test]
fn pictures_only_when_asked() {
    let problem = common::shipped(
        "plane_wave.toml",
        &[
            "time.end=1e-7",
            "output.snapshot_times=[1e-7]",
            "output.png=false",
        ],
    );
    let (summary, dir) = common::solve(&problem, 2, true);
    assert_eq!(summary.snapshots.len(), 1);
    let pngs = std::fs::read_dir(dir.path())
        .unwrap()
        .filter(|e| {
            e.as_ref()
                .unwrap()
                .path()
                .extension()
                .is_some_and(|x| x == "png")
        })
        .count();
    assert_eq!(pngs, 0);
}

#[test]
fn sdg_plot_reads_meshio_files_and_names_missing_fields() {
    let problem = common::shipped(
        "contact_separation.toml",
        &[
            "time.end=1.2e-6",
            "solver.order=1",
            "output.snapshot_times=[1.2e-6]",
        ],
    );
    let (_, dir) = common::solve(&problem, 2, true);
    let snapshot = dir.path().join("snapshot_0000.vtu");
    // The run's own picture and the interface drawn on it in red.
    let mesh_size = (0.004, 0.004);
    let lay = layout(mesh_size.0, mesh_size.1);
    let run_png = check_field_png(&dir.path().join("snapshot_0000.png"), &lay);
    let [x0, y0, x1, y1] = lay.field;
    let red = (y0..y1)
        .flat_map(|y| (x0..x1).map(move |x| (x, y)))
        .filter(|&(x, y)| {
            let i = 3 * (y as usize * run_png.width as usize + x as usize);
            run_png.rgb[i..i + 3] == [228, 26, 28]
        })
        .count();
    assert!(red > 100, "{red} interface pixels");

    // Our own file through `sdg plot`: default field and output path, then a named field.
    let out = sdg(&["plot", snapshot.to_str().unwrap(), "--quiet"]);
    assert!(out.status.success(), "{}", stderr(&out));
    check_field_png(&snapshot.with_extension("png"), &lay);
    let von_mises = dir.path().join("von_mises.png");
    let out = sdg(&[
        "plot",
        snapshot.to_str().unwrap(),
        "--field",
        "von_mises",
        "--edges",
        "--out",
        von_mises.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    check_field_png(&von_mises, &lay);

    // A missing field: exit 2, naming the file and the field and listing those present.
    let out = sdg(&["plot", snapshot.to_str().unwrap(), "--field", "pressure"]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    for needle in [
        "snapshot_0000.vtu",
        "`pressure`",
        "velocity",
        "stress_xy",
        "von_mises",
    ] {
        assert!(err.contains(needle), "`{needle}` not in: {err}");
    }
    // Not a VTU file: exit 2 naming it.
    let bogus = dir.path().join("bogus.vtu");
    std::fs::write(&bogus, "not xml").unwrap();
    let out = sdg(&["plot", bogus.to_str().unwrap()]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("bogus.vtu"), "{err}");

    if !common::meshio_available("sdg plot of meshio's VTU files") {
        return;
    }
    // meshio's encodings: zlib-compressed base64 (its default), uncompressed base64, ASCII.
    let script = "import sys, meshio\n\
                  m = meshio.read(sys.argv[1])\n\
                  meshio.write(sys.argv[2] + '/zlib.vtu', m)\n\
                  meshio.write(sys.argv[2] + '/raw.vtu', m, compression=None)\n\
                  meshio.write(sys.argv[2] + '/ascii.vtu', m, binary=False)\n";
    let meshio_dir = tempfile::tempdir().unwrap();
    common::python(script, &[&snapshot, meshio_dir.path()]);
    // The reference: our file alone in that folder (no pvd, no interfaces beside it).
    let ours = meshio_dir.path().join("ours.vtu");
    std::fs::copy(&snapshot, &ours).unwrap();
    let out = sdg(&["plot", ours.to_str().unwrap(), "--quiet"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let reference = Decoded::read(&ours.with_extension("png"));
    for name in ["zlib", "raw", "ascii"] {
        let vtu = meshio_dir.path().join(format!("{name}.vtu"));
        let out = sdg(&["plot", vtu.to_str().unwrap(), "--quiet"]);
        assert!(out.status.success(), "{name}: {}", stderr(&out));
        let image = check_field_png(&vtu.with_extension("png"), &lay);
        // The same picture: binary copies are exact, ASCII ones round to 12 digits.
        let differ = image
            .rgb
            .iter()
            .zip(&reference.rgb)
            .filter(|(a, b)| a != b)
            .count();
        let allowed = if name == "ascii" {
            image.rgb.len() / 1000
        } else {
            0
        };
        assert!(
            differ <= allowed,
            "{name}: {differ} bytes differ from our file's picture"
        );
    }
}

#[test]
fn sdg_plot_draws_several_runs_tips_together() {
    let dir = tempfile::tempdir().unwrap();
    let header = "t_s,interface,x_m,y_m,extension_m,speed_m_s,process_zone_length_m\n";
    let mut files = Vec::new();
    for (run, speed) in [("xu_needleman", 400.0), ("damage", 700.0)] {
        let folder = dir.path().join(run);
        std::fs::create_dir(&folder).unwrap();
        let mut csv = String::from(header);
        for i in 0..40 {
            let t = 1e-6 + 2e-8 * f64::from(i);
            let a = speed * 2e-8 * f64::from(i);
            csv += &format!("{t:e},path,{a:e},1.2e-3,{a:e},{speed:e},0\n");
        }
        let file = folder.join("crack_tips.csv");
        std::fs::write(&file, csv).unwrap();
        files.push(file.to_str().unwrap().to_string());
    }
    let png = dir.path().join("tips.png");
    let out = sdg(&["plot", &files[0], &files[1], "--out", png.to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));
    let image = Decoded::read(&png);
    assert_eq!((image.width, image.height), CRACK_PNG_SIZE);
    // One colour per run (the palette's first two).
    let count = |rgb: [u8; 3]| image.rgb.chunks(3).filter(|p| *p == rgb).count();
    assert!(count([31, 119, 180]) > 500, "first run not drawn");
    assert!(count([255, 127, 14]) > 500, "second run not drawn");
    // Bad requests exit 2 and say why.
    let vtu = dir.path().join("snapshot.vtu");
    for (args, needle) in [
        (vec!["plot", &files[0]], "--out"),
        (
            vec!["plot", &files[0], vtu.to_str().unwrap(), "--out", "x.png"],
            "not both",
        ),
        (
            vec!["plot", &files[0], "--field", "speed", "--out", "x.png"],
            "--field",
        ),
    ] {
        let out = sdg(&args);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: {err}");
    }
    // A file without the tip columns is named.
    let other = dir.path().join("other.csv");
    std::fs::write(&other, "t_s,x\n1,2\n").unwrap();
    let out = sdg(&["plot", other.to_str().unwrap(), "--out", "x.png"]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("other.csv") && err.contains("interface"),
        "{err}"
    );
}
