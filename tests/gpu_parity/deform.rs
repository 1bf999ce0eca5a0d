//! `deform` against its mirror and the brush fields, with whole and paged neighbours, and with
//! the frame taken from `brush_frame`'s sums.

use glam::Vec3;
use slayer::brush::{Brush, BrushKind, Dab, DabFrame, Falloff};
use slayer::gpu::{SelectedVertex, deform_params, run_deform, smoothing_neighbours};
use slayer::grid::SpatialHash;

use crate::common::{
    Binding, FALLOFFS, SIZES, binding_limit_paging, bumpy_sheets, gpu, gpu_with_binding_limit,
    selection_under, worst_relative,
};

/// Deformation targets may differ by this share of the brush radius: the shader's sin/cos,
/// sqrt and fused multiply-adds round differently from the CPU's.
const DEFORM_TOLERANCE: f32 = 1e-5;

#[test]
fn deform_matches_cpu_mirror_and_the_brush_fields() {
    check_deform(Binding::Whole);
}

#[test]
fn deform_reads_neighbours_split_over_several_bindings() {
    check_deform(Binding::Paged);
}

fn check_deform(binding: Binding) {
    // Every deforming brush, alternately inverted, over the falloffs; each on the full
    // selection (a large odd size) and on a prefix of an awkward size. The mirror is checked
    // against `pipeline::step::deform` (src/brush/field.rs), the GPU against the mirror.
    let mesh = bumpy_sheets();
    let mut gpu = match binding {
        Binding::Whole => gpu(),
        Binding::Paged => {
            // Whole: positions, normals and targets, 12 bytes a vertex at most.
            let unpaged = 12 * mesh.vertex_count() as u64;
            let neighbours = smoothing_neighbours(&mesh, 0).words.len() as u64 * 4;
            gpu_with_binding_limit(binding_limit_paging(unpaged, &[neighbours]))
        }
    };
    let grid = SpatialHash::build(&mesh, 0.05).unwrap();
    let active = [true, false, true];
    let state = slayer::collide::StrokeState {
        grid: Some(&grid),
        active: &active,
        parallel: false,
        collision_distance: 0.05,
        ring: 2,
        max_edge: 0.08,
        cull: true,
    };
    let neighbours = smoothing_neighbours(&mesh, 0);
    let (mut worst_mirror, mut worst_gpu) = (0.0f32, 0.0f32);
    for (k, &kind) in BrushKind::DEFORMING.iter().enumerate() {
        let falloff = FALLOFFS[k % FALLOFFS.len()];
        let center = Vec3::new(3.0, 2.5, 0.2);
        let dab = Dab {
            brush: Brush {
                kind,
                radius: 2.2,
                strength: 0.8,
                falloff,
                invert: k % 2 == 1,
            },
            frame: DabFrame {
                center,
                normal: Vec3::new(0.1, -0.2, 1.0).normalize(),
                plane_point: center - Vec3::new(0.0, 0.0, 0.15),
                motion: Vec3::new(0.03, -0.02, 0.04),
            },
            pressure: 0.9,
            share: 0.5,
        };
        let full = slayer::pipeline::step::select(&state, &mesh, &dab);
        assert!(full.len() > 8315, "{} selects {}", kind.name(), full.len());
        // The last round folds the dispatch into two dimensions.
        if k == BrushKind::DEFORMING.len() - 1 {
            gpu.limits.max_compute_workgroups_per_dimension = 7;
        }
        for size in [8315, SIZES[k % SIZES.len()]] {
            let selection = &full[..size];
            let reference = slayer::pipeline::step::deform(&state, &mesh, &dab, selection);
            let entries: Vec<SelectedVertex> = selection
                .iter()
                .map(|&(vertex, weight)| SelectedVertex { vertex, weight })
                .collect();
            let params = deform_params(&dab, entries.len());
            let inputs = slayer::cpu::DeformInputs {
                positions: mesh.positions(),
                normals: mesh.normals(),
                selected: &entries,
                selection_count: entries.len() as u32,
                neighbour_rows: &neighbours.rows.table,
                neighbours: &neighbours.words,
                frame_sums: &[0; slayer::cpu::FRAME_SUM_WORDS],
            };
            let mut mirror = vec![Vec3::ZERO; entries.len()];
            slayer::cpu::deform(&params, &inputs, &mut mirror);
            let actual = run_deform(&gpu, &mesh, &dab, &entries).expect("GPU run");
            let (m, g) = (
                worst_relative(&mirror, &reference, dab.brush.radius),
                worst_relative(&actual, &mirror, dab.brush.radius),
            );
            let label = format!("{} ({}) at size {size}", kind.name(), falloff.name());
            assert!(
                m <= DEFORM_TOLERANCE,
                "{label}: mirror off the field by {m:e} radii"
            );
            assert!(
                g <= DEFORM_TOLERANCE,
                "{label}: GPU off the mirror by {g:e} radii"
            );
            // A prefix may hold only rim vertices whose weight rounds their move away.
            if size == 8315 {
                let moved = mirror
                    .iter()
                    .zip(selection)
                    .any(|(q, &(v, _))| *q != mesh.positions()[v as usize]);
                assert!(moved, "{label}: nothing moved");
            }
            worst_mirror = worst_mirror.max(m);
            worst_gpu = worst_gpu.max(g);
        }
    }
    eprintln!(
        "deform: largest deviation mirror vs field {worst_mirror:e}, GPU vs mirror {worst_gpu:e} (× radius)"
    );
}

