//! A vertex's one-ring as a small list kept on the stack: the remesher and the topology edits
//! ask for rings millions of times a pass, and a heap list each time cost as much as walking
//! the fan.

use super::Mesh;

/// The longest ring kept on the stack; longer ones (rare: valence above 32) go to the heap.
const STACK_RING: usize = 32;

/// A vertex's neighbours in fan order ([`Mesh::neighbours`]): a slice, and an owned iterator.
#[derive(Debug, Clone)]
pub enum Ring {
    Stack([u32; STACK_RING], usize),
    Heap(Vec<u32>),
}

impl Ring {
    pub(super) fn of(mesh: &Mesh, vertex: u32) -> Ring {
        let mut stack = [0; STACK_RING];
        let mut count = 0;
        for u in mesh.ring(vertex) {
            let Some(slot) = stack.get_mut(count) else {
                return Ring::Heap(mesh.ring(vertex).collect());
            };
            *slot = u;
            count += 1;
        }
        Ring::Stack(stack, count)
    }
}

impl std::ops::Deref for Ring {
    type Target = [u32];

    fn deref(&self) -> &[u32] {
        match self {
            Ring::Stack(stack, count) => &stack[..*count],
            Ring::Heap(ring) => ring,
        }
    }
}

impl IntoIterator for Ring {
    type Item = u32;
    type IntoIter = RingIter;

    fn into_iter(self) -> RingIter {
        RingIter { ring: self, at: 0 }
    }
}

/// [`Ring`]'s vertices, by value.
pub struct RingIter {
    ring: Ring,
    at: usize,
}

impl Iterator for RingIter {
    type Item = u32;

    fn next(&mut self) -> Option<u32> {
        let v = self.ring.get(self.at).copied();
        self.at += 1;
        v
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        let left = self.ring.len().saturating_sub(self.at);
        (left, Some(left))
    }
}

impl ExactSizeIterator for RingIter {}
