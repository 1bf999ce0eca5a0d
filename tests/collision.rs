//! No interpenetration, measured: seeded random strokes pushing, dragging and twisting upper
//! layers into lower ones, then an exact triangle–triangle test over the whole mesh. Also: the
//! grid backend against the brute-force reference, and the derived neighbourhood ring.

mod common;

use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use slayer::bench::{BrushMix, ScriptSpec, generate_script};
use slayer::brush::{Brush, BrushKind, Falloff, Sample, Stroke};
use slayer::collide::neighbourhood::{exclusion_ring, ring_vertices};
use slayer::collide::{find_intersections, smallest_layer_gap};
use slayer::geom::point_triangle_distance_squared;
use slayer::grid::SpatialHash;
use slayer::mesh::Mesh;
use slayer::pipeline::{Pipeline, PipelineSettings, Remeshing};
use slayer::scene::{SceneKind, SceneSpec, generate, shapes};

/// The brush pipeline without remeshing: these tests are about collisions (and compare vertex
/// by vertex); `tests/remesh.rs` runs torture strokes with remeshing on.
fn sculpt_only() -> PipelineSettings {
    PipelineSettings {
        remeshing: Remeshing::Off,
        ..PipelineSettings::default()
    }
}

fn scene(kind: SceneKind, triangles: usize, seed: u64) -> Mesh {
    generate(&SceneSpec {
        kind,
        triangles,
        seed,
    })
    .unwrap()
}

fn assert_sound(mesh: &Mesh, context: &str) {
    mesh.validate().unwrap_or_else(|e| panic!("{context}: {e}"));
    assert!(
        mesh.positions().iter().all(|p| p.is_finite()),
        "{context}: non-finite position"
    );
    assert!(
        mesh.normals().iter().all(|n| n.is_finite()),
        "{context}: non-finite normal"
    );
    let report = find_intersections(mesh);
    assert_eq!(
        report.between_layers, 0,
        "{context}: layers cross: {:?}",
        report.examples
    );
    assert_eq!(
        report.within_layers, 0,
        "{context}: a layer crosses itself: {:?}",
        report.examples
    );
    assert_eq!(
        report.folded_neighbours, 0,
        "{context}: a face folded onto its neighbour: {:?}",
        report.examples
    );
}

/// A straight push of the upper layers down through everything, at full strength.
fn push_down(mesh: &Mesh, rng: &mut ChaCha8Rng, edge: f32) -> Stroke {
    let (lo, hi) = mesh.bounds().unwrap();
    let at = |t: f32, s: f32| Vec3::new(lo.x + (hi.x - lo.x) * t, lo.y + (hi.y - lo.y) * s, hi.z);
    let (t, s) = (rng.random_range(0.25..0.75), rng.random_range(0.25..0.75));
    let samples = (0..24)
        .map(|k| Sample {
            position: at(t + 0.004 * k as f32, s),
            pressure: 1.0,
            normal: Some(Vec3::Z),
        })
        .collect();
    Stroke {
        paint: None,
        brush: Brush {
            kind: BrushKind::Draw,
            radius: 10.0 * edge,
            strength: 1.0,
            falloff: Falloff::Smooth,
            invert: true,
        },
        layers: (1..mesh.layer_count() as u32).collect(),
        spacing: 0.25,
        symmetry: None,
        samples,
    }
}

// Three hundred random strokes in all, 102 on each material, a test per material so that
// they run side by side.
#[test]
fn random_strokes_on_plaster_leave_no_intersection() {
    random_strokes_leave_no_intersection(SceneKind::Plaster, 11);
}

#[test]
fn random_strokes_on_bark_leave_no_intersection() {
    random_strokes_leave_no_intersection(SceneKind::Bark, 12);
}

#[test]
fn random_strokes_on_metal_leave_no_intersection() {
    random_strokes_leave_no_intersection(SceneKind::Metal, 13);
}

