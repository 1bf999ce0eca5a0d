//! Scale: once a mesh is prepared, a stroke allocates what its brush covers, not what the mesh
//! holds; the edge bound comes back down after a grab stretched edges. Memory is counted by
//! installing the allocator `slayer` installs.

use slayer::bench::{BrushMix, ScriptSpec, generate_script};
use slayer::brush::Stroke;
use slayer::mesh::Mesh;
use slayer::pipeline::{Pipeline, PipelineSettings};
use slayer::scene::{SceneKind, SceneSpec, generate};

#[global_allocator]
static HEAP: slayer::memory::Counting = slayer::memory::Counting;

/// The counters are the process's: tests that read them run one at a time.
static COUNTING: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn alone() -> std::sync::MutexGuard<'static, ()> {
    COUNTING.lock().unwrap_or_else(|e| e.into_inner())
}

fn plaster(triangles: usize) -> Mesh {
    generate(&SceneSpec {
        kind: SceneKind::Plaster,
        triangles,
        seed: 3,
    })
    .unwrap()
}

fn strokes(mesh: &Mesh, count: usize, mix: BrushMix) -> Vec<Stroke> {
    let spec = ScriptSpec {
        strokes: count,
        seed: 5,
        mix,
        ..ScriptSpec::default()
    };
    generate_script(mesh, &spec)
        .resolve(mesh, "script")
        .unwrap()
}

fn longest_edge(mesh: &Mesh) -> f32 {
    mesh.edge_length_stats().max as f32
}

#[test]
fn the_counting_allocator_sees_a_large_allocation_and_its_peak() {
    let _alone = alone();
    // 64 MiB against a margin of 16: other threads (rayon's, from earlier tests) may free a
    // little meanwhile.
    let before = slayer::memory::live_bytes().unwrap();
    slayer::memory::reset_peak();
    let block = std::hint::black_box(vec![1u8; 64 << 20]);
    assert!(slayer::memory::live_bytes().unwrap() >= before + (48 << 20));
    drop(std::hint::black_box(block));
    assert!(slayer::memory::peak_bytes().unwrap() >= before + (48 << 20));
}

/// The most heap a stroke holds above the prepared state, over the script's strokes, on
/// plaster of `triangles` faces.
fn stroke_heap(triangles: usize) -> usize {
    let mut mesh = plaster(triangles);
    let strokes = strokes(&mesh, 4, BrushMix::Bench);
    let mut pipeline = Pipeline::new(PipelineSettings::default());
    pipeline.prepare(&mesh).unwrap();
    let mut most = 0;
    for stroke in &strokes {
        let before = slayer::memory::live_bytes().unwrap();
        slayer::memory::reset_peak();
        let report = pipeline.apply_stroke(&mut mesh, stroke).unwrap();
        assert!(report.moves > 0, "the stroke moved nothing");
        most = most.max(slayer::memory::peak_bytes().unwrap() - before);
    }
    most
}

#[test]
fn a_prepared_stroke_allocates_for_its_brush_not_for_the_mesh() {
    let _alone = alone();
    // The scripts' brushes are 12 L wide at every size: the same work on 64 times the faces.
    let (small, large) = (stroke_heap(20_000), stroke_heap(1_280_000));
    eprintln!("a stroke's heap: {small} bytes at 20K faces, {large} at 1.28M");
    assert!(
        large < 2 * small,
        "a stroke held {large} bytes at 1.28M faces, {small} at 20K: it grows with the mesh"
    );
}

#[test]
fn the_edge_bound_holds_and_comes_back_down_after_a_grab() {
    let _alone = alone();
    let mut mesh = plaster(40_000);
    let strokes = strokes(&mesh, 12, BrushMix::InflateGrab);
    let mut pipeline = Pipeline::new(PipelineSettings::default());
    pipeline.prepare(&mesh).unwrap();
    for stroke in &strokes {
        pipeline.apply_stroke(&mut mesh, stroke).unwrap();
        let (bound, longest) = (pipeline.edge_bound().unwrap(), longest_edge(&mesh));
        assert!(
            bound >= longest,
            "bound {bound} below the longest edge {longest}"
        );
        // Tightened at each stroke's end: no stretch that remeshing undid stays in it.
        assert!(
            bound <= 2.0 * longest,
            "bound {bound} far above the longest edge {longest}"
        );
    }
}
