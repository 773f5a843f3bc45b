use super::*;
use crate::output::snapshot::files::remove_earlier;
use crate::output::snapshot::slicing::signed_area;

#[test]
fn an_earlier_run_s_snapshot_files_are_removed_and_nothing_else() {
    let dir = tempfile::tempdir().unwrap();
    let removed = [
        "snapshot_0000.vtu",
        "snapshot_0012.png",
        "snapshot_12345.vtu",
        "cracks_0003.vtu",
        "snapshots.pvd",
        "snapshot_0004.pvtu",
        "snapshot_0004_0.vtu",
        "snapshot_0004_12.vtu",
    ];
    let kept = [
        "summary.json",
        "snapshot_notes.txt",
        "snapshot_.vtu",
        "snapshot_0001.vtu.bak",
        "cracks_0003.png",
        "my_snapshot_0001.vtu",
        "crack_path.png",
        "snapshot_0004_x.vtu",
        "snapshot_0004_1.png",
        "snapshot_0004_1_2.vtu",
    ];
    for name in removed.iter().chain(&kept) {
        std::fs::write(dir.path().join(name), b"x").unwrap();
    }
    std::fs::create_dir(dir.path().join("snapshot_0002.vtu")).unwrap();
    assert_eq!(remove_earlier(dir.path()).unwrap(), removed.len());
    for name in removed {
        assert!(!dir.path().join(name).exists(), "{name} left");
    }
    for name in kept.iter().chain(&["snapshot_0002.vtu"]) {
        assert!(dir.path().join(name).exists(), "{name} removed");
    }
    assert_eq!(remove_earlier(dir.path()).unwrap(), 0);
}

/// Unit square: 4 vertices, 2 counter-clockwise triangles.
const SQUARE: [[f64; 2]; 4] = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
const TRIANGLES: [[usize; 3]; 2] = [[0, 1, 2], [0, 2, 3]];

/// Tetrahedra tiling the square times the layers between consecutive fronts (`fronts[k][v]`
/// is the tau of vertex `v` on front `k`, increasing in `k`). Each prism is split into three
/// tetrahedra by vertex index, which makes the splits of shared faces agree.
fn tets(fronts: &[[f64; 4]]) -> Vec<[[f64; 3]; 4]> {
    let mut out = Vec::new();
    for layer in fronts.windows(2) {
        for tri in TRIANGLES {
            let mut t = tri;
            t.sort_unstable();
            let [a, b, c] = t;
            let lo = |v: usize| [SQUARE[v][0], SQUARE[v][1], layer[0][v]];
            let hi = |v: usize| [SQUARE[v][0], SQUARE[v][1], layer[1][v]];
            out.push([lo(a), lo(b), lo(c), hi(c)]);
            out.push([lo(a), lo(b), hi(b), hi(c)]);
            out.push([lo(a), hi(a), hi(b), hi(c)]);
        }
    }
    out
}

fn linear(p: [f64; 3]) -> PointValues {
    let [x, y, tau] = p;
    PointValues {
        velocity: [1.0 + 2.0 * x - y, 3.0 * y + tau, -tau],
        stress: [x, y, tau, x + y, y - tau, 2.0 * x + 0.5 * tau],
        displacement: [x * 0.25, -y, x + y + tau],
        strain_energy_density: 7.0 - x + 4.0 * tau,
    }
}

/// Reads `file`, checks that the corner values are `linear` at `tau` and returns the total
/// triangle area and the number of triangles.
fn check_file(dir: &std::path::Path, file: &str, tau: f64) -> (f64, usize) {
    let grid = crate::plot::VtuGrid::read(&dir.join(file)).unwrap();
    let field = |name: &str| {
        let mut fields = grid.point_data.iter().chain(&grid.cell_data);
        fields.find(|f| f.name == name).unwrap().values.clone()
    };
    let points: Vec<f64> = grid.points.iter().flatten().copied().collect();
    let velocity = field("velocity");
    let stress = field("stress");
    let displacement = field("displacement");
    let sed = field("strain_energy_density");
    let areas = field("area");
    let n = points.len() / 3;
    assert_eq!(n % 3, 0);
    assert_eq!(velocity.len(), 3 * n);
    assert_eq!(stress.len(), 6 * n);
    assert_eq!(areas.len(), n / 3);
    for k in 0..n {
        let p = [points[3 * k], points[3 * k + 1], tau];
        assert_eq!(points[3 * k + 2], 0.0);
        let want = linear(p);
        let close = |a: &[f64], b: &[f64]| a.iter().zip(b).all(|(a, b)| (a - b).abs() <= 1e-12);
        assert!(close(&velocity[3 * k..3 * k + 3], &want.velocity));
        assert!(close(&stress[6 * k..6 * k + 6], &want.stress));
        assert!(close(&displacement[3 * k..3 * k + 3], &want.displacement));
        assert!((sed[k] - want.strain_energy_density).abs() <= 1e-12);
    }
    let mut total = 0.0;
    for (c, &area) in areas.iter().enumerate() {
        let q = |i: usize| [points[9 * c + 3 * i], points[9 * c + 3 * i + 1]];
        let a = signed_area(q(0), q(1), q(2));
        assert!(a > 0.0, "triangle {c} of {file} is not counter-clockwise");
        assert_eq!(a, area);
        total += a;
    }
    (total, n / 3)
}

