//! Snapshots: time slices cut from the spacetime elements agree with the exact plane wave at
//! every written point (ASCII files), and open in meshio (binary files, the default).

use crate::common;

use std::path::Path;

/// The values of the ASCII `DataArray` whose opening tag contains `marker`.
fn data_array(text: &str, marker: &str) -> Vec<f64> {
    let start = text
        .find(marker)
        .unwrap_or_else(|| panic!("{marker} not found"));
    let body = &text[start..];
    let open = body.find('>').unwrap() + 1;
    let close = body.find("</DataArray>").unwrap();
    body[open..close]
        .split_whitespace()
        .map(|w| w.parse().unwrap())
        .collect()
}

#[test]
fn snapshots_agree_with_the_exact_solution() {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/plane_wave.toml"),
    )
    .unwrap();
    let times = [0.0, 2.5e-7, 5e-7];
    let overrides = common::set(&[
        ("time.end", "5e-7".into()),
        ("output.snapshot_times", format!("{times:?}")),
        ("output.vtu", "\"ascii\"".into()),
    ]);
    let (summary, dir) = common::run(&text, &overrides);
    assert_eq!(summary.snapshots.len(), 3);
    let config = sdg_engine::Config::parse(&text, "plane_wave.toml", &overrides).unwrap();
    let loaded = sdg_engine::LoadedConfig {
        config,
        file: "plane_wave.toml".into(),
        overrides: Vec::new(),
    };
    let problem = sdg_engine::Problem::setup(loaded).unwrap();
    let wave = problem.exact.as_ref().unwrap();
    let stress_scale = problem.material.c_d() * problem.material.density();
    for (t, file) in &summary.snapshots {
        let vtu = std::fs::read_to_string(dir.path().join(file)).unwrap();
        assert!(!vtu.contains("format=\"binary\""));
        let points = data_array(&vtu[vtu.find("<Points>").unwrap()..], "<DataArray");
        let velocity = data_array(&vtu, "Name=\"velocity\"");
        let stress = data_array(&vtu, "Name=\"stress\"");
        let displacement = data_array(&vtu, "Name=\"displacement\"");
        let area: f64 = data_array(&vtu, "Name=\"area\"").iter().sum();
        assert!((area - 1e-4).abs() < 1e-14, "t = {t}: slice area {area}");
        let (mut ev, mut es, mut eu): (f64, f64, f64) = (0.0, 0.0, 0.0);
        for (i, p) in points.chunks(3).enumerate() {
            let exact = wave.state([p[0], p[1]], *t);
            let u = wave.displacement([p[0], p[1]], *t);
            ev = ev.max((velocity[3 * i] - exact[0]).hypot(velocity[3 * i + 1] - exact[1]));
            for (k, c) in [(0, 2), (1, 3), (3, 4)] {
                es = es.max((stress[6 * i + k] - exact[c]).abs() / stress_scale);
            }
            eu = eu.max((displacement[3 * i] - u[0]).hypot(displacement[3 * i + 1] - u[1]));
        }
        // Pointwise at slice corners, for unit velocity amplitude and a wavelength of 10 mm
        // (displacement amplitude 0.76 um).
        eprintln!(
            "t = {t}: max errors velocity {ev:.2e}, stress/Z {es:.2e}, displacement {eu:.2e}"
        );
        assert!(ev < 1e-2 && es < 1e-2 && eu < 1e-2 * 0.76e-6, "t = {t}");
    }
}

#[test]
fn snapshots_open_in_meshio() {
    if !common::meshio_available("meshio reads the snapshots") {
        return;
    }
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/antiplane_pulse.toml"),
    )
    .unwrap();
    let overrides = common::set(&[
        ("time.end", "1e-6".into()),
        ("output.snapshot_times", "[1e-6]".into()),
        ("solver.order", "1".into()),
    ]);
    let (summary, dir) = common::run(&text, &overrides);
    // Shapes, and the largest speed (exact whatever the summation order) to compare bit for bit.
    let script = "import sys, meshio\n\
                  m = meshio.read(sys.argv[1])\n\
                  v = m.point_data['velocity']\n\
                  print(m.cells_dict['triangle'].shape[0], v.shape[1], \
                  m.point_data['stress'].shape[1], m.point_data['strain_energy_density'].ndim, \
                  repr(float(abs(v).max())))";
    let snapshot = dir.path().join(&summary.snapshots[0].1);
    let text = std::fs::read_to_string(&snapshot).unwrap();
    assert!(text.contains("compressor=\"vtkZLibDataCompressor\""));
    assert!(text.contains("format=\"binary\"") && !text.contains("format=\"ascii\""));
    let out = common::python(script, &[&snapshot]);
    let words: Vec<&str> = out.split_whitespace().collect();
    let fields: Vec<usize> = words[..4].iter().map(|w| w.parse().unwrap()).collect();
    assert!(fields[0] >= 800, "{fields:?}");
    assert_eq!(&fields[1..], [3, 6, 1]);
    let ours = sdg_engine::plot::VtuGrid::read(&snapshot).unwrap();
    let velocity = &ours
        .point_data
        .iter()
        .find(|f| f.name == "velocity")
        .unwrap()
        .values;
    let max = velocity.iter().fold(0.0, |m: f64, v| m.max(v.abs()));
    assert!(max > 0.0);
    assert_eq!(words[4].parse::<f64>().unwrap().to_bits(), max.to_bits());
    let pvd = std::fs::read_to_string(dir.path().join("snapshots.pvd")).unwrap();
    assert!(pvd.contains("snapshot_0000.vtu"));
}

#[test]
fn interface_cuts_open_in_meshio() {
    if !common::meshio_available("meshio reads the interface cuts") {
        return;
    }
    // Contact and separation to just after the wave closes the interface; p = 1 for speed.
    let problem = common::shipped(
        "contact_separation.toml",
        &[
            "time.end=1.2e-6",
            "solver.order=1",
            "output.snapshot_times=[1.2e-6]",
        ],
    );
    let (_, dir) = common::solve(&problem, 2, true);
    let file = dir.path().join("cracks_0000.vtu");
    let script = "import sys, meshio\n\
                  m = meshio.read(sys.argv[1])\n\
                  print(m.cells_dict['line'].shape[0], m.point_data['traction'].shape[1], \
                  m.point_data['delta'].ndim, int(m.point_data['mode'].max()))";
    let fields: Vec<usize> = common::python(script, &[&file])
        .split_whitespace()
        .map(|w| w.parse().unwrap())
        .collect();
    // The four interface edges of the 4 mm line, cut once each; tractions as 3-vectors; the
    // faces are in contact (frictionless: slip, mode 1) by then.
    assert_eq!(fields, [4, 3, 1, 1]);
    let pvd = std::fs::read_to_string(dir.path().join("snapshots.pvd")).unwrap();
    assert!(pvd.contains("part=\"1\" file=\"cracks_0000.vtu\""));
}
