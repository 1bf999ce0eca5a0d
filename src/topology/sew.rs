//! The faces a topology change sews in: a tube between two holes (a join), a cap over one (a
//! split). Both take holes as [`hole_loops`](super::regions::hole_loops) gives them, so every
//! new face runs each rim edge against the remaining face that holds it.

use glam::Vec3;

use crate::mesh::{Brdf, LayerId, Mesh};

/// Triangles joining loop `a` to loop `b` into a tube. Facing holes wind the same way about
/// the tube's axis when one is walked backwards, so `b` is walked backwards from the vertex
/// that best matches `a[0]`; the zipper then steps along whichever loop gives the shorter
/// new edge.
pub fn tube(mesh: &Mesh, a: &[u32], b: &[u32]) -> Vec<[u32; 3]> {
    let p = |v: u32| mesh.positions()[v as usize];
    let (n, m) = (a.len(), b.len());
    let start = best_alignment(&p, a, b);
    // w(j): the j-th vertex of b walked backwards from `start`.
    let w = |j: usize| b[(start + m - j % m) % m];
    let u = |i: usize| a[i % n];
    let mut tris = Vec::with_capacity(n + m);
    let (mut i, mut j) = (0, 0);
    while i < n || j < m {
        let advance_a = j == m
            || (i < n
                && p(u(i + 1)).distance_squared(p(w(j))) <= p(u(i)).distance_squared(p(w(j + 1))));
        if advance_a {
            tris.push([u(i + 1), u(i), w(j)]);
            i += 1;
        } else {
            tris.push([w(j), w(j + 1), u(i)]);
            j += 1;
        }
    }
    tris
}

/// The vertex of `b` to start its backwards walk from: the one whose walk, spread evenly
/// along `a`, lies nearest to it (summed squared distances).
fn best_alignment(p: &impl Fn(u32) -> Vec3, a: &[u32], b: &[u32]) -> usize {
    let (n, m) = (a.len(), b.len());
    let cost = |start: usize| -> f32 {
        (0..n)
            .map(|i| {
                let j = (i * m + n / 2) / n;
                p(a[i]).distance_squared(p(b[(start + m - j % m) % m]))
            })
            .sum()
    };
    (0..m)
        .min_by(|&x, &y| cost(x).total_cmp(&cost(y)).then(x.cmp(&y)))
        .unwrap_or(0)
}

/// A new vertex at the loop's centroid and the fan of triangles from it closing the hole.
pub fn cap(mesh: &mut Mesh, hole: &[u32], layer: LayerId) -> Vec<[u32; 3]> {
    let n = hole.len();
    let centroid = hole
        .iter()
        .map(|&v| mesh.positions()[v as usize])
        .sum::<Vec3>()
        / n as f32;
    let brdf = hole.iter().enumerate().fold(Brdf::CLAY, |acc, (k, &v)| {
        let here = mesh.brdfs()[v as usize];
        if k == 0 {
            here
        } else {
            acc.lerp(&here, 1.0 / (k + 1) as f32)
        }
    });
    let apex = mesh.push_vertex(centroid, brdf, layer);
    (0..n).map(|i| [hole[(i + 1) % n], hole[i], apex]).collect()
}