fn timesteps(pvd: &str) -> Vec<(f64, String)> {
    pvd.lines()
        .filter(|l| l.starts_with("<DataSet"))
        .map(|l| {
            let attr = |k: &str| {
                let s = &l[l.find(k).unwrap() + k.len()..];
                s[..s.find('"').unwrap()].to_string()
            };
            (attr("timestep=\"").parse().unwrap(), attr("file=\""))
        })
        .collect()
}

const TIMES: [f64; 5] = [0.0, 0.3, 1.0, 1.7, 2.0];

#[test]
fn elements_between_pending_planes_are_told_apart_from_those_they_cut() {
    let dir = tempfile::tempdir().unwrap();
    let mut snaps = Snapshots::new(&[0.3, 1.0], 2.0, dir.path().to_path_buf());
    assert!(snaps.pending_within(0.1, 0.3), "touches the first plane");
    assert!(snaps.pending_within(0.2, 0.5));
    assert!(snaps.pending_within(0.9, 1.2));
    assert!(!snaps.pending_within(0.0, 0.29));
    assert!(!snaps.pending_within(0.31, 0.99), "between the planes");
    assert!(!snaps.pending_within(1.01, 2.0));
    assert_eq!(snaps.flush(0.5).unwrap(), 1);
    assert!(!snaps.pending_within(0.1, 0.5), "the first is written");
    assert!(snaps.pending_within(0.5, 1.0));
}

/// Feeds `elements` in the given order and checks the five snapshots of `TIMES`.
fn run(elements: &[[[f64; 3]; 4]]) {
    let dir = tempfile::tempdir().unwrap();
    // Unsorted, with a duplicate.
    let times = [1.7, 0.3, 2.0, 0.0, 1.0, 0.3];
    let mut snaps = Snapshots::new(&times, 1.0, dir.path().to_path_buf());
    assert_eq!(snaps.flush(0.0).unwrap(), 0, "start-time snapshot waits");
    for e in elements {
        snaps.add_element(e, linear);
    }
    assert_eq!(snaps.flush(0.5).unwrap(), 2);
    snaps.finish().unwrap();
    let names = ["snapshot_0000.vtu", "snapshot_0001.vtu"];
    assert_eq!(
        snaps.written(),
        &[(0.0, names[0].to_string()), (0.3, names[1].to_string())]
    );
    assert!(!dir.path().join("snapshot_0002.vtu").exists());
    let pvd = std::fs::read_to_string(dir.path().join("snapshots.pvd")).unwrap();
    assert_eq!(timesteps(&pvd).len(), 2);

    assert_eq!(snaps.flush(2.0).unwrap(), 3);
    assert_eq!(snaps.flush(2.0).unwrap(), 0);
    snaps.finish().unwrap();
    let pvd = std::fs::read_to_string(dir.path().join("snapshots.pvd")).unwrap();
    let listed = timesteps(&pvd);
    assert_eq!(listed.len(), 5);
    for (i, (time, file)) in listed.iter().enumerate() {
        assert_eq!(*time, TIMES[i]);
        assert_eq!(file, &format!("snapshot_{i:04}.vtu"));
        let (area, _) = check_file(dir.path(), file, TIMES[i]);
        assert!((area - 1.0).abs() <= 1e-12, "t = {time}: area {area}");
    }
    assert_eq!(snaps.written().len(), 5);
    assert!(snaps.snapshots.iter().all(|s| s.triangles.capacity() == 0));
}

