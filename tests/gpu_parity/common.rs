//! What the parity tests share: adapters (whole or with a lowered binding limit), the awkward
//! sizes, seeded random inputs, and the meshes and steps several kernels are tested on.

use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use slayer::brush::Falloff;
use slayer::collide::{Region, StrokeState};
use slayer::gpu::{
    AdapterChoice, CsrTable, GpuContext, MovingVertex, NormalParams, PackedTopology, SelectedVertex,
};
use slayer::mesh::{INVALID, Mesh, VertexFlags};

pub fn gpu() -> GpuContext {
    let gpu = GpuContext::new(AdapterChoice {
        allow_software: true,
    })
    .unwrap_or_else(|e| panic!("GPU tests need an adapter (run tools/test.sh): {e}"));
    eprintln!("GPU tests on: {}", gpu.adapter);
    gpu
}

/// An adapter whose device enforces storage bindings of `bytes` at most, so that the arrays
/// the kernels page (topology, smoothing neighbours) span several bindings.
pub fn gpu_with_binding_limit(bytes: u64) -> GpuContext {
    let gpu = GpuContext::with_limits(
        AdapterChoice {
            allow_software: true,
        },
        |limits| limits.max_storage_buffer_binding_size = bytes,
    )
    .unwrap_or_else(|e| panic!("GPU tests need an adapter (run tools/test.sh): {e}"));
    assert_eq!(gpu.page_bytes(), bytes, "a power of two is its own page");
    gpu
}

/// The smallest power-of-two binding limit that holds `unpaged` bytes (the largest array bound
/// whole) and each of `paged` in four pages, checked to split the first over two or more.
pub fn binding_limit_paging(unpaged: u64, paged: &[u64]) -> u64 {
    let largest = paged.iter().copied().max().unwrap_or(0);
    let limit = unpaged
        .max(largest.div_ceil(slayer::gpu::PAGE_COUNT))
        .next_power_of_two()
        .max(256);
    let pages: Vec<u64> = paged.iter().map(|bytes| bytes.div_ceil(limit)).collect();
    assert!(
        pages[0] >= 2,
        "{paged:?} bytes in pages of {limit}: {pages:?} pages"
    );
    eprintln!("binding limit {limit} bytes: {paged:?} bytes paged over {pages:?} bindings");
    limit
}

/// Awkward sizes around the 64-wide workgroup, plus a large odd one.
pub const SIZES: [usize; 7] = [0, 1, 63, 64, 65, 1000, 512 * 16 + 123];

pub fn random_positions(count: usize, seed: u64, extent: f32) -> Vec<Vec3> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..count)
        .map(|_| {
            Vec3::new(
                rng.random_range(-extent..extent),
                rng.random_range(-extent..extent),
                rng.random_range(-extent..extent),
            )
        })
        .collect()
}

pub fn random_u32s(count: usize, seed: u64, below: u32) -> Vec<u32> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..count).map(|_| rng.random_range(0..below)).collect()
}

/// About one vertex in eight dead; dead ones must stay out of every table.
pub fn random_flags(count: usize, seed: u64) -> Vec<u32> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..count)
        .map(|_| match rng.random_range(0..8) {
            0 => VertexFlags::DEAD.bits(),
            1 => VertexFlags::MASKED.bits(),
            _ => 0,
        })
        .collect()
}

pub const FALLOFFS: [Falloff; 6] = [
    Falloff::blend(3),
    Falloff::blend(6),
    Falloff::Blend { n: 4, inner: 0.5 },
    Falloff::Smooth,
    Falloff::Sphere,
    Falloff::Linear,
];

/// Random vertices on three layers (the middle one inactive), some masked or dead.
pub fn random_vertices(size: usize, seed: u64, extent: f32) -> (Vec<Vec3>, Vec<u32>, Vec<u32>) {
    let positions = random_positions(size, seed, extent);
    let layers = random_u32s(size, seed + 1, 3);
    let flags = random_flags(size, seed + 2);
    (positions, layers, flags)
}

/// Stacked sheets with bumpy heights and matching normals, masked here and there, so that
/// every field (smooth, flatten, inflate) has something to do.
pub fn bumpy_sheets() -> slayer::mesh::Mesh {
    let mut mesh = slayer::scene::shapes::stacked_sheets(3, 120, 100, 0.05, 0.2);
    let mut rng = ChaCha8Rng::seed_from_u64(500);
    for p in mesh.positions_mut() {
        p.z += 0.01 * (3.0 * p.x).sin() * (2.0 * p.y).cos() + rng.random_range(-0.004..0.004);
    }
    mesh.recompute_normals();
    for v in (0..mesh.vertex_count()).step_by(11) {
        mesh.flags_mut()[v].insert(VertexFlags::MASKED);
    }
    mesh
}

/// Largest distance between corresponding targets, over the radius.
pub fn worst_relative(a: &[Vec3], b: &[Vec3], radius: f32) -> f32 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(p, q)| p.distance(*q) / radius)
        .fold(0.0, f32::max)
}

