//! Deliberately irregular meshes: every interior vertex displaced within its tangent plane, for
//! testing that remeshing makes edges uniform again (`slayer scene … --jitter`).

use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::mesh::Mesh;

/// Largest jitter (× mean edge length) accepted: beyond it a vertex of a regular lattice could
/// cross the opposite edge of one of its triangles (altitude √3/2 ≈ 0.87 L, and both ends of an
/// edge move too), folding the surface.
pub const MAX_JITTER: f32 = 0.4;

/// Moves every interior vertex by a random tangential offset of length below `amount` × the
/// mean edge length; boundary vertices stay, so open layers keep their outline. The result
/// depends only on the mesh and `seed`.
pub fn jitter(mesh: &mut Mesh, amount: f32, seed: u64) -> Result<(), String> {
    if !(0.0..=MAX_JITTER).contains(&amount) {
        return Err(format!(
            "jitter {amount} is out of range (0 to {MAX_JITTER} edge lengths)"
        ));
    }
    let reach = amount * mesh.mean_edge_length();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    for v in 0..mesh.vertex_count() {
        // Draw for every vertex so that one vertex's offset does not depend on its neighbours'.
        let (angle, radius) = (
            rng.random_range(0.0..std::f32::consts::TAU),
            reach * rng.random::<f32>().sqrt(),
        );
        let vertex = v as u32;
        if mesh.is_vertex_dead(vertex)
            || mesh.is_boundary_vertex(vertex)
            || mesh.faces_around(vertex).next().is_none()
        {
            continue;
        }
        let normal = mesh.normals()[v];
        let normal = if normal.is_finite() && normal != Vec3::ZERO {
            normal
        } else {
            Vec3::Z
        };
        let e1 = normal.any_orthonormal_vector();
        let e2 = normal.cross(e1);
        mesh.positions_mut()[v] += radius * (angle.cos() * e1 + angle.sin() * e2);
    }
    mesh.recompute_normals();
    Ok(())
}
