use super::*;
use sdg_mesh::VertexId;

fn tent(id: u64, duration_s: f64, deps: &[u64]) -> Entry {
    Entry {
        id,
        kind: Kind::Patch,
        vertex: Some(id as VertexId),
        start_s: 0.0,
        duration_s,
        deps: deps.to_vec(),
    }
}

#[test]
fn the_replay_follows_dependencies_workers_and_events() {
    // Two independent chains of two unit tents, then an event of 0.5 s, then one tent.
    let mut entries = vec![
        tent(0, 1.0, &[]),
        tent(1, 1.0, &[]),
        tent(2, 1.0, &[0]),
        tent(3, 1.0, &[1]),
    ];
    entries.push(Entry {
        kind: Kind::Event,
        vertex: None,
        ..tent(4, 0.5, &[])
    });
    entries.push(tent(5, 1.0, &[4]));
    let one = replay(&entries, 1, 0.0);
    assert_eq!(one.wall_time_s, 5.5);
    let two = replay(&entries, 2, 0.0);
    assert_eq!(two.wall_time_s, 3.5);
    assert_eq!(replay(&entries, 8, 0.0).wall_time_s, 3.5);
    assert_eq!(critical_path(&entries, 0.0), 3.5);
    let parts = critical_path_parts(&entries, 0.0);
    assert_eq!(
        (parts.tents_s, parts.events_s, parts.scheduler_s),
        (3.0, 0.5, 0.0)
    );
    // One worker: one tent waits while the other runs, for the first three tents.
    assert!(
        (one.mean_ready - 3.0 / 5.5).abs() < 1e-12,
        "{}",
        one.mean_ready
    );
    assert_eq!(replay(&entries, 2, 0.25).wall_time_s, 4.25);
}

/// A regional event waits only for its dependencies and takes one worker; an event of the
/// other kind still runs alone.
#[test]
fn the_replay_lets_other_tents_run_beside_a_region_event() {
    let event = |id: u64, duration_s: f64, kind: Kind, deps: &[u64]| Entry {
        kind,
        vertex: None,
        ..tent(id, duration_s, deps)
    };
    let entries = vec![
        tent(0, 1.0, &[]),
        tent(1, 2.0, &[]),
        event(2, 0.5, Kind::Region, &[0]),
        tent(3, 1.0, &[2]),
        event(4, 0.25, Kind::Event, &[]),
        tent(5, 1.0, &[]),
    ];
    assert_eq!(regions(&entries), 1);
    // Tent 1 runs beside the event and tent 3 (1 + 0.5 + 1), then 0.25 + 1.
    assert_eq!(replay(&entries, 2, 0.0).wall_time_s, 3.75);
    assert_eq!(critical_path(&entries, 0.0), 3.75);
    let parts = critical_path_parts(&entries, 0.0);
    assert_eq!((parts.tents_s, parts.events_s), (3.5, 0.25));
    // One worker does everything in turn.
    assert_eq!(replay(&entries, 1, 0.0).wall_time_s, 5.75);
}

/// Two rounds: three unit tents, an event of 0.5 s and 0.25 s of the scheduler's own; then
/// one tent of 2 s and 0.25 s.
#[test]
fn the_rounds_replay_hands_each_round_s_tents_to_free_workers() {
    let marker = |id: u64, duration_s: f64, kind: Kind| Entry {
        kind,
        vertex: None,
        ..tent(id, duration_s, &[])
    };
    let entries = vec![
        tent(0, 1.0, &[]),
        tent(1, 1.0, &[]),
        tent(2, 1.0, &[]),
        marker(3, 0.5, Kind::Event),
        marker(4, 0.25, Kind::Round),
        tent(5, 2.0, &[]),
        marker(6, 0.25, Kind::Round),
    ];
    assert_eq!(rounds(&entries), 2);
    let wall = |workers, overhead| replay(&entries, workers, overhead).wall_time_s;
    assert_eq!(wall(1, 0.0), 6.0);
    assert_eq!(wall(2, 0.0), 5.0);
    assert_eq!(wall(8, 0.0), 4.0);
    assert_eq!(critical_path(&entries, 0.0), 4.0);
    let parts = critical_path_parts(&entries, 0.0);
    assert_eq!(
        (parts.tents_s, parts.events_s, parts.scheduler_s),
        (3.0, 0.5, 0.5)
    );
    // Two workers: the third tent of the first round waits 1 s.
    assert_eq!(replay(&entries, 2, 0.0).mean_ready, 1.0 / 5.0);
    assert_eq!(wall(2, 0.5), 6.5);
}