fn random_strokes_leave_no_intersection(kind: SceneKind, seed: u64) {
    let mut mesh = scene(kind, 6_000, seed);
    assert_sound(&mesh, "generated");
    let edge = mesh.mean_edge_length();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let script = generate_script(
        &mesh,
        &ScriptSpec {
            strokes: 90,
            seed,
            samples: 16,
            mix: BrushMix::Torture,
            ..ScriptSpec::default()
        },
    );
    let mut strokes = script.resolve(&mesh, "script").unwrap();
    for _ in 0..12 {
        strokes.push(push_down(&mesh, &mut rng, edge));
    }
    let mut pipeline = Pipeline::new(sculpt_only());
    let mut collisions = 0;
    for (i, stroke) in strokes.iter().enumerate() {
        let report = pipeline.apply_stroke(&mut mesh, stroke).unwrap();
        collisions += report.clamped;
        if i % 10 == 9 {
            assert_sound(
                &mesh,
                &format!("{kind} after stroke {i} ({:?})", stroke.brush.kind),
            );
        }
    }
    assert_sound(&mesh, &format!("{kind} at the end"));
    assert!(
        collisions > 100,
        "{kind}: the strokes must actually collide ({collisions})"
    );
    // The layers started more than 2·d apart, and keep d (the gap guard).
    let d = sculpt_only().collision_distance * pipeline.edge_length().unwrap();
    let gap = smallest_layer_gap(&mesh, 3.0 * d).unwrap();
    assert!(
        gap.is_some_and(|g| g >= 0.99 * d),
        "{kind}: layers came {gap:?} apart (d = {d})"
    );
    assert_eq!(strokes.len(), 102);
}

#[test]
fn a_layer_pushed_down_stops_one_collision_distance_above_the_next() {
    let mut mesh = shapes::stacked_sheets(2, 30, 30, 1.0, 2.5);
    let settings = sculpt_only();
    let mut pipeline = Pipeline::new(settings);
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let edge = mesh.mean_edge_length();
    for _ in 0..4 {
        let stroke = push_down(&mesh, &mut rng, edge);
        pipeline.apply_stroke(&mut mesh, &stroke).unwrap();
    }
    assert_sound(&mesh, "pushed");
    // Closest approach of a top vertex to the bottom sheet.
    let bottom: Vec<[Vec3; 3]> = (0..mesh.face_count())
        .filter(|&f| mesh.face_layers()[f] == 0)
        .map(|f| mesh.face_positions(f))
        .collect();
    let closest = (0..mesh.vertex_count())
        .filter(|&v| mesh.vertex_layers()[v] == 1)
        .map(|v| {
            let p = mesh.positions()[v];
            bottom
                .iter()
                .map(|[a, b, c]| point_triangle_distance_squared(p, *a, *b, *c))
                .fold(f32::MAX, f32::min)
                .sqrt()
        })
        .fold(f32::MAX, f32::min);
    let d = settings.collision_distance * pipeline.edge_length().unwrap();
    assert!(
        closest >= 0.99 * d,
        "came within {closest} of the lower sheet (limit {d})"
    );
    assert!(
        closest <= 1.2 * d,
        "never reached the lower sheet ({closest})"
    );
}

#[test]
fn grid_backend_agrees_with_the_brute_force_reference_bit_for_bit() {
    let base = scene(SceneKind::Plaster, 2_500, 5);
    let script = generate_script(
        &base,
        &ScriptSpec {
            strokes: 12,
            seed: 5,
            samples: 12,
            mix: BrushMix::Torture,
            ..ScriptSpec::default()
        },
    );
    let strokes = script.resolve(&base, "script").unwrap();
    let (mut fast, mut reference) = (base.clone(), base.clone());
    let mut fast_pipeline = Pipeline::new(sculpt_only());
    let mut reference_pipeline = Pipeline::reference(sculpt_only());
    assert_eq!(reference_pipeline.name(), "cpu-reference");
    for (i, stroke) in strokes.iter().enumerate() {
        let a = fast_pipeline.apply_stroke(&mut fast, stroke).unwrap();
        let b = reference_pipeline
            .apply_stroke(&mut reference, stroke)
            .unwrap();
        assert_eq!(
            (a.samples, a.steps, a.moves, a.clamped, a.reverted),
            (b.samples, b.steps, b.moves, b.clamped, b.reverted),
            "stroke {i}"
        );
        assert!(
            fast.positions() == reference.positions(),
            "positions differ after stroke {i}"
        );
    }
    assert!(fast.normals() == reference.normals());
}

#[test]
fn masked_vertices_and_inactive_layers_stay_still() {
    let mut mesh = shapes::stacked_sheets(3, 20, 20, 1.0, 3.0);
    let before = mesh.positions().to_vec();
    let center_vertex = 2 * 441 + 10 * 21 + 10; // middle of the top sheet
    for v in 0..mesh.vertex_count() {
        if mesh.vertex_layers()[v] == 2 && v % 2 == 0 {
            mesh.flags_mut()[v].insert(slayer::mesh::VertexFlags::MASKED);
        }
    }
    let stroke = Stroke {
        paint: None,
        brush: Brush {
            kind: BrushKind::Draw,
            radius: 6.0,
            strength: 1.0,
            falloff: Falloff::Smooth,
            invert: false,
        },
        layers: vec![2, 0],
        spacing: 0.25,
        symmetry: None,
        samples: vec![Sample {
            position: before[center_vertex],
            pressure: 1.0,
            normal: Some(Vec3::Z),
        }],
    };
    let report = Pipeline::new(sculpt_only())
        .apply_stroke(&mut mesh, &stroke)
        .unwrap();
    assert!(report.moves > 0);
    for (v, old) in before.iter().enumerate() {
        let moved = mesh.positions()[v] != *old;
        let layer = mesh.vertex_layers()[v];
        if layer == 1 || (layer == 2 && v % 2 == 0) {
            assert!(!moved, "vertex {v} on layer {layer} moved");
        }
    }
    assert!(
        (0..mesh.vertex_count())
            .any(|v| mesh.vertex_layers()[v] == 2 && mesh.positions()[v] != before[v])
    );
}