#[test]
fn retimed_snapshots_keep_what_is_written_and_collected() {
    let dir = tempfile::tempdir().unwrap();
    let mut snaps = Snapshots::new(&[0.3, 1.0, 1.7], 1.0, dir.path().to_path_buf());
    for e in tets(&[[0.0; 4], [1.2; 4]]) {
        snaps.add_element(&e, linear);
    }
    assert_eq!(snaps.flush(0.5).unwrap(), 1);
    snaps.finish().unwrap();
    let before = format!("{snaps:?}");
    // 0.5 is new and the front has reached 1.2: refused, nothing changed.
    assert_eq!(snaps.retime(&[0.3, 0.5, 1.0, 2.5], 0.0, 1.2), Err(0.5));
    assert_eq!(format!("{snaps:?}"), before);
    // 1.7 dropped, 1.0 kept with its slices, 2.5 and 3.0 new (numbered after 1.7's 2).
    snaps.retime(&[3.0, 1.0, 0.3, 2.5], 0.0, 1.2).unwrap();
    let pending: Vec<(usize, f64, usize)> = (snaps.snapshots[snaps.next..].iter())
        .map(|s| (s.index, s.time, s.triangles.len()))
        .collect();
    assert_eq!(pending, [(1, 1.0, 8), (3, 2.5, 0), (4, 3.0, 0)]);
    assert_eq!(snaps.written()[0].1, "snapshot_0000.vtu");
}

#[test]
fn flat_layers_are_sliced_exactly_once() {
    let elements = tets(&[[0.0; 4], [1.0; 4], [2.0; 4]]);
    run(&elements);
    // Reversed order: the bottom faces of the upper layer at tau = 1 arrive first and must
    // be dropped once the top faces of the lower layer come.
    let reversed: Vec<_> = elements.into_iter().rev().collect();
    run(&reversed);
}

#[test]
fn flat_front_slices_are_the_faces_in_the_plane() {
    let dir = tempfile::tempdir().unwrap();
    let mut snaps = Snapshots::new(&TIMES, 1.0, dir.path().to_path_buf());
    for e in tets(&[[0.0; 4], [1.0; 4], [2.0; 4]]) {
        snaps.add_element(&e, linear);
    }
    // tau = 0, 1, 2: the two square triangles (one face per prism); tau = 0.3: 4 per prism.
    let counts: Vec<usize> = snaps.snapshots.iter().map(|s| s.triangles.len()).collect();
    assert_eq!(counts, [0, 8, 2, 8, 2]);
    assert_eq!(snaps.snapshots[0].fallback.len(), 2);
    assert!(snaps.snapshots[2].fallback.is_empty());
}

#[test]
fn curved_fronts_tile_every_plane() {
    // The middle front is not flat: planes at 0.95..1.15 cut both layers.
    let fronts = [[0.0; 4], [0.9, 1.2, 1.0, 1.1], [2.0; 4]];
    let elements = tets(&fronts);
    let times = [0.5, 0.9, 0.95, 1.0, 1.05, 1.1, 1.15, 1.2, 1.5];
    let dir = tempfile::tempdir().unwrap();
    // c_ref = 2: tau = 2 t.
    let times_s: Vec<f64> = times.iter().map(|t| t / 2.0).collect();
    let mut snaps =
        Snapshots::new(&times_s, 2.0, dir.path().to_path_buf()).with_vtu(VtuFormat::Ascii);
    for e in &elements {
        snaps.add_element(e, linear);
    }
    assert_eq!(snaps.flush(1.0).unwrap(), times.len());
    snaps.finish().unwrap();
    for (i, (time, file)) in snaps.written().iter().enumerate() {
        assert_eq!(*time, times_s[i]);
        let text = std::fs::read_to_string(dir.path().join(file)).unwrap();
        assert!(text.contains("format=\"ascii\"") && !text.contains("format=\"binary\""));
        let (area, _) = check_file(dir.path(), file, times[i]);
        assert!(
            (area - 1.0).abs() <= 1e-12,
            "tau = {}: area {area}",
            times[i]
        );
    }
}

#[test]
fn files_are_written_off_the_caller_and_their_errors_come_at_finish() {
    let file = tempfile::NamedTempFile::new().unwrap();
    // A folder inside a file cannot be made: every write fails.
    let mut snaps = Snapshots::new(&[0.3], 1.0, file.path().join("out"));
    for e in tets(&[[0.0; 4], [1.0; 4]]) {
        snaps.add_element(&e, linear);
    }
    assert_eq!(snaps.flush(1.0).unwrap(), 1, "the caller does not wait");
    assert_eq!(snaps.written().len(), 1);
    let e = snaps.finish().unwrap_err();
    assert!(e.to_string().contains("out"), "{e}");
    assert!(snaps.finish().is_ok(), "reported once");
}