#[test]
fn deform_takes_the_frame_from_the_sums_as_the_mirror_does() {
    // Selection → brush_frame → deform in one submission, as the GPU backend opens a sample:
    // the brushes that read the frame (flatten its plane and normal, draw and twist their
    // normal) move every vertex as the mirror does with the mirror's sums; with the sample's
    // own normal only the plane comes from the sums.
    let mesh = bumpy_sheets();
    let gpu = gpu();
    let neighbours = smoothing_neighbours(&mesh, 0);
    let center = Vec3::new(2.6, 1.9, 0.1);
    let full = selection_under(&mesh, center, 1.7);
    let mut worst = 0.0f32;
    for (k, kind) in [BrushKind::Flatten, BrushKind::Draw, BrushKind::Twist]
        .into_iter()
        .enumerate()
    {
        for own_normal in [None, Some(Vec3::new(0.3, 0.1, 1.0).normalize())] {
            let dab = Dab {
                brush: Brush {
                    kind,
                    radius: 1.7,
                    strength: 0.7,
                    falloff: Falloff::Smooth,
                    invert: k == 1,
                },
                frame: DabFrame {
                    center,
                    normal: own_normal.unwrap_or(Vec3::Z),
                    plane_point: center,
                    motion: Vec3::ZERO,
                },
                pressure: 1.0,
                share: 1.0,
            };
            let flags = slayer::pipeline::step::frame_flags(own_normal);
            for size in [0, 65, full.len()] {
                let selection = &full[..size];
                let (sums, actual) =
                    slayer::gpu::run_framed_deform(&gpu, &mesh, &dab, selection, flags)
                        .expect("GPU run");
                let mut mirror_sums = [0u32; slayer::cpu::FRAME_SUM_WORDS];
                slayer::cpu::brush_frame(
                    &slayer::abi::frame_params(center, dab.brush.radius, size),
                    &slayer::cpu::FrameInputs {
                        positions: mesh.positions(),
                        normals: mesh.normals(),
                        selected: selection,
                        selection_count: size as u32,
                    },
                    &mut mirror_sums,
                );
                let label = format!("{} at size {size}, own normal {own_normal:?}", kind.name());
                assert_eq!(sums, mirror_sums, "{label}: sums");
                let params = slayer::gpu::DeformParams {
                    frame: flags,
                    ..deform_params(&dab, size)
                };
                let mirror_deform = |params: &slayer::gpu::DeformParams, frame_sums| {
                    let mut targets = vec![Vec3::ZERO; size];
                    let inputs = slayer::cpu::DeformInputs {
                        positions: mesh.positions(),
                        normals: mesh.normals(),
                        selected: selection,
                        selection_count: size as u32,
                        neighbour_rows: &neighbours.rows.table,
                        neighbours: &neighbours.words,
                        frame_sums,
                    };
                    slayer::cpu::deform(params, &inputs, &mut targets);
                    targets
                };
                let mirror = mirror_deform(&params, &mirror_sums);
                let g = worst_relative(&actual, &mirror, dab.brush.radius);
                assert!(
                    g <= DEFORM_TOLERANCE,
                    "{label}: GPU off the mirror by {g:e} radii"
                );
                worst = worst.max(g);
                // The mirror with the frame resolved up front, as the pipeline passes it on to
                // the sample's later steps: the same targets.
                let frame = slayer::pipeline::step::frame_of_sums(&mirror_sums, &dab, own_normal);
                let resolved = deform_params(&Dab { frame, ..dab }, size);
                let again = mirror_deform(&resolved, &[0; slayer::cpu::FRAME_SUM_WORDS]);
                assert_eq!(again, mirror, "{label}: frame resolved up front");
                if size == full.len() {
                    let moved = mirror
                        .iter()
                        .zip(selection)
                        .filter(|(q, s)| **q != mesh.positions()[s.vertex as usize])
                        .count();
                    assert!(moved > size / 2, "{label}: {moved} of {size} moved");
                }
            }
        }
    }
    eprintln!("deform with the frame from the sums: GPU off the mirror by {worst:e} radii at most");
}
