//! Refinement by a large factor: whole levels of 1-to-4 subdivision before the usual passes.
//! Splitting edges one at a time toward an edge length many times shorter than the mesh's
//! splits slivers into slivers and collapses most of what it made (a 20K-face sphere refined
//! to 1.26M faces took 765K splits, 145K collapses and 203K flips); halving every edge at once
//! keeps the mesh as regular as it was, in time linear in what it makes.
//!
//! Each new vertex sits on the curve its edge's two vertex normals describe (Phong
//! tessellation's midpoint with shape factor ½, which puts it on the circle through the two
//! ends when they lie on a sphere), so a smooth input stays smooth. Where the surface bends
//! sharply (the two normals, or the two faces along the edge, more than [`FEATURE_DEGREES`]
//! apart) the midpoint stays on the edge, so a cube stays a cube.

use glam::Vec3;

use crate::mesh::{INVALID, Mesh, MeshError, VertexFlags};

/// Normals further apart than this mark a crease or a corner: no bulging across it.
const FEATURE_DEGREES: f32 = 30.0;

/// How many halvings take edges of mean length `mean` toward `target` without going below
/// about 0.85·`target` (the passes after them then mostly flip and relax, not collapse).
pub fn subdivision_levels(mean: f32, target: f32) -> u32 {
    if !(mean > 0.0 && target > 0.0) {
        return 0;
    }
    (mean / (0.85 * target)).log2().floor().clamp(0.0, 8.0) as u32
}

/// The mesh with every live face split into four at its edges' midpoints (placed as the
/// module says), its layers, BRDFs and masks carried over (a midpoint takes the mean of its
/// edge's ends). The result is compact: dead vertices and faces are left behind.
pub fn subdivide(mesh: &Mesh) -> Result<Mesh, MeshError> {
    let (positions, old_index) = live_positions(mesh);
    let vertex_count = positions.len();
    let mut positions = positions;
    let mut ends: Vec<(u32, u32)> = Vec::new();
    let opposite = &mesh.adjacency().opposite;
    // The new vertex on the edge a corner faces; the first of its two corners makes it.
    let mut midpoint = vec![INVALID; 3 * mesh.face_count()];
    let bend = FEATURE_DEGREES.to_radians().cos();
    for face in (0..mesh.face_count()).filter(|&f| !mesh.is_face_dead(f)) {
        for k in 0..3 {
            let corner = 3 * face + k;
            let across = opposite[corner];
            if across != INVALID && midpoint[across as usize] != INVALID {
                midpoint[corner] = midpoint[across as usize];
                continue;
            }
            let tri = mesh.faces()[face];
            let (a, b) = (tri[(k + 1) % 3], tri[(k + 2) % 3]);
            let smooth = across == INVALID
                || mesh
                    .face_normal(face)
                    .dot(mesh.face_normal(across as usize / 3))
                    >= bend;
            midpoint[corner] = (vertex_count + ends.len()) as u32;
            positions.push(edge_point(mesh, (a, b), smooth, bend));
            ends.push((old_index[a as usize], old_index[b as usize]));
        }
    }
    let mut faces = Vec::with_capacity(4 * mesh.live_face_count());
    let mut layers = Vec::with_capacity(faces.capacity());
    for face in (0..mesh.face_count()).filter(|&f| !mesh.is_face_dead(f)) {
        let [a, b, c] = mesh.faces()[face].map(|v| old_index[v as usize]);
        let [ma, mb, mc] = [0, 1, 2].map(|k| midpoint[3 * face + k]);
        faces.extend([[a, mc, mb], [mc, b, ma], [mb, ma, c], [ma, mb, mc]]);
        layers.extend([mesh.face_layers()[face]; 4]);
    }
    let names = mesh.layer_names().to_vec();
    let mut refined = Mesh::new(positions, faces, layers, names)?;
    carry_attributes(mesh, &mut refined, &old_index, &ends)?;
    Ok(refined)
}

/// The live vertices' positions, and each old vertex's index among them.
fn live_positions(mesh: &Mesh) -> (Vec<Vec3>, Vec<u32>) {
    let mut old_index = vec![INVALID; mesh.vertex_count()];
    let mut positions = Vec::with_capacity(mesh.live_vertex_count());
    for (v, index) in old_index.iter_mut().enumerate() {
        if mesh.is_vertex_live(v as u32) {
            *index = positions.len() as u32;
            positions.push(mesh.positions()[v]);
        }
    }
    (positions, old_index)
}

/// The new vertex on edge `(a, b)`: lifted toward the curve of the two vertex normals where the
/// edge is `smooth` and the normals agree within `bend` (a cosine), else the midpoint.
fn edge_point(mesh: &Mesh, (a, b): (u32, u32), smooth: bool, bend: f32) -> Vec3 {
    let (pa, pb) = (mesh.positions()[a as usize], mesh.positions()[b as usize]);
    let (na, nb) = (mesh.normals()[a as usize], mesh.normals()[b as usize]);
    let middle = 0.5 * (pa + pb);
    if !smooth || na.dot(nb) < bend {
        return middle;
    }
    // Phong tessellation's projections of the midpoint onto the two tangent planes, taken
    // half way: on a sphere, the point on the great circle through `a` and `b`.
    let lift = |p: Vec3, n: Vec3| -n * (middle - p).dot(n);
    let point = middle + 0.25 * (lift(pa, na) + lift(pb, nb));
    if point.is_finite() { point } else { middle }
}

/// BRDFs and masks: the old vertices keep theirs, a midpoint takes its edge's mean.
fn carry_attributes(
    mesh: &Mesh,
    refined: &mut Mesh,
    old_index: &[u32],
    ends: &[(u32, u32)],
) -> Result<(), MeshError> {
    let live: Vec<usize> = (0..mesh.vertex_count())
        .filter(|&v| old_index[v] != INVALID)
        .collect();
    let old_brdf = |i: u32| mesh.brdfs()[live[i as usize]];
    let old_flags = |i: u32| mesh.flags()[live[i as usize]];
    let mut brdfs: Vec<_> = live.iter().map(|&v| mesh.brdfs()[v]).collect();
    brdfs.extend(
        ends.iter()
            .map(|&(a, b)| old_brdf(a).lerp(&old_brdf(b), 0.5)),
    );
    refined.set_brdfs(brdfs)?;
    let flags = refined.flags_mut();
    for (i, &v) in live.iter().enumerate() {
        flags[i] |= mesh.flags()[v] & VertexFlags::PERSISTENT;
    }
    for (k, &(a, b)) in ends.iter().enumerate() {
        let mask = 0.5 * (old_flags(a).mask() + old_flags(b).mask());
        flags[live.len() + k].set_mask(mask);
    }
    Ok(())
}