#[test]
fn a_failed_snapshot_is_not_listed_and_the_next_flush_reports_it() {
    let dir = tempfile::tempdir().unwrap();
    // A folder that is not empty where the file should go: its rename fails.
    std::fs::create_dir_all(dir.path().join("snapshot_0000.vtu").join("x")).unwrap();
    let mut snaps = Snapshots::new(&[0.3, 0.6], 1.0, dir.path().to_path_buf());
    for e in tets(&[[0.0; 4], [1.0; 4]]) {
        snaps.add_element(&e, linear);
    }
    assert_eq!(snaps.flush(0.4).unwrap(), 1);
    let waited = std::time::Instant::now();
    while !snaps.writer.as_ref().is_some_and(Writer::has_failed) {
        assert!(waited.elapsed().as_secs() < 30, "the write never failed");
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    let e = snaps.flush(1.0).unwrap_err();
    assert!(e.to_string().contains("snapshot_0000.vtu"), "{e}");
    assert_eq!(
        snaps.flush(1.0).unwrap(),
        0,
        "reported once, then nothing written"
    );
    snaps.finish().unwrap();
    assert!(!dir.path().join("snapshots.pvd").exists());
    assert!(!dir.path().join("snapshot_0001.vtu").exists());
}

#[test]
fn elements_away_from_the_planes_are_skipped() {
    let dir = tempfile::tempdir().unwrap();
    let mut snaps = Snapshots::new(&[5.0], 1.0, dir.path().to_path_buf());
    let mut calls = 0;
    for e in tets(&[[0.0; 4], [1.0; 4]]) {
        snaps.add_element(&e, |p| {
            calls += 1;
            linear(p)
        });
    }
    assert_eq!(calls, 0);
    assert_eq!(snaps.flush(1.0).unwrap(), 0);
    assert!(snaps.written().is_empty());
    assert!(!dir.path().join("snapshots.pvd").exists());
}

#[test]
fn meshio_reads_a_snapshot() {
    let have_meshio = std::process::Command::new("python3")
        .args(["-c", "import meshio"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !have_meshio {
        assert!(
            std::env::var_os("CI").is_none(),
            "meshio is required on CI (python3 -c 'import meshio' failed)"
        );
        eprintln!("skipping: python3 with meshio not available");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let mut snaps = Snapshots::new(&[0.3], 1.0, dir.path().to_path_buf());
    for e in tets(&[[0.0; 4], [1.0; 4]]) {
        snaps.add_element(&e, linear);
    }
    snaps.flush(1.0).unwrap();
    snaps.finish().unwrap();
    let path = dir.path().join(&snaps.written()[0].1);
    let script = "import sys, meshio\n\
                  m = meshio.read(sys.argv[1])\n\
                  print(sum(len(b.data) for b in m.cells), m.cells[0].type)\n\
                  for k in ('velocity', 'stress', 'displacement', 'strain_energy_density'):\n    \
                      print(k, *m.point_data[k].shape)\n";
    let out = std::process::Command::new("python3")
        .args(["-c", script])
        .arg(&path)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines[0], "8 triangle");
    assert_eq!(lines[1], "velocity 24 3");
    assert_eq!(lines[2], "stress 24 6");
    assert_eq!(lines[3], "displacement 24 3");
    assert_eq!(lines[4], "strain_energy_density 24");
}

/// A rank's piece with the interface's cut: written as `snapshot_0000_1.vtu` and
/// `cracks_0000_1.vtu`; a checkpoint taken before the other rank wrote its piece puts both the
/// slices and the segment back (`rewound`), through the bytes a checkpoint gathers
/// (`pending_cbor`, `add_pending`), and forgets the crack file with the snapshot.
#[test]
fn a_piece_s_slices_and_crack_segments_are_written_and_rewound_together() {
    let dir = tempfile::tempdir().unwrap();
    let piece = Piece {
        rank: 1,
        ranks: 2,
        cuts: true,
    };
    let mut snaps = Snapshots::new(&[0.3], 1.0, dir.path().to_path_buf()).with_piece(piece);
    for e in tets(&[[0.0; 4], [1.2; 4]]) {
        snaps.add_element(&e, linear);
    }
    let values = [InterfaceValues {
        delta: 1e-6,
        ..InterfaceValues::default()
    }; 2];
    snaps.add_interface_segment(0.3, [[0.0, 0.5], [1.0, 0.5]], values);
    assert_eq!(snaps.flush(0.5).unwrap(), 1);
    snaps.finish().unwrap();
    for name in ["snapshot_0000_1.vtu", "cracks_0000_1.vtu"] {
        assert!(dir.path().join(name).exists(), "{name}");
    }
    assert!(!dir.path().join("cracks_0000.pvtu").exists(), "rank 0's");
    let rewound = snaps.rewound(0);
    let pending = &rewound.snapshots[0];
    assert_eq!((pending.triangles.len(), pending.segments.len()), (8, 1));
    assert!(rewound.crack_files.is_empty() && rewound.written.is_empty());
    let (next, bytes) = snaps.pending_cbor();
    let mut gathered = Snapshots::new(&[0.3], 1.0, dir.path().to_path_buf());
    gathered.add_pending(&bytes).unwrap();
    assert_eq!(next, 1);
    assert_eq!(gathered.snapshots[0].segments.len(), 1);
    assert_eq!(gathered.snapshots[0].segments[0].values, values);
}
