//! What the viewport's GPU buffers must receive: the engine thread keeps a [`Mirror`] of
//! what it has sent (each vertex's render row, each face's corners, by number) and sends only
//! the rows and corners that differ from it, in runs. A stroke sample says which vertices it
//! changed, so only those are compared; after remeshing, an undo or an open, the whole mesh
//! is compared (a few milliseconds at a million faces, on the engine's thread) and still only
//! what differs is sent.
//!
//! Where the viewport shares the GPU backend's device, it draws positions and normals from the
//! backend's own buffers ([`EngineVertices`]): the rows it is sent then carry only what the
//! backend does not keep (layer, material, mask), so a sculpting stroke sends none.

use bytemuck::Zeroable;
use glam::Vec3;

use crate::mesh::{INVALID, Mesh};
use crate::pipeline::EngineVertices;
use crate::render::{RenderVertex, render_vertex};

/// Items closer than this are sent as one run with those between them: one buffer write
/// instead of several small ones.
const RUN_GAP: u32 = 8;

/// A face the viewport must not draw (dead, or never filled): zero area, culled.
const NO_FACE: [u32; 3] = [0; 3];

/// Changes for the viewport's buffers.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MeshUpdate {
    pub vertex_count: u32,
    pub face_count: u32,
    /// Runs of consecutive vertex rows: (first vertex, rows).
    pub rows: Vec<(u32, Vec<RenderVertex>)>,
    /// Runs of consecutive faces' corners: (first face, corners).
    pub corners: Vec<(u32, Vec<[u32; 3]>)>,
    /// The mesh's box, when the whole mesh was compared.
    pub bounds: Option<Option<(Vec3, Vec3)>>,
    /// Where positions and normals are drawn from: the GPU backend's buffers, or (`None`) the
    /// rows.
    pub engine: Option<EngineVertices>,
    /// Positions or normals changed in the backend's buffers, which the rows do not show:
    /// the viewport must draw again.
    pub redraw: bool,
}

impl MeshUpdate {
    /// Bytes the update writes.
    pub fn bytes(&self) -> usize {
        let rows: usize = self.rows.iter().map(|(_, r)| r.len()).sum();
        let corners: usize = self.corners.iter().map(|(_, c)| c.len()).sum();
        rows * std::mem::size_of::<RenderVertex>() + corners * 12
    }

    pub fn is_empty(&self) -> bool {
        self.rows.is_empty() && self.corners.is_empty() && self.bounds.is_none() && !self.redraw
    }
}

/// What the viewport holds, as last sent.
#[derive(Debug, Clone, Default)]
pub struct Mirror {
    rows: Vec<RenderVertex>,
    corners: Vec<[u32; 3]>,
    engine: Option<EngineVertices>,
}

impl Mirror {
    /// What differs between the mirror and `mesh`, looking only at the vertices `changed`
    /// (and any the mesh gained) when given, at every vertex otherwise; `faces_changed`: the
    /// faces may differ too. `engine`: the GPU backend's buffers to draw positions and normals
    /// from, current with `mesh`, or `None` to send them in the rows. The mirror then matches
    /// the mesh.
    pub fn update(
        &mut self,
        mesh: &Mesh,
        changed: Option<&[u32]>,
        faces_changed: bool,
        engine: Option<EngineVertices>,
    ) -> MeshUpdate {
        // Rows switch between carrying geometry and not: every row is compared again.
        let switched = self.engine.is_some() != engine.is_some();
        // Other buffers (the backend uploaded its copy afresh), or as many vertices in them
        // (remeshing added some), or a switch of mode: the viewport binds them again.
        let rebound = self.engine != engine;
        let changed = changed.filter(|_| !switched);
        let geometry = engine.is_none();
        self.engine = engine;
        let old_vertices = self.rows.len();
        let vertex_count = mesh.vertex_count();
        self.rows.resize(vertex_count, RenderVertex::zeroed());
        let mut differing: Vec<u32> = Vec::new();
        let mut compare = |v: usize, rows: &mut Vec<RenderVertex>| {
            let row = drawn_row(mesh, v, geometry);
            if rows[v] != row || v >= old_vertices {
                rows[v] = row;
                differing.push(v as u32);
            }
        };
        match changed {
            Some(changed) => {
                for &v in changed.iter().filter(|&&v| (v as usize) < vertex_count) {
                    compare(v as usize, &mut self.rows);
                }
                (old_vertices..vertex_count).for_each(|v| compare(v, &mut self.rows));
                differing.sort_unstable();
                differing.dedup();
            }
            None => (0..vertex_count).for_each(|v| compare(v, &mut self.rows)),
        }
        let corners = if faces_changed || changed.is_none() {
            self.update_corners(mesh)
        } else {
            Vec::new()
        };
        MeshUpdate {
            vertex_count: vertex_count as u32,
            face_count: self.corners.len() as u32,
            rows: runs(&differing, &self.rows),
            corners: runs(&corners, &self.corners),
            bounds: changed.is_none().then(|| mesh.bounds()),
            redraw: rebound || (!geometry && changed.is_none_or(|c| !c.is_empty())),
            engine: self.engine.clone(),
        }
    }