#[test]
fn the_rounds_replay_shares_the_settling_chunks_after_the_tents() {
    let marker = |id: u64, duration_s: f64, kind: Kind| Entry {
        kind,
        vertex: None,
        ..tent(id, duration_s, &[])
    };
    // One round: two unit tents, three settling chunks of 0.5, 0.5 and 0.25 s, then 0.25 s of
    // the scheduler alone.
    let entries = vec![
        tent(0, 1.0, &[]),
        tent(1, 1.0, &[]),
        marker(2, 0.5, Kind::Settle),
        marker(3, 0.5, Kind::Settle),
        marker(4, 0.25, Kind::Settle),
        marker(5, 0.25, Kind::Round),
    ];
    let wall = |workers| replay(&entries, workers, 0.0).wall_time_s;
    assert_eq!(wall(1), 3.5);
    assert_eq!(wall(2), 2.0);
    assert_eq!(wall(8), 1.75);
    let parts = critical_path_parts(&entries, 0.0);
    assert_eq!(
        (parts.tents_s, parts.events_s, parts.scheduler_s),
        (1.0, 0.0, 0.75)
    );
    assert_eq!(critical_path(&entries, 0.0), 1.75);
}

#[test]
fn a_written_trace_reads_back_and_bad_ones_are_refused() {
    let tracer = Tracer::new();
    let mesh = sdg_mesh::Rectangle {
        width: 1.0,
        height: 1.0,
        nx: 2,
        ny: 2,
        diagonal: sdg_mesh::Diagonal::Right,
        interfaces: Vec::new(),
        sides: Vec::new(),
        perturb: 0.0,
        seed: 0,
    }
    .build()
    .unwrap();
    let a = tracer.begin(&mesh, 0);
    tracer.end(a, 0, Kind::Patch, true);
    tracer.event(|| ());
    let b = tracer.begin(&mesh, 1);
    tracer.end(b, 1, Kind::Newton, true);
    let rejected = tracer.begin(&mesh, 8);
    tracer.end(rejected, 8, Kind::Rejected, false);
    let region = tracer.begin_region();
    tracer.end_region(region, &mesh, &[8], None);
    let c = tracer.begin(&mesh, 0);
    tracer.end(c, 0, Kind::Patch, true);
    let d = tracer.begin(&mesh, 5);
    tracer.end(d, 5, Kind::Patch, true);
    tracer.settled(std::time::Duration::from_micros(2));
    tracer.round(std::time::Duration::from_micros(3));
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("trace.csv");
    tracer.write(&path).unwrap();
    let entries = read(&path).unwrap();
    let kinds: Vec<Kind> = entries.iter().map(|e| e.kind).collect();
    assert_eq!(
        kinds,
        [
            Kind::Patch,
            Kind::Event,
            Kind::Newton,
            Kind::Rejected,
            Kind::Region,
            Kind::Patch,
            Kind::Patch,
            Kind::Settle,
            Kind::Round
        ]
    );
    assert_eq!(entries[7].duration_s, 2e-6);
    assert_eq!(entries[8].duration_s, 3e-6);
    assert_eq!(rounds(&entries), 1);
    // Tents depend on the last tents at their vertex and its neighbours (vertices 0, 1, 3
    // and 4 of the 3 x 3 grid are neighbours), across an event that holds the whole state.
    assert_eq!(entries[2].deps, [0]);
    // The regional event at the corner 8 depends on the rejected tent there (its
    // neighbours 5 and 7 have had none); the later tent at 5 depends on the event and on
    // the tent at its diagonal neighbour 1.
    assert_eq!(entries[4].deps, [3]);
    assert_eq!(entries[5].deps, [0, 2]);
    assert_eq!(entries[6].deps, [2, 4]);
    std::fs::write(&path, "id,kind\n").unwrap();
    assert!(read(&path).unwrap_err().to_string().contains("header"));
    std::fs::write(
        &path,
        "id,kind,vertex,start_s,duration_s,deps\n0,patch,0,0,1,3\n",
    )
    .unwrap();
    assert!(
        read(&path)
            .unwrap_err()
            .to_string()
            .contains(":2: a dependency on a later")
    );
}