/// Same-layer faces outside the exclusion ring that are closer than `distance` to a vertex.
fn false_contacts(mesh: &Mesh, ring: u32, distance: f32) -> usize {
    let grid = SpatialHash::build(mesh, mesh.mean_edge_length()).unwrap();
    let csr = mesh.vertex_faces();
    let max_edge = mesh.edge_length_stats().max as f32;
    let mut near = Vec::new();
    let mut count = 0;
    let mut wide = Vec::new();
    for v in 0..mesh.vertex_count() as u32 {
        // The bound holds where the surface is a sheet all around the vertex; across a narrow
        // notch in an open boundary, the far side is genuinely near and must collide.
        ring_vertices(mesh, v, ring + 1, &mut wide);
        if wide.iter().any(|&u| mesh.is_boundary_vertex(u)) {
            continue;
        }
        ring_vertices(mesh, v, ring, &mut near);
        let p = mesh.positions()[v as usize];
        for f in grid.faces_within(
            mesh.positions(),
            mesh.faces(),
            &csr,
            p,
            distance * 0.999,
            max_edge,
        ) {
            let tri = mesh.faces()[f as usize];
            if mesh.face_layers()[f as usize] == mesh.vertex_layers()[v as usize]
                && !tri.iter().any(|u| near.contains(u))
            {
                count += 1;
            }
        }
    }
    count
}

#[test]
fn the_derived_ring_skips_exactly_the_neighbourhood() {
    // Regular scenes and a jittered sheet whose thin triangles need a wider ring.
    let mut jittered = shapes::stacked_sheets(1, 24, 24, 1.0, 0.0);
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    for p in jittered.positions_mut() {
        *p += Vec3::new(
            rng.random_range(-0.2..0.2),
            rng.random_range(-0.2..0.2),
            0.0,
        );
    }
    jittered.recompute_normals();
    let distance = jittered.mean_edge_length();
    assert!(exclusion_ring(&jittered, distance) > 1);
    assert!(
        false_contacts(&jittered, 1, distance) > 0,
        "the ring that suits a regular mesh is too small for a jittered one: the ring is derived"
    );
    for (name, mesh) in [
        ("plaster", scene(SceneKind::Plaster, 8_000, 2)),
        ("sphere", scene(SceneKind::Sphere, 8_000, 2)),
        ("jittered", jittered),
    ] {
        let distance = mesh.mean_edge_length();
        let ring = exclusion_ring(&mesh, distance);
        assert_eq!(
            false_contacts(&mesh, ring, distance),
            0,
            "{name}: ring {ring} is too small"
        );
    }
}

#[test]
fn a_fold_within_one_layer_still_collides() {
    // A sheet folded over itself: the far part is outside every vertex's ring, so pushing the
    // upper fold down must stop above the lower one.
    let (mut positions, faces) = shapes::grid_patch(40, 6, 1.0, 0.0, glam::Vec2::ZERO);
    for p in &mut positions {
        if p.x > 20.0 {
            // Fold back over the first half, three units up.
            let s = p.x - 20.0;
            let angle = (s / 3.0).min(std::f32::consts::PI);
            let arc = Vec3::new(20.0 + 1.5 * angle.sin(), p.y, 1.5 - 1.5 * angle.cos());
            *p = if s <= 3.0 * std::f32::consts::PI {
                arc
            } else {
                Vec3::new(20.0 - (s - 3.0 * std::f32::consts::PI), p.y, 3.0)
            };
        }
    }
    let layers = vec![0; faces.len()];
    let mut mesh = Mesh::new(positions, faces, layers, vec!["sheet".into()]).unwrap();
    assert_eq!(find_intersections(&mesh).total(), 0);
    let stroke = Stroke {
        paint: None,
        brush: Brush {
            kind: BrushKind::Draw,
            radius: 3.0,
            strength: 1.0,
            falloff: Falloff::Smooth,
            invert: true,
        },
        layers: vec![0],
        spacing: 0.25,
        symmetry: None,
        // Back and forth over the upper fold, so every vertex there is pressed many times.
        samples: (0..=8)
            .map(|k| Sample {
                position: Vec3::new(if k % 2 == 0 { 12.0 } else { 17.0 }, 3.0, 3.0),
                pressure: 1.0,
                normal: Some(Vec3::Z),
            })
            .collect(),
    };
    let report = Pipeline::new(sculpt_only())
        .apply_stroke(&mut mesh, &stroke)
        .unwrap();
    assert!(report.clamped > 0, "the fold collided with itself");
    assert_sound(&mesh, "fold");
}