/// A selection of `mesh` under a brush at `center`, as (vertex, weight) in vertex order.
pub fn selection_under(
    mesh: &slayer::mesh::Mesh,
    center: Vec3,
    radius: f32,
) -> Vec<SelectedVertex> {
    mesh.positions()
        .iter()
        .enumerate()
        .filter_map(|(v, p)| {
            let t = p.distance(center) / radius;
            (t < 1.0).then(|| SelectedVertex {
                vertex: v as u32,
                weight: Falloff::Smooth.weight(t),
            })
        })
        .collect()
}

/// Pulled-back positions may differ by this share of the edge length, beside [`rounding`]: one
/// flipped decision in the last bisection rounds moves a result by 2⁻¹⁶ of its move.
pub const PROXIMITY_TOLERANCE: f32 = 1e-5;

/// WGSL lets an implementation fuse a multiply and an add, and round a division or a square
/// root within a few ulps, so a hardware GPU may differ from the mirror in the last bits of
/// whatever it computes from the coordinates (lavapipe rounds as the CPU does; an NVIDIA H200
/// differed by up to 2 ulps of the largest coordinate). Results may differ by this many ulps
/// of the largest coordinate.
const ROUNDING_ULPS: f32 = 8.0;

/// How far apart a GPU result and its mirror's may lie when both are computed from coordinates
/// no larger than `extent` in magnitude: not at all on lavapipe, which rounds as the CPU does.
pub fn rounding(extent: f32) -> f32 {
    static SOFTWARE: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    if *SOFTWARE.get_or_init(|| gpu().adapter.software) {
        0.0
    } else {
        ROUNDING_ULPS * f32::EPSILON * extent
    }
}

/// The largest coordinate magnitude among `points`.
pub fn extent(points: &[Vec3]) -> f32 {
    points
        .iter()
        .map(|p| p.abs().max_element())
        .fold(0.0, f32::max)
}

/// How far a pulled-back position may lie from the mirror's on `scene`, in edge lengths.
pub fn proximity_tolerance(scene: &ProximityScene) -> f32 {
    PROXIMITY_TOLERANCE + rounding(extent(scene.mesh.positions())) / scene.edge
}

/// Asserts that `actual` matches `expected` point by point, each coordinate within
/// [`rounding`] of coordinates as large as `extent`.
pub fn assert_close(label: &str, actual: &[Vec3], expected: &[Vec3], extent: f32) {
    assert_eq!(actual.len(), expected.len(), "{label}: lengths");
    let allowed = rounding(extent);
    for (i, (a, e)) in actual.iter().zip(expected).enumerate() {
        assert!(
            (*a - *e).abs().max_element() <= allowed,
            "{label}: point {i} is {a} here, {e} in the reference (allowed {allowed:e})"
        );
    }
}

/// A step to test proximity on: the mesh at the step's start, its selection (a seeded shuffle
/// of the vertices that move) and every vertex's tentative position.
pub struct ProximityScene {
    pub name: &'static str,
    pub mesh: slayer::mesh::Mesh,
    pub order: Vec<u32>,
    pub targets: Vec<Vec3>,
    pub edge: f32,
}

/// A moving list over `listed`, each entry starting where `start` has its vertex, one slot in
/// seven vacant; about half the slots' vertices (vacant ones too) moved in `positions` by what
/// `step` draws. Returns the list and the vertices of its (not vacant) entries that moved.
pub fn half_moved_list(
    start: &[Vec3],
    positions: &mut [Vec3],
    listed: &[u32],
    (rng, step): (&mut ChaCha8Rng, impl Fn(&mut ChaCha8Rng) -> Vec3),
) -> (Vec<slayer::gpu::MovingVertex>, Vec<u32>) {
    let mut moving = Vec::with_capacity(listed.len());
    let mut moved = Vec::new();
    for (slot, &v) in listed.iter().enumerate() {
        let vertex = if slot % 7 == 6 { INVALID } else { v };
        moving.push(slayer::gpu::MovingVertex {
            start: start[v as usize].to_array(),
            vertex,
            ..Default::default()
        });
        if rng.random_bool(0.5) {
            positions[v as usize] += step(rng);
            if vertex != INVALID {
                moved.push(v);
            }
        }
    }
    (moving, moved)
}

pub fn shuffled(mut vertices: Vec<u32>, seed: u64) -> Vec<u32> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    for i in (1..vertices.len()).rev() {
        vertices.swap(i, rng.random_range(0..=i));
    }
    vertices
}

/// Each vertex of `moved` pushed down by `depth` (± 0.02) and jittered sideways by ± 0.02.
pub fn pushed_down(mesh: &slayer::mesh::Mesh, moved: &[u32], depth: f32, seed: u64) -> Vec<Vec3> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut targets = mesh.positions().to_vec();
    for &v in moved {
        targets[v as usize] += Vec3::new(
            rng.random_range(-0.02..0.02),
            rng.random_range(-0.02..0.02),
            -depth + rng.random_range(-0.02..0.02),
        );
    }
    targets
}

