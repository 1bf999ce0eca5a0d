//! Small meshes of every kind the engine must handle — closed, open, tiny, several components,
//! high valence — for tests and examples.

use glam::{Vec2, Vec3};

use crate::mesh::{LayerId, Mesh, MeshError};

fn single_layer(positions: Vec<Vec3>, faces: Vec<[u32; 3]>) -> Result<Mesh, MeshError> {
    let layers = vec![0; faces.len()];
    Mesh::new(positions, faces, layers, vec!["layer0".into()])
}

/// One triangle.
pub fn triangle() -> Mesh {
    single_layer(
        vec![Vec3::ZERO, Vec3::X, Vec3::new(0.5, 0.866_025_4, 0.0)],
        vec![[0, 1, 2]],
    )
    .expect("valid")
}

/// The smallest closed surface.
pub fn tetrahedron() -> Mesh {
    single_layer(
        vec![
            Vec3::new(1.0, 1.0, 1.0),
            Vec3::new(1.0, -1.0, -1.0),
            Vec3::new(-1.0, 1.0, -1.0),
            Vec3::new(-1.0, -1.0, 1.0),
        ],
        vec![[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]],
    )
    .expect("valid")
}

/// A closed octahedron (every vertex of valence 4).
pub fn octahedron() -> Mesh {
    single_layer(
        vec![Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z],
        vec![
            [0, 2, 4],
            [2, 1, 4],
            [1, 3, 4],
            [3, 0, 4],
            [2, 0, 5],
            [1, 2, 5],
            [3, 1, 5],
            [0, 3, 5],
        ],
    )
    .expect("valid")
}

/// An open disk: `sides` triangles around a centre vertex of valence `sides`.
pub fn fan(sides: u32) -> Mesh {
    let mut positions = vec![Vec3::ZERO];
    for k in 0..sides {
        let angle = std::f32::consts::TAU * k as f32 / sides as f32;
        positions.push(Vec3::new(angle.cos(), angle.sin(), 0.0));
    }
    let faces = (0..sides)
        .map(|k| [0, 1 + k, 1 + (k + 1) % sides])
        .collect();
    single_layer(positions, faces).expect("valid")
}

/// A flat patch of `columns × rows` squares, each split into two right triangles, with spacing
/// `edge`, at height `z`, from `origin`.
pub fn grid_patch(
    columns: u32,
    rows: u32,
    edge: f32,
    z: f32,
    origin: Vec2,
) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut positions = Vec::new();
    for j in 0..=rows {
        for i in 0..=columns {
            positions.push(Vec3::new(
                origin.x + i as f32 * edge,
                origin.y + j as f32 * edge,
                z,
            ));
        }
    }
    let at = |i: u32, j: u32| j * (columns + 1) + i;
    let mut faces = Vec::new();
    for j in 0..rows {
        for i in 0..columns {
            faces.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            faces.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    (positions, faces)
}

/// Stacked flat sheets, one layer each, `gap` apart; layer `k` is `columns × rows` cells.
pub fn stacked_sheets(layers: u32, columns: u32, rows: u32, edge: f32, gap: f32) -> Mesh {
    let mut positions = Vec::new();
    let mut faces = Vec::new();
    let mut face_layers = Vec::new();
    for layer in 0..layers {
        let (p, f) = grid_patch(columns, rows, edge, layer as f32 * gap, Vec2::ZERO);
        let base = positions.len() as u32;
        positions.extend(p);
        face_layers.extend(std::iter::repeat_n(layer as LayerId, f.len()));
        faces.extend(f.into_iter().map(|t| t.map(|v| v + base)));
    }
    let names = (0..layers).map(|l| format!("layer{l}")).collect();
    Mesh::new(positions, faces, face_layers, names).expect("valid")
}

/// Two disjoint patches on one layer (several components).
pub fn two_patches() -> Mesh {
    let (mut positions, mut faces) = grid_patch(3, 3, 1.0, 0.0, Vec2::ZERO);
    let (p, f) = grid_patch(2, 2, 1.0, 0.0, Vec2::new(10.0, 0.0));
    let base = positions.len() as u32;
    positions.extend(p);
    faces.extend(f.into_iter().map(|t| t.map(|v| v + base)));
    single_layer(positions, faces).expect("valid")
}
