//! Where a fuse layer comes within the join distance of itself: per vertex, the nearest face of
//! its own layer that is not one of its neighbours (the faces touching its exclusion ring,
//! `collide::neighbourhood`, are near only because they are adjacent).

use glam::Vec3;
use rayon::prelude::*;

use crate::collide::LocalFaceGrid;
use crate::collide::neighbourhood::{in_ring, ring_vertices};
use crate::geom::{Aabb, point_triangle_distance_squared};
use crate::mesh::Mesh;

/// A vertex within the join distance of a face of its own layer that is not its neighbour.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    pub vertex: u32,
    pub face: u32,
    pub distance: f32,
}

/// The contacts of `vertices` (those live and on a layer `fuse` marks), nearest first (ties to
/// the lower vertex), at most one per vertex: its nearest face.
pub fn find_contacts(
    mesh: &Mesh,
    fuse: &[bool],
    vertices: &[u32],
    (join_distance, ring): (f32, u32),
) -> Vec<Contact> {
    let on_fuse = |v: u32| {
        mesh.is_vertex_live(v) && fuse.get(mesh.vertex_layers()[v as usize] as usize) == Some(&true)
    };
    let mut vertices: Vec<u32> = vertices.iter().copied().filter(|&v| on_fuse(v)).collect();
    vertices.sort_unstable();
    vertices.dedup();
    if vertices.is_empty() {
        return Vec::new();
    }
    let near = box_of(mesh, &vertices).expanded(join_distance);
    let faces: Vec<u32> = (0..mesh.face_count() as u32)
        .filter(|&f| {
            let layer = mesh.face_layers()[f as usize] as usize;
            !mesh.is_face_dead(f as usize)
                && fuse.get(layer) == Some(&true)
                && Aabb::of_points(&mesh.face_positions(f as usize)).overlaps(&near)
        })
        .collect();
    if faces.is_empty() {
        return Vec::new();
    }
    let boxes: Vec<Aabb> = faces
        .iter()
        .map(|&f| Aabb::of_points(&mesh.face_positions(f as usize)))
        .collect();
    let bounds = boxes
        .iter()
        .fold(Aabb::EMPTY, |all, b| all.including_box(b));
    let mut grid = LocalFaceGrid::default();
    grid.build(&boxes, bounds, join_distance);
    let mut contacts: Vec<Contact> = vertices
        .par_iter()
        .map_init(Vec::new, |ring_scratch, &v| {
            nearest_stranger(
                mesh,
                v,
                (&faces, &grid),
                (join_distance, ring),
                ring_scratch,
            )
        })
        .flatten()
        .collect();
    contacts.sort_by(|a, b| {
        a.distance
            .total_cmp(&b.distance)
            .then(a.vertex.cmp(&b.vertex))
    });
    contacts
}

/// The nearest face of `v`'s layer within `join_distance` that has no vertex in `v`'s ring.
fn nearest_stranger(
    mesh: &Mesh,
    v: u32,
    (faces, grid): (&[u32], &LocalFaceGrid),
    (join_distance, ring): (f32, u32),
    ring_scratch: &mut Vec<u32>,
) -> Option<Contact> {
    let p = mesh.positions()[v as usize];
    let layer = mesh.vertex_layers()[v as usize];
    ring_vertices(mesh, v, ring, ring_scratch);
    let query = Aabb::of_points(&[p]).expanded(join_distance);
    let mut best: Option<(f32, u32)> = None;
    grid.for_each_candidate(&query, |local| {
        let f = faces[local as usize];
        let tri = mesh.faces()[f as usize];
        if mesh.face_layers()[f as usize] != layer || tri.iter().any(|&w| in_ring(ring_scratch, w))
        {
            return;
        }
        let [a, b, c] = tri.map(|w| mesh.positions()[w as usize]);
        let found = (point_triangle_distance_squared(p, a, b, c), f);
        // Ties go to the lower face: the grid may offer a face twice, in any order.
        if best.is_none_or(|b| found.0 < b.0 || (found.0 == b.0 && found.1 < b.1)) {
            best = Some(found);
        }
    });
    best.filter(|&(d2, _)| d2 < join_distance * join_distance)
        .map(|(d2, face)| Contact {
            vertex: v,
            face,
            distance: d2.sqrt(),
        })
}

/// The box around `points`.
pub fn box_of(mesh: &Mesh, vertices: &[u32]) -> Aabb {
    let points: Vec<Vec3> = vertices
        .iter()
        .map(|&v| mesh.positions()[v as usize])
        .collect();
    Aabb::of_points(&points)
}
