//! The region's filing and keeping, against what filing and gathering everything find.

use super::*;
use crate::grid::SpatialHash;
use crate::scene::shapes;

/// The faces a search meets among a few searched vertices' faces filed alone are those it
/// meets among all the region's faces filed: on two sheets, the top one's middle pushed
/// down and sideways unevenly, for several sets of searched vertices.
#[test]
fn filing_near_a_few_searches_meets_what_filing_all_meets() {
    let mesh = shapes::stacked_sheets(2, 24, 24, 2.0, 0.6);
    // Cells far smaller than an edge: a face can meet a search with no corner near it.
    let grid = SpatialHash::build(&mesh, 0.3).unwrap();
    let active = vec![true; mesh.layer_count()];
    let state = StrokeState::for_tests(&grid, &active, mesh.longest_edge() * 1.01);
    let selection = top_sheet_around(&mesh, Vec3::new(24.0, 24.0, 0.0), 9.0);
    let before: Vec<Vec3> = selection
        .iter()
        .map(|&(v, _)| mesh.positions()[v as usize])
        .collect();
    let targets: Vec<Vec3> = (before.iter().enumerate())
        .map(|(i, p)| *p + Vec3::new(0.1 * (i % 3) as f32, 0.0, -0.2 - 0.05 * (i % 5) as f32))
        .collect();
    let mut target_of = vec![INVALID; mesh.vertex_count()];
    for (slot, &(v, _)) in selection.iter().enumerate() {
        target_of[v as usize] = slot as u32;
    }
    let moves = (&selection[..], &targets[..], &target_of[..]);
    let mut all = Region::default();
    all.size_for(&mesh);
    all.gather(&state, &mesh, &selection, &targets, &target_of);
    let slots: Vec<usize> = (0..selection.len()).collect();
    for searched in [
        vec![0],
        vec![5, 6, 7],
        slots.iter().step_by(7).copied().collect(),
    ] {
        let mut near = Region::default();
        near.size_for(&mesh);
        near.gather_unfiled(&state, &mesh, &selection, &targets);
        near.file_faces_near(&state, &mesh, moves, (&before, &searched));
        let filed_near = near.filed == Filing::Near;
        assert!(filed_near, "{} searches filed alone", searched.len());
        let mut scratch = Scratch::default();
        for &slot in &searched {
            let query = Aabb::of_points(&[before[slot], targets[slot]]).expanded(0.5);
            let met = |region: &Region, scratch: &mut Scratch| {
                let mut met = Vec::new();
                let met_one = |local| met.push(region.faces[local]);
                region.candidates((&query, None), scratch, met_one);
                met.sort_unstable();
                met
            };
            let (from_near, from_all) = (met(&near, &mut scratch), met(&all, &mut scratch));
            assert!(!from_all.is_empty(), "slot {slot} meets faces");
            assert_eq!(from_near, from_all, "slot {slot} of {searched:?}");
        }
    }
}

/// The top sheet's vertices within `radius` of `middle` (across the sheet), at full weight.
fn top_sheet_around(mesh: &Mesh, middle: Vec3, radius: f32) -> Vec<(u32, f32)> {
    let top = mesh.layer_count() as u32 - 1;
    (0..mesh.vertex_count() as u32)
        .filter(|&v| mesh.vertex_layers()[v as usize] == top)
        .filter(|&v| (mesh.positions()[v as usize] - middle).truncate().length() < radius)
        .map(|v| (v, 1.0))
        .collect()
}

/// The vertices of the top sheet within `radius` of its middle, pushed down by `by`.
fn step(mesh: &Mesh, radius: f32, by: f32) -> (Vec<(u32, f32)>, Vec<Vec3>) {
    let selection = top_sheet_around(mesh, Vec3::new(12.0, 12.0, 0.0), radius);
    let targets = (selection.iter())
        .map(|&(v, _)| mesh.positions()[v as usize] - Vec3::Z * by)
        .collect();
    (selection, targets)
}

fn move_to(mesh: &mut Mesh, (selection, targets): &(Vec<(u32, f32)>, Vec<Vec3>)) {
    for (&(v, _), &q) in selection.iter().zip(targets) {
        mesh.positions_mut()[v as usize] = q;
    }
}

/// A step keeps the last step's listing where the mesh stands as that step left it and its
/// reach fits (then it holds every face a fresh gathering finds), and not after a vertex
/// it did not list moved, nor where its reach leaves the listing's.
#[test]
fn a_region_is_kept_only_while_nothing_outside_it_moved() {
    let mut mesh = shapes::stacked_sheets(2, 24, 24, 1.0, 0.6);
    let grid = SpatialHash::build(&mesh, 1.0).unwrap();
    let active = vec![true; mesh.layer_count()];
    let state = StrokeState::for_tests(&grid, &active, mesh.longest_edge() * 1.01);
    let mut region = Region::default();
    region.size_for(&mesh);
    type Step = (Vec<(u32, f32)>, Vec<Vec3>);
    let gather = |region: &mut Region, mesh: &Mesh, (selection, targets): &Step| {
        region.forget();
        region.gather_unfiled(&state, mesh, selection, targets);
        region.kept_last
    };
    // The listing leaves room for a move as long again: 0.2 down in all.
    let first = step(&mesh, 4.0, 0.1);
    assert!(
        !gather(&mut region, &mesh, &first),
        "nothing to keep at first"
    );
    move_to(&mut mesh, &first);
    region.step_ended(&mesh);

    let second = step(&mesh, 4.0, 0.05);
    assert!(
        gather(&mut region, &mesh, &second),
        "a next step within reach keeps it"
    );
    let mut fresh = Region::default();
    fresh.size_for(&mesh);
    gather(&mut fresh, &mesh, &second);
    let kept: std::collections::HashSet<u32> = region.faces.iter().copied().collect();
    assert!(
        fresh.faces.iter().all(|f| kept.contains(f)),
        "a kept listing misses a face"
    );
    move_to(&mut mesh, &second);
    region.step_ended(&mesh);

    // Within reach again, but a vertex it did not list moved (the lower sheet's corner).
    mesh.positions_mut()[0].z -= 0.1;
    let third = step(&mesh, 4.0, 0.02);
    assert!(
        !gather(&mut region, &mesh, &third),
        "kept after a vertex outside moved"
    );
    move_to(&mut mesh, &third);
    region.step_ended(&mesh);

    // A wider brush reaches past the listing.
    let wider = step(&mesh, 8.0, 0.0);
    assert!(
        !gather(&mut region, &mesh, &wider),
        "kept for a reach past the listing"
    );
}
