//! A grab lets go of what collisions hold still. A grab moves the vertices it caught by the
//! brush's motion at every sample, and collisions hold back those that would come within the
//! collision distance of something (or undo their whole move, where the exact backstop finds
//! a crossing). Dragged on, those held still are held still again: a drag of 300 sphere
//! diameters spent 94 % of its time clamping vertices that did not move (177 a step, 10
//! moving). The sLayer paper locks a vertex once it collides. A grab here lets go of a vertex
//! that two samples in a row left where it was (after one, a shorter move may still pass what
//! the backstop undid whole), for as long as the drag keeps its direction, so that each sample
//! costs what still moves. When the drag turns (past [`TURN_COS`]) every vertex let go
//! rejoins: a push into a wall and a pull back still brings the surface back.

use glam::Vec3;

/// The cosine of the largest turn, from the motion that held the first vertex still, that
/// keeps the vertices let go out of the grab (45°).
const TURN_COS: f32 = std::f32::consts::FRAC_1_SQRT_2;

/// The vertices a grab has let go of, and the motion that held the first of them. Empty for
/// a stroke that does not let go (the pipeline tells it nothing then).
#[derive(Debug, Default)]
pub(super) struct LetGo {
    /// Let go: ascending, no repeats.
    vertices: Vec<u32>,
    /// Held still during the sample now running.
    this_sample: Vec<u32>,
    /// Held still during the sample before it: ascending, no repeats.
    last_sample: Vec<u32>,
    /// The brush's motion at the sample that held the first of `vertices`.
    motion: Vec3,
    /// The brush's motion at the sample now running.
    running: Vec3,
}

impl LetGo {
    /// A vertex the grab wanted to move that a step left where it was.
    pub(super) fn held_still(&mut self, vertex: u32) {
        self.this_sample.push(vertex);
    }

    /// Lets go of `vertices` at once, measuring the turn from the running sample's motion if
    /// they are the first. The pipeline gives it the ends of edges that remeshing left
    /// stretched and could not split: the grab would only draw their faces out into slivers
    /// (a drag of 64 units drew faces 7 units long between vertices let go and those still
    /// moving, and each moving face's box then covered the whole collision region).
    pub(super) fn let_go_of(&mut self, vertices: impl Iterator<Item = u32>) {
        if self.vertices.is_empty() {
            self.motion = self.running;
        }
        self.vertices.extend(vertices);
        self.vertices.sort_unstable();
        self.vertices.dedup();
    }

    /// At each grab sample, before its selection: the vertices held still in each of the last
    /// two samples are let go, and all are taken back when `motion` (the brush's, since the
    /// last sample) has turned from the motion that held the first of them by more than 45°.
    /// A sample that does not move leaves everything as it was.
    pub(super) fn start_sample(&mut self, motion: Vec3) {
        self.this_sample.sort_unstable();
        self.this_sample.dedup();
        let twice: Vec<u32> = (self.this_sample.iter().copied())
            .filter(|v| self.last_sample.binary_search(v).is_ok())
            .collect();
        if !twice.is_empty() {
            self.let_go_of(twice.into_iter());
        }
        self.last_sample = std::mem::take(&mut self.this_sample);
        let turned = motion.dot(self.motion) < TURN_COS * motion.length() * self.motion.length();
        if motion != Vec3::ZERO && turned {
            self.vertices.clear();
        }
        self.running = motion;
    }

    /// What the grab still holds of what it caught, in the caught order.
    pub(super) fn still_held(&self, caught: &[(u32, f32)]) -> Vec<(u32, f32)> {
        if self.vertices.is_empty() {
            return caught.to_vec();
        }
        caught
            .iter()
            .copied()
            .filter(|(v, _)| self.vertices.binary_search(v).is_err())
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vertices_held_still_twice_leave_the_grab_until_the_drag_turns() {
        let caught = [(3, 1.0), (1, 0.5), (7, 0.25)];
        let mut let_go = LetGo::default();
        let along = Vec3::new(1.0, 0.0, 0.0);
        let_go.start_sample(along);
        let_go.held_still(7);
        let_go.held_still(3);
        let_go.start_sample(along);
        // Held still once: still in the grab.
        assert_eq!(let_go.still_held(&caught), caught);
        let_go.held_still(3);
        let_go.held_still(1);
        let_go.start_sample(along * 2.0);
        // Held still twice in a row: let go (3); 7 moved in between, 1 only once.
        assert_eq!(let_go.still_held(&caught), [(1, 0.5), (7, 0.25)]);
        let_go.held_still(1);
        let_go.start_sample(along);
        assert_eq!(let_go.still_held(&caught), [(7, 0.25)]);
        // A turn of 40° keeps them out, a sample that does not move too.
        let_go.start_sample(Vec3::new(0.766, 0.643, 0.0));
        let_go.start_sample(Vec3::ZERO);
        assert_eq!(let_go.still_held(&caught), [(7, 0.25)]);
        // 50° from the motion that held the first: all rejoin, in the caught order.
        let_go.start_sample(Vec3::new(0.643, 0.766, 0.0));
        assert_eq!(let_go.still_held(&caught), caught);
        // The next set is measured from the motion that held its first vertex.
        let_go.held_still(1);
        let_go.start_sample(Vec3::new(0.0, 1.0, 0.0));
        let_go.held_still(1);
        let_go.start_sample(Vec3::new(0.0, 1.0, 0.0));
        assert_eq!(let_go.still_held(&caught), [(3, 1.0), (7, 0.25)]);
        let_go.start_sample(Vec3::new(0.8, 1.0, 0.0));
        assert_eq!(let_go.still_held(&caught), [(3, 1.0), (7, 0.25)]);
        let_go.start_sample(Vec3::new(1.0, 0.0, 0.0));
        assert_eq!(let_go.still_held(&caught), caught);
        // Vertices at edges remeshing could not split are let go at once.
        let_go.let_go_of([7, 1].into_iter());
        assert_eq!(let_go.still_held(&caught), [(3, 1.0)]);
    }
}
