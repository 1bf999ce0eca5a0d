//! A closed geodesic sphere: every icosahedron face divided into `n²` triangles and projected
//! onto the sphere. Unlike repeated 4-way subdivision, any `n` is allowed, so the face count
//! `20·n²` can land near a requested size.

use glam::Vec3;
use rustc_hash::FxHashMap;

use crate::material;
use crate::mesh::{Mesh, MeshError};

/// Frequency whose face count `20·n²` is closest to `triangles`.
pub fn frequency_for(triangles: usize) -> u32 {
    ((triangles as f64 / 20.0).sqrt().round() as u32).max(1)
}

/// The geodesic sphere of radius `radius` and frequency `n`.
pub fn geodesic_sphere(n: u32, radius: f32) -> Result<Mesh, MeshError> {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let corners: [Vec3; 12] = [
        Vec3::new(-1.0, t, 0.0),
        Vec3::new(1.0, t, 0.0),
        Vec3::new(-1.0, -t, 0.0),
        Vec3::new(1.0, -t, 0.0),
        Vec3::new(0.0, -1.0, t),
        Vec3::new(0.0, 1.0, t),
        Vec3::new(0.0, -1.0, -t),
        Vec3::new(0.0, 1.0, -t),
        Vec3::new(t, 0.0, -1.0),
        Vec3::new(t, 0.0, 1.0),
        Vec3::new(-t, 0.0, -1.0),
        Vec3::new(-t, 0.0, 1.0),
    ];
    const ICOSAHEDRON: [[u32; 3]; 20] = [
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    // A lattice point is identified by its icosahedron corners and integer weights, so points
    // on shared edges and corners are created once whichever face reaches them first.
    let mut index: FxHashMap<[(u32, u32); 3], u32> = FxHashMap::default();
    let mut positions: Vec<Vec3> = Vec::new();
    let mut point = |weights: [(u32, u32); 3]| -> u32 {
        let mut key = weights.map(|(c, w)| if w == 0 { (u32::MAX, 0) } else { (c, w) });
        key.sort_unstable();
        *index.entry(key).or_insert_with(|| {
            let p: Vec3 = weights
                .iter()
                .map(|&(c, w)| corners[c as usize] * w as f32)
                .sum();
            positions.push(p.normalize() * radius);
            (positions.len() - 1) as u32
        })
    };
    let mut faces = Vec::with_capacity(20 * (n * n) as usize);
    for [a, b, c] in ICOSAHEDRON {
        // Point (i, j) has weights (n - i - j, i, j) on corners (a, b, c).
        let mut at = |i: u32, j: u32| point([(a, n - i - j), (b, i), (c, j)]);
        for j in 0..n {
            for i in 0..n - j {
                let p0 = at(i, j);
                let p1 = at(i + 1, j);
                let p2 = at(i, j + 1);
                faces.push([p0, p1, p2]);
                if i + j + 1 < n {
                    let p3 = at(i + 1, j + 1);
                    faces.push([p1, p3, p2]);
                }
            }
        }
    }
    let face_layers = vec![0; faces.len()];
    let mut mesh = Mesh::new(positions, faces, face_layers, vec!["sphere".to_string()])?;
    mesh.set_layer_brdf(0, material::CLAY.brdf);
    Ok(mesh)
}
