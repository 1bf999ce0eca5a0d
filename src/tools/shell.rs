//! Thickening a sheet into a closed shell: the sheet turned inward, a copy of it moved out
//! along the normals, and a band of triangles about one edge length high joining their
//! boundaries.

use glam::Vec3;

use crate::mesh::{INVALID, Mesh, MeshError};

/// `sheet` (one layer) as a closed shell `thickness` thick: the sheet itself, turned to face
/// inward, and its copy `thickness` out along the vertex normals, joined along every
/// boundary by rows of about `edge` high. A closed sheet gives two nested closed surfaces.
pub(super) fn thicken(sheet: &Mesh, thickness: f32, edge: f32) -> Result<Mesh, MeshError> {
    let n = sheet.vertex_count() as u32;
    let rows = ((thickness / edge).round() as u32).max(1);
    let faces = sheet.faces();
    let opposite = &sheet.adjacency().opposite;
    // Each boundary edge as it runs in its face: (a, b) with the face on its left.
    let boundary: Vec<(u32, u32)> = (0..faces.len())
        .flat_map(|f| (0..3).map(move |k| (f, k)))
        .filter(|&(f, k)| opposite[3 * f + k] == INVALID)
        .map(|(f, k)| (faces[f][(k + 1) % 3], faces[f][(k + 2) % 3]))
        .collect();
    let mut ring_index = vec![INVALID; n as usize];
    let mut ring = Vec::new();
    for &(a, _) in &boundary {
        if ring_index[a as usize] == INVALID {
            ring_index[a as usize] = ring.len() as u32;
            ring.push(a);
        }
    }
    let inner = sheet.positions();
    let outer: Vec<Vec3> = inner
        .iter()
        .zip(sheet.normals())
        .map(|(&p, &normal)| p + normal * thickness)
        .collect();
    let mut positions = outer.clone();
    positions.extend_from_slice(inner);
    for k in 1..rows {
        let t = k as f32 / rows as f32;
        positions.extend(
            ring.iter()
                .map(|&v| outer[v as usize].lerp(inner[v as usize], t)),
        );
    }
    // Row 0 is the outer sheet, row `rows` the inner one, the rows between hold ring vertices.
    let at = |v: u32, row: u32| match row {
        0 => v,
        r if r == rows => n + v,
        r => 2 * n + (r - 1) * ring.len() as u32 + ring_index[v as usize],
    };
    let mut tris: Vec<[u32; 3]> = faces.to_vec();
    tris.extend(faces.iter().map(|&[a, b, c]| [a + n, c + n, b + n]));
    for &(a, b) in &boundary {
        for k in 0..rows {
            let (a0, b0, a1, b1) = (at(a, k), at(b, k), at(a, k + 1), at(b, k + 1));
            tris.push([b0, a0, a1]);
            tris.push([b0, a1, b1]);
        }
    }
    let layers = vec![0; tris.len()];
    let mut shell = Mesh::new(positions, tris, layers, sheet.layer_names().to_vec())?;
    let brdfs = sheet.brdfs();
    let mut shell_brdfs: Vec<_> = brdfs.iter().chain(brdfs).copied().collect();
    for _ in 1..rows {
        shell_brdfs.extend(ring.iter().map(|&v| brdfs[v as usize]));
    }
    shell.set_brdfs(shell_brdfs)?;
    Ok(shell)
}