    /// The faces whose corners differ from the mirror's (which then matches).
    fn update_corners(&mut self, mesh: &Mesh) -> Vec<u32> {
        let old_faces = self.corners.len();
        self.corners.resize(mesh.face_count(), NO_FACE);
        let mut differing = Vec::new();
        for (f, face) in mesh.faces().iter().enumerate() {
            let drawn = if face[0] == INVALID || mesh.is_face_dead(f) {
                NO_FACE
            } else {
                *face
            };
            if self.corners[f] != drawn || f >= old_faces {
                self.corners[f] = drawn;
                differing.push(f as u32);
            }
        }
        differing
    }
}

/// Vertex `v`'s row as the viewport draws it: without position and normal where those come
/// from the GPU backend's buffers (`geometry` false).
fn drawn_row(mesh: &Mesh, v: usize, geometry: bool) -> RenderVertex {
    let row = render_vertex(mesh, v);
    if geometry {
        row
    } else {
        RenderVertex {
            position: [0.0; 3],
            normal: [0.0; 3],
            ..row
        }
    }
}

/// `items` (ascending) grouped into runs of consecutive numbers, gaps of up to [`RUN_GAP`]
/// filled from `all`.
fn runs<T: Copy>(items: &[u32], all: &[T]) -> Vec<(u32, Vec<T>)> {
    let mut runs: Vec<(u32, Vec<T>)> = Vec::new();
    for &i in items {
        match runs.last_mut() {
            Some((first, run)) if i <= *first + run.len() as u32 + RUN_GAP => {
                let next = *first + run.len() as u32;
                run.extend_from_slice(&all[next as usize..=i as usize]);
            }
            _ => runs.push((i, vec![all[i as usize]])),
        }
    }
    runs
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{SceneKind, SceneSpec, generate};

    fn plaster() -> Mesh {
        generate(&SceneSpec {
            kind: SceneKind::Plaster,
            triangles: 500,
            seed: 1,
        })
        .unwrap()
    }

    /// Applies an update to plain arrays, as the viewport does to its buffers.
    fn apply(rows: &mut Vec<RenderVertex>, corners: &mut Vec<[u32; 3]>, update: &MeshUpdate) {
        rows.resize(update.vertex_count as usize, RenderVertex::zeroed());
        corners.resize(update.face_count as usize, NO_FACE);
        for (first, run) in &update.rows {
            rows[*first as usize..*first as usize + run.len()].copy_from_slice(run);
        }
        for (first, run) in &update.corners {
            corners[*first as usize..*first as usize + run.len()].copy_from_slice(run);
        }
    }

    #[test]
    fn updates_keep_a_copy_equal_to_the_mesh_and_send_only_what_changed() {
        let mut mesh = plaster();
        let mut mirror = Mirror::default();
        let (mut rows, mut corners) = (Vec::new(), Vec::new());
        let first = mirror.update(&mesh, None, true, None);
        assert_eq!(first.rows.len(), 1, "everything, in one run");
        apply(&mut rows, &mut corners, &first);

        // A sample moved three vertices.
        for v in [3u32, 5, 200] {
            mesh.positions_mut()[v as usize].z += 0.01;
        }
        let update = mirror.update(&mesh, Some(&[3, 5, 200, 7]), false, None);
        assert_eq!(update.rows.len(), 2, "3..=5 and 200 (7 did not change)");
        assert!(update.corners.is_empty());
        assert!(update.bytes() < 5 * std::mem::size_of::<RenderVertex>());
        apply(&mut rows, &mut corners, &update);

        // Remeshing: an edge split, with nothing said about what it changed.
        let faces_before = mesh.face_count();
        mesh.split_edge(30, 0.5);
        let update = mirror.update(&mesh, None, true, None);
        let rewritten: usize = update.corners.iter().map(|(_, c)| c.len()).sum();
        assert!(
            rewritten >= 2 && rewritten < 2 * RUN_GAP as usize + 4,
            "{rewritten} faces sent"
        );
        assert_eq!(update.face_count as usize, mesh.face_count());
        assert!(mesh.face_count() > faces_before);
        apply(&mut rows, &mut corners, &update);

        let expected: Vec<RenderVertex> = (0..mesh.vertex_count())
            .map(|v| render_vertex(&mesh, v))
            .collect();
        assert_eq!(rows, expected);
        let drawn: Vec<[u32; 3]> = (0..mesh.face_count())
            .map(|f| {
                if mesh.is_face_dead(f) {
                    NO_FACE
                } else {
                    mesh.faces()[f]
                }
            })
            .collect();
        assert_eq!(corners, drawn);
        assert!(mirror.update(&mesh, None, true, None).rows.is_empty());
    }
}