/// Two sheets 0.15 apart (edges 0.1), the upper one pushed 0.12 down: most of it comes within
/// the collision distance of the lower sheet and clamps.
pub fn pressed_sheets() -> ProximityScene {
    let mesh = slayer::scene::shapes::stacked_sheets(2, 80, 60, 0.1, 0.15);
    let upper: Vec<u32> = (0..mesh.vertex_count() as u32)
        .filter(|&v| mesh.vertex_layers()[v as usize] == 1)
        .collect();
    let targets = pushed_down(&mesh, &upper, 0.12, 71);
    ProximityScene {
        name: "pressed sheets",
        order: shuffled(upper, 72),
        mesh,
        targets,
        edge: 0.1,
    }
}

/// One sheet folded over itself (flat, a half-turn of radius 0.1, flat again 0.2 above), its
/// upper part pushed 0.17 down onto the lower: same-layer collisions outside the ring.
pub fn folded_sheet() -> ProximityScene {
    let mut mesh = slayer::scene::shapes::stacked_sheets(1, 80, 20, 0.1, 0.0);
    let (bend, radius) = (4.0f32, 0.1f32);
    let arc = std::f32::consts::PI * radius;
    let mut upper = Vec::new();
    for (v, p) in mesh.positions_mut().iter_mut().enumerate() {
        let s = p.x;
        if s <= bend {
            continue;
        }
        if s < bend + arc {
            let angle = (s - bend) / radius;
            p.x = bend + radius * angle.sin();
            p.z = radius - radius * angle.cos();
        } else {
            p.x = bend - (s - bend - arc);
            p.z = 2.0 * radius;
            upper.push(v as u32);
        }
    }
    let targets = pushed_down(&mesh, &upper, 0.17, 73);
    ProximityScene {
        name: "folded sheet",
        order: shuffled(upper, 74),
        mesh,
        targets,
        edge: 0.1,
    }
}

/// How a check binds the arrays the kernels page (the packed topology, smoothing neighbours,
/// exclusion rings).
#[derive(Clone, Copy, PartialEq)]
pub enum Binding {
    /// Whole, as the adapter's limits allow.
    Whole,
    /// Split over several bindings by a lowered binding limit.
    Paged,
}

/// The adapter for a normals kernel over `mesh`: with `Binding::Paged`, a binding limit that
/// keeps positions and normals (12 bytes a vertex) whole and splits the topology.
pub fn gpu_for_normals(binding: Binding, mesh: &Mesh) -> GpuContext {
    match binding {
        Binding::Whole => gpu(),
        Binding::Paged => {
            let unpaged = 12 * mesh.vertex_count() as u64;
            let topology = slayer::gpu::PackedTopology::of(mesh).words.len() as u64 * 4;
            gpu_with_binding_limit(binding_limit_paging(unpaged, &[topology]))
        }
    }
}

/// Packed x, y, z triples, as the kernels and their mirrors read positions and normals.
pub fn packed(points: &[Vec3]) -> Vec<f32> {
    points.iter().flat_map(|p| p.to_array()).collect()
}

/// The mesh's vertex flags as the kernels read them.
pub fn flag_bits(mesh: &Mesh) -> Vec<u32> {
    mesh.flags().iter().map(|f| f.bits()).collect()
}

/// The mirror's hash table of `mesh`'s live vertices where the mesh has them (a step's start),
/// as the proximity and backstop kernels query it.
pub fn mesh_table(mesh: &Mesh, inv_cell_size: f32, table_size: u32) -> CsrTable {
    slayer::cpu::hash_table(
        mesh.positions(),
        &flag_bits(mesh),
        inv_cell_size,
        table_size,
    )
}

/// The host's moving list (and rings of `ring`) over `selection`, each entry starting where
/// `mesh` has its vertex.
pub fn host_moving_list(
    mesh: &Mesh,
    selection: &[u32],
    ring: u32,
) -> (Vec<MovingVertex>, Vec<u32>) {
    let starts: Vec<Vec3> = selection
        .iter()
        .map(|&v| mesh.positions()[v as usize])
        .collect();
    slayer::gpu::moving_vertices(mesh, selection, &starts, ring)
}

/// The parameters of a normals pass (`vertex_normals`, `moved_normals`, `moved_edges`) over
/// `count` entries of `topology`.
pub fn normal_params(count: usize, topology: &PackedTopology) -> NormalParams {
    NormalParams {
        count: count as u32,
        vertex_rows_base: topology.layout.vertex_rows_base,
        _pad0: 0,
        _pad1: 0,
    }
}

/// The CPU pipeline's region of a step moving `selection` (vertex, weight) to `targets`, and
/// each vertex's index in the selection (`INVALID` where not selected), as a step gathers them.
pub fn gathered_region(
    state: &StrokeState<'_>,
    mesh: &Mesh,
    selection: &[(u32, f32)],
    targets: &[Vec3],
) -> (Region, Vec<u32>) {
    let mut target_of = vec![INVALID; mesh.vertex_count()];
    for (i, &(v, _)) in selection.iter().enumerate() {
        target_of[v as usize] = i as u32;
    }
    let mut region = Region::default();
    region.gather(state, mesh, selection, targets, &target_of);
    (region, target_of)
}
