//! The volume-keeping sweep ([`BrushKind::SweepVolume`](crate::brush::BrushKind)): each
//! step's targets are corrected before the collision response so that every closed layer
//! they touch encloses the volume it had. What the sweep draws out is taken back along the
//! normals of the brush's flanks, weighted `4w(1 − w)` by the falloff weight `w`: the part
//! carried at full strength keeps the brush's motion, the rim stays put, and the surface in
//! between sinks (or swells) as clay drawn out of its surroundings would.
//!
//! The change is measured exactly, from the signed volumes of the faces around the selection
//! before and after the step; the correction along the normals is linear in its size only to
//! first order, so it is taken in two Newton rounds.

use glam::{DVec3, Vec3};

use crate::mesh::{INVALID, Mesh};
use crate::pipeline::step::longest_move;

/// Newton rounds per step: the second takes out what the first's linearization missed (the
/// correction's own effect on the faces' normals), about the square of the first's error.
const ROUNDS: usize = 2;

/// Per layer: whether it is closed (no boundary edge), so that it encloses a volume to keep.
pub(super) fn closed_layers(mesh: &Mesh) -> Vec<bool> {
    let mut closed = vec![true; mesh.layer_count()];
    let opposite = &mesh.adjacency().opposite;
    for (face, &layer) in mesh.face_layers().iter().enumerate() {
        let open = (0..3).any(|k| opposite[3 * face + k] == INVALID);
        if open && !mesh.is_face_dead(face) {
            closed[layer as usize] = false;
        }
    }
    closed
}

/// `targets` (one per `selection` entry) corrected so that each closed layer keeps the volume
/// it encloses at the mesh's current positions. `index_of[v]` is `v`'s entry in `selection`
/// (`INVALID` for a vertex not in it). Layers that are open keep the targets they had; no
/// vertex moves farther than the step's longest move.
pub(super) fn keep_volume(
    mesh: &Mesh,
    selection: &[(u32, f32)],
    targets: &[Vec3],
    closed: &[bool],
    index_of: &[u32],
) -> Vec<Vec3> {
    let mut kept = targets.to_vec();
    let faces = faces_held(mesh, selection, closed);
    if faces.is_empty() {
        return kept;
    }
    let flank: Vec<f32> = selection
        .iter()
        .map(|&(_, w)| 4.0 * w * (1.0 - w))
        .collect();
    let whole: Vec<f32> = selection.iter().map(|&(_, w)| w).collect();
    let reach = longest_move(mesh, selection, targets);
    for _ in 0..ROUNDS {
        let change = volume_change(mesh, &faces, &kept, index_of);
        // Where the flanks cannot move the volume (a plateau as wide as the brush), the whole
        // selection takes the correction.
        for profile in [&flank, &whole] {
            let rate = correction_rate(mesh, &faces, (&kept, index_of), profile);
            let scale: Vec<f64> = (change.iter().zip(&rate))
                .map(|(&c, &r)| if r.abs() > 1e-30 { c / r } else { 0.0 })
                .collect();
            take_back(mesh, selection, (&mut kept, reach), |i, layer| {
                scale[layer] * profile[i] as f64
            });
            if scale.iter().any(|&s| s != 0.0) {
                break;
            }
        }
    }
    kept
}

/// Moves each entry `i` of `kept` in along its vertex normal by `amount(i, layer)`, but no
/// farther from where the vertex is than `reach`: the step was split so that nothing moves
/// farther, and the collision response counts on it.
fn take_back(
    mesh: &Mesh,
    selection: &[(u32, f32)],
    (kept, reach): (&mut [Vec3], f32),
    amount: impl Fn(usize, usize) -> f64,
) {
    let (normals, layers) = (mesh.normals(), mesh.vertex_layers());
    for (i, &(v, _)) in selection.iter().enumerate() {
        let by = amount(i, layers[v as usize] as usize) as f32;
        let at = mesh.positions()[v as usize];
        let offset = kept[i] - normals[v as usize] * by - at;
        kept[i] = at + offset.clamp_length_max(reach);
    }
}

/// The live faces of closed layers around the selected vertices, each once.
fn faces_held(mesh: &Mesh, selection: &[(u32, f32)], closed: &[bool]) -> Vec<u32> {
    let mut faces: Vec<u32> = (selection.iter())
        .flat_map(|&(v, _)| mesh.faces_around(v))
        .filter(|&f| closed[mesh.face_layers()[f as usize] as usize])
        .collect();
    faces.sort_unstable();
    faces.dedup();
    faces
}

/// Where `v` is once the step moves the selection to `kept`.
fn moved_position(mesh: &Mesh, (kept, index_of): (&[Vec3], &[u32]), v: u32) -> DVec3 {
    let i = index_of[v as usize];
    let p = if i == INVALID {
        mesh.positions()[v as usize]
    } else {
        kept[i as usize]
    };
    p.as_dvec3()
}

/// Per layer: the volume the faces enclose with the selection at `kept`, less what they
/// enclose now (each face's signed tetrahedron with the origin; the origin's share cancels
/// over a closed layer).
fn volume_change(mesh: &Mesh, faces: &[u32], kept: &[Vec3], index_of: &[u32]) -> Vec<f64> {
    let mut change = vec![0.0f64; mesh.layer_count()];
    for &f in faces {
        let tri = mesh.faces()[f as usize];
        let before = tri.map(|v| mesh.positions()[v as usize].as_dvec3());
        let after = tri.map(|v| moved_position(mesh, (kept, index_of), v));
        let layer = mesh.face_layers()[f as usize] as usize;
        change[layer] += (signed_volume(after) - signed_volume(before)) / 6.0;
    }
    change
}

/// Per layer: how fast its volume grows as the selection moves out along its normals by
/// `profile` (the derivative of [`volume_change`], at `kept`).
fn correction_rate(
    mesh: &Mesh,
    faces: &[u32],
    (kept, index_of): (&[Vec3], &[u32]),
    profile: &[f32],
) -> Vec<f64> {
    let mut rate = vec![0.0f64; mesh.layer_count()];
    for &f in faces {
        let tri = mesh.faces()[f as usize];
        let p = tri.map(|v| moved_position(mesh, (kept, index_of), v));
        let layer = mesh.face_layers()[f as usize] as usize;
        for k in 0..3 {
            let i = index_of[tri[k] as usize];
            if i == INVALID {
                continue;
            }
            let gradient = p[(k + 1) % 3].cross(p[(k + 2) % 3]) / 6.0;
            let normal = mesh.normals()[tri[k] as usize].as_dvec3();
            rate[layer] += profile[i as usize] as f64 * normal.dot(gradient);
        }
    }
    rate
}

/// Six times the signed volume of the tetrahedron of a face and the origin.
fn signed_volume([a, b, c]: [DVec3; 3]) -> f64 {
    a.dot(b.cross(c))
}
