//! A set of small indices that empties in O(1): each index remembers the round that last
//! marked it, and starting a round bumps the round number. The broad phases use it to visit
//! each face once per query without clearing anything.

#[derive(Debug, Clone, Default)]
pub struct Stamps {
    marks: Vec<u32>,
    round: u32,
}

impl Stamps {
    /// Empties the set and makes room for indices below `len`.
    pub fn start(&mut self, len: usize) {
        self.size_for(len);
        self.round = self.round.wrapping_add(1);
        if self.round == 0 {
            // After 2³² rounds the marks could alias: clear them once.
            self.marks.fill(0);
            self.round = 1;
        }
    }

    /// Makes room for indices below `len` without starting a round (set-up, ahead of use).
    pub fn size_for(&mut self, len: usize) {
        crate::grow::grow_to(&mut self.marks, len, 0);
    }

    /// Adds `index`; true when it was not in the set yet this round.
    #[inline]
    pub fn insert(&mut self, index: usize) -> bool {
        let mark = &mut self.marks[index];
        let fresh = *mark != self.round;
        *mark = self.round;
        fresh
    }

    #[inline]
    pub fn contains(&self, index: usize) -> bool {
        self.marks.get(index) == Some(&self.round)
    }
}
