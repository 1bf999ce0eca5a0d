//! The vertex→faces incidence in compressed sparse rows: the form GPU kernels read, and the
//! cheapest way to visit "faces incident to vertices in a cell" in the broad phase.

use super::INVALID;

#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct VertexFaces {
    /// `offsets[v]..offsets[v + 1]` indexes `faces` for vertex `v`.
    pub offsets: Vec<u32>,
    pub faces: Vec<u32>,
}

impl VertexFaces {
    /// Counting sort of the live faces' corners by vertex; faces stay in ascending order.
    pub fn build(faces: &[[u32; 3]], vertex_count: usize) -> Self {
        let mut offsets = vec![0u32; vertex_count + 1];
        for tri in faces.iter().filter(|t| t[0] != INVALID) {
            for &v in tri {
                offsets[v as usize + 1] += 1;
            }
        }
        for i in 0..vertex_count {
            offsets[i + 1] += offsets[i];
        }
        let mut cursor = offsets.clone();
        let mut incident = vec![0u32; offsets[vertex_count] as usize];
        for (f, tri) in faces.iter().enumerate() {
            if tri[0] == INVALID {
                continue;
            }
            for &v in tri {
                let slot = &mut cursor[v as usize];
                incident[*slot as usize] = f as u32;
                *slot += 1;
            }
        }
        VertexFaces {
            offsets,
            faces: incident,
        }
    }

    /// Faces incident to `vertex`.
    #[inline]
    pub fn of(&self, vertex: u32) -> &[u32] {
        let v = vertex as usize;
        &self.faces[self.offsets[v] as usize..self.offsets[v + 1] as usize]
    }
}