/// Two edges crossing where no vertex comes within the collision distance of the other face:
/// the proximity clamp sees nothing, and the exact backstop must undo the step that crosses.
#[test]
fn the_backstop_undoes_a_crossing_the_clamp_cannot_see() {
    let (mut mesh, stroke) = common::crossing_edges(1.0);
    let settings = PipelineSettings {
        collision_distance: 0.25,
        ..sculpt_only()
    };
    let start = mesh.clone();
    let report = Pipeline::new(settings)
        .apply_stroke(&mut mesh, &stroke)
        .unwrap();
    assert_eq!(report.clamped, 0, "the clamp saw it: {report:?}");
    assert!(report.reverted > 0, "nothing was undone: {report:?}");
    assert_ne!(mesh.positions(), start.positions(), "the blade moved");
    assert_eq!(find_intersections(&mesh).total(), 0);
    // The case does cross when nothing stops it: the blade's lower edge moved down as far.
    let mut free = start.clone();
    free.positions_mut()[0].z -= 0.5;
    free.positions_mut()[1].z -= 0.5;
    assert!(
        find_intersections(&free).total() > 0,
        "the hand-built case crosses"
    );
}

/// A flat sheet (layer 0, spacing 1) over a thin spike (layer 1) whose tip is 0.6 below the
/// middle of one of the sheet's faces, far (horizontally) from every sheet vertex.
fn sheet_over_a_spike() -> Mesh {
    let (mut positions, mut faces) = shapes::grid_patch(8, 8, 1.0, 0.0, glam::Vec2::ZERO);
    let tip = Vec3::new(4.0 + 2.0 / 3.0, 4.0 + 1.0 / 3.0, -0.6);
    let base = tip - Vec3::Z * 3.0;
    let s = positions.len() as u32;
    positions.push(tip);
    for k in 0..3 {
        let angle = k as f32 * std::f32::consts::TAU / 3.0;
        positions.push(base + 0.15 * Vec3::new(angle.cos(), angle.sin(), 0.0));
    }
    let mut layers = vec![0; faces.len()];
    for tri in [
        [s, s + 1, s + 2],
        [s, s + 2, s + 3],
        [s, s + 3, s + 1],
        [s + 1, s + 3, s + 2],
    ] {
        faces.push(tri);
        layers.push(1);
    }
    Mesh::new(
        positions,
        faces,
        layers,
        vec!["sheet".into(), "spike".into()],
    )
    .unwrap()
}

#[test]
fn a_face_pushed_onto_a_still_vertex_of_another_layer_keeps_its_distance() {
    let mut mesh = sheet_over_a_spike();
    let settings = PipelineSettings {
        collision_distance: 0.25,
        ..sculpt_only()
    };
    let tip = mesh.vertex_count() - 4;
    let centre = Vec3::new(4.5, 4.5, 0.0);
    let path: Vec<Vec3> = (0..24)
        .map(|k| centre + Vec3::X * if k % 2 == 0 { 0.1 } else { -0.1 })
        .collect();
    let mut stroke = common::one_brush_stroke(BrushKind::Draw, 2.0, &path);
    stroke.brush.invert = true;
    let mut pipeline = Pipeline::new(settings);
    let report = pipeline.apply_stroke(&mut mesh, &stroke).unwrap();
    assert_sound(&mesh, "sheet over a spike");
    let d = settings.collision_distance * pipeline.edge_length().unwrap();
    let p = mesh.positions()[tip];
    let gap = (0..mesh.face_count())
        .filter(|&f| mesh.face_layers()[f] == 0)
        .map(|f| {
            let [a, b, c] = mesh.face_positions(f);
            point_triangle_distance_squared(p, a, b, c).sqrt()
        })
        .fold(f32::MAX, f32::min);
    let lowest = (0..tip)
        .map(|v| mesh.positions()[v].z)
        .fold(f32::MAX, f32::min);
    assert!(
        lowest < -0.5,
        "the sheet came down to the tip ({lowest}): {report:?}"
    );
    assert!(
        gap >= (1.0 - 1.0 / 1024.0) * d,
        "the sheet came within {gap} of the spike's tip (d = {d}): {report:?}"
    );
}
