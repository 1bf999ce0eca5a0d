//! The pieces of surface a topology change removes: the faces around a cluster of touching
//! vertices, their Euler characteristic, and the loops their removal leaves.

use std::collections::{HashMap, HashSet};

use crate::mesh::{INVALID, Mesh, face_of, next, prev};

/// Clusters of `members` (vertices) joined by edges of the mesh, each sorted; `members` in
/// ascending order gives the clusters in order of their lowest vertex.
pub fn clusters(mesh: &Mesh, members: &[u32]) -> Vec<Vec<u32>> {
    let wanted: HashSet<u32> = members.iter().copied().collect();
    let mut seen = HashSet::new();
    let mut out = Vec::new();
    for &start in members {
        if !seen.insert(start) {
            continue;
        }
        let mut cluster = vec![start];
        let mut i = 0;
        while i < cluster.len() {
            for w in mesh.neighbours(cluster[i]) {
                if wanted.contains(&w) && seen.insert(w) {
                    cluster.push(w);
                }
            }
            i += 1;
        }
        cluster.sort_unstable();
        out.push(cluster);
    }
    out
}

/// The faces around `vertices` and `rings` rings of faces more, sorted.
pub fn faces_around(mesh: &Mesh, vertices: &[u32], rings: usize) -> Vec<u32> {
    let mut faces: HashSet<u32> = vertices
        .iter()
        .flat_map(|&v| mesh.faces_around(v))
        .collect();
    for _ in 0..rings {
        let corners: HashSet<u32> = faces
            .iter()
            .flat_map(|&f| mesh.faces()[f as usize])
            .collect();
        faces.extend(corners.iter().flat_map(|&v| mesh.faces_around(v)));
    }
    let mut faces: Vec<u32> = faces.into_iter().collect();
    faces.sort_unstable();
    faces
}

/// V − E + F of the surface the faces make on their own: 1 for a disc, 0 for an annulus.
pub fn euler_characteristic(mesh: &Mesh, faces: &[u32]) -> i64 {
    let inside: HashSet<u32> = faces.iter().copied().collect();
    let vertices: HashSet<u32> = faces
        .iter()
        .flat_map(|&f| mesh.faces()[f as usize])
        .collect();
    let mut twice_edges = 0i64;
    for &f in faces {
        for k in 0..3 {
            let o = mesh.adjacency().opposite[3 * f as usize + k];
            // An edge between two of the faces is seen twice, one on their rim once.
            twice_edges += if o != INVALID && inside.contains(&face_of(o)) {
                1
            } else {
                2
            };
        }
    }
    vertices.len() as i64 - twice_edges / 2 + faces.len() as i64
}

/// The holes removing `faces` leaves: each a closed loop of vertices in the direction of the
/// remaining faces' edges (the way a face filling the hole must run the other way). `None`
/// where the faces reach the mesh's own boundary or a loop passes a vertex twice (removing
/// them would pinch the surface there).
pub fn hole_loops(mesh: &Mesh, faces: &[u32]) -> Option<Vec<Vec<u32>>> {
    let inside: HashSet<u32> = faces.iter().copied().collect();
    // The remaining face across each rim edge holds it as (to, from) of the removed face's.
    let mut step: HashMap<u32, u32> = HashMap::new();
    for &f in faces {
        for k in 0..3 {
            let c = 3 * f + k as u32;
            let o = mesh.adjacency().opposite[c as usize];
            if o == INVALID {
                return None;
            }
            if inside.contains(&face_of(o)) {
                continue;
            }
            let (from, to) = (mesh.corner_vertex(prev(c)), mesh.corner_vertex(next(c)));
            if step.insert(from, to).is_some() {
                return None;
            }
        }
    }
    let mut starts: Vec<u32> = step.keys().copied().collect();
    starts.sort_unstable();
    let mut walked = HashSet::new();
    let mut loops = Vec::new();
    for start in starts {
        if walked.contains(&start) {
            continue;
        }
        let mut cycle = vec![start];
        walked.insert(start);
        let mut v = step[&start];
        while v != start {
            if !walked.insert(v) {
                return None;
            }
            cycle.push(v);
            v = *step.get(&v)?;
        }
        loops.push(cycle);
    }
    Some(loops)
}

/// Faces reached from the rim of `hole` (a loop of [`hole_loops`] of `removed`) without
/// crossing `removed`, counted up to `limit`.
pub fn faces_beyond(mesh: &Mesh, removed: &[u32], hole: &[u32], limit: usize) -> usize {
    let removed: HashSet<u32> = removed.iter().copied().collect();
    let on_hole: HashSet<u32> = hole.iter().copied().collect();
    // The remaining faces holding a rim edge of this hole.
    let mut reached: Vec<u32> = removed
        .iter()
        .flat_map(|&f| (0..3).map(move |k| 3 * f + k))
        .filter_map(|c| {
            let o = mesh.adjacency().opposite[c as usize];
            let rim = [mesh.corner_vertex(next(c)), mesh.corner_vertex(prev(c))];
            (o != INVALID
                && !removed.contains(&face_of(o))
                && rim.iter().all(|v| on_hole.contains(v)))
            .then(|| face_of(o))
        })
        .collect();
    reached.sort_unstable();
    reached.dedup();
    let mut seen: HashSet<u32> = reached.iter().copied().collect();
    let mut i = 0;
    while i < reached.len() && reached.len() < limit {
        let f = reached[i];
        for k in 0..3 {
            let o = mesh.adjacency().opposite[(3 * f + k) as usize];
            if o != INVALID && !removed.contains(&face_of(o)) && seen.insert(face_of(o)) {
                reached.push(face_of(o));
            }
        }
        i += 1;
    }
    reached.len().min(limit)
}
