//! A certificate that the faces around a vertex meet only where they share: what lets the
//! intersection count skip the neighbour pairs of a smooth surface (nine in ten of the pairs
//! it tests) with one look per vertex instead of one exact test per pair.

use glam::{DVec2, DVec3, Vec3};

/// Longest ring looked at; a vertex with more neighbours is left to the pair tests.
const MAX_RING: usize = 32;

/// How far above its rounding a 2-D cross product must be to count: the rounded differences and
/// products err by about 4.4e-16 of `|t1| + |t2|`, so this margin leaves a factor of 2,000.
const MARGIN: f64 = 1e-12;

/// True only when the fan of triangles around `centre` projects one-to-one onto a coordinate
/// plane. `ring` yields the far corners in fan order: face `i` has corners `centre`, `ring[i]`
/// and `ring[i + 1]`, and a `closed` fan has the face of the last and the first too. A ring
/// longer than `MAX_RING` (32) is not looked at.
///
/// Why that settles every pair in the fan: two faces whose projections overlap only at
/// `centre` or along the projection of a shared edge meet only there, since a triangle whose
/// projection has area meets each line of projection at one point. The projections overlap no
/// more than that when each face turns the same way around `centre` (sign of its 2-D cross
/// product, with a margin far above rounding) and the turns add up to less than one full turn,
/// or, closed, to exactly one. Each turn is below half a turn, so the sum is tracked by the
/// side of the first ray each later ray lies on (left, straight behind, right), which may only
/// move on: a ray back on the left would be a wrap. Closed, the last face then adds less than
/// half a turn to less than one, and a closed fan's turns add up to whole turns: exactly one.
pub fn fan_projects_one_to_one(
    centre: Vec3,
    ring: impl IntoIterator<Item = Vec3>,
    closed: bool,
) -> bool {
    let centre = centre.as_dvec3();
    let mut rays = [DVec3::ZERO; MAX_RING];
    let mut n = 0;
    for q in ring {
        let Some(ray) = rays.get_mut(n) else {
            return false;
        };
        *ray = q.as_dvec3() - centre;
        n += 1;
    }
    let faces = if closed { n } else { n.saturating_sub(1) };
    if faces < if closed { 3 } else { 1 } {
        return false;
    }
    let rays = &rays[..n];
    if !centre.is_finite() || !rays.iter().all(|r| r.is_finite()) {
        return false;
    }
    // Any axis would be sound; the one the fan faces most keeps its faces' turns clear of 0.
    let normal: DVec3 = (0..faces).map(|i| rays[i].cross(rays[(i + 1) % n])).sum();
    let axis = normal.abs().max_position();
    let sign = normal[axis].signum();
    if normal[axis] == 0.0 {
        return false;
    }
    // Right-handed about the axis, so a face's turn has the sign of its normal along it.
    let flat = |r: DVec3| match axis {
        0 => DVec2::new(r.y, r.z),
        1 => DVec2::new(r.z, r.x),
        _ => DVec2::new(r.x, r.y),
    };
    // The turn from a to b seen from the fan's side, and whether it is surely left, surely
    // right, or too close to straight (ahead or behind) to say.
    let side = |a: DVec2, b: DVec2| {
        let (t1, t2) = (a.x * b.y, a.y * b.x);
        let turn = sign * (t1 - t2);
        let margin = MARGIN * (t1.abs() + t2.abs());
        if turn > margin {
            Side::Left
        } else if turn < -margin {
            Side::Right
        } else if a.dot(b) < 0.0 {
            Side::Behind
        } else {
            Side::Ahead
        }
    };
    let first = flat(rays[0]);
    let mut last_side = Side::Left;
    for i in 0..faces {
        let (a, b) = (flat(rays[i]), flat(rays[(i + 1) % n]));
        if side(a, b) != Side::Left {
            return false;
        }
        if i + 1 < n {
            let from_first = side(first, b);
            if from_first == Side::Ahead || from_first < last_side {
                return false;
            }
            last_side = from_first;
        }
    }
    true
}

/// Where a ray lies from the first ray of the fan, in the order the fan may pass them.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Side {
    Left,
    Behind,
    Right,
    /// Along the first ray: a fan whose turns add up to a whole turn before its end.
    Ahead,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::neighbours_overlap;

    /// Every pair of the fan's faces, through the exact neighbour test.
    fn some_pair_overlaps(centre: Vec3, ring: &[Vec3], closed: bool) -> bool {
        let n = ring.len();
        let faces = if closed { n } else { n - 1 };
        let face = |i: usize| {
            let j = (i + 1) % n;
            ([centre, ring[i], ring[j]], [0, i as u32 + 1, j as u32 + 1])
        };
        (0..faces).any(|i| {
            (i + 1..faces).any(|k| {
                let ((a, a_ids), (b, b_ids)) = (face(i), face(k));
                neighbours_overlap(a, a_ids, b, b_ids)
            })
        })
    }

    fn regular_ring(count: usize, turns: f32, tilt: f32) -> Vec<Vec3> {
        (0..count)
            .map(|k| {
                let t = k as f32 * turns * std::f32::consts::TAU / count as f32;
                Vec3::new(t.cos(), t.sin(), tilt * t.cos())
            })
            .collect()
    }

    #[test]
    fn flat_and_tilted_fans_are_certified_and_wound_twice_are_not() {
        for count in [3, 6, 9] {
            assert!(fan_projects_one_to_one(
                Vec3::ZERO,
                regular_ring(count, 1.0, 0.0),
                true
            ));
            assert!(fan_projects_one_to_one(
                Vec3::ZERO,
                regular_ring(count, 1.0, 3.0),
                true
            ));
        }
        // Seven rays two turns round: every face turns left, yet the fan covers the plane twice.
        let twice = regular_ring(7, 2.0, 0.0);
        assert!(!fan_projects_one_to_one(
            Vec3::ZERO,
            twice.iter().copied(),
            true
        ));
        assert!(some_pair_overlaps(Vec3::ZERO, &twice, true));
        // Open: a boundary vertex's half fan, straight rays at both ends, is certified.
        let half: Vec<Vec3> = regular_ring(6, 1.0, 0.0)[..4].to_vec();
        assert!(fan_projects_one_to_one(
            Vec3::ZERO,
            half.iter().copied(),
            false
        ));
    }

    #[test]
    fn a_fan_folded_onto_itself_is_not_certified() {
        // The last face comes back over the first: an open fan of more than one turn.
        let mut ring = regular_ring(6, 1.0, 0.0);
        ring.push(Vec3::new(1.0, 0.5, 0.0));
        assert!(!fan_projects_one_to_one(
            Vec3::ZERO,
            ring.iter().copied(),
            false
        ));
        assert!(some_pair_overlaps(Vec3::ZERO, &ring, false));
        // A face flipped over (turning the other way), and a degenerate one.
        let mut flipped = regular_ring(6, 1.0, 0.0);
        flipped.swap(2, 3);
        assert!(!fan_projects_one_to_one(
            Vec3::ZERO,
            flipped.iter().copied(),
            true
        ));
        let mut degenerate = regular_ring(6, 1.0, 0.0);
        degenerate[2] = Vec3::ZERO;
        assert!(!fan_projects_one_to_one(
            Vec3::ZERO,
            degenerate.iter().copied(),
            true
        ));
        // A face seen edge-on from the axis: its projection has no area, so the proof is void.
        let mut edge_on = regular_ring(6, 1.0, 0.0);
        edge_on[3] = edge_on[2] * 2.0 + Vec3::Z;
        assert!(!fan_projects_one_to_one(
            Vec3::ZERO,
            edge_on.iter().copied(),
            true
        ));
        let not_finite = [Vec3::X, Vec3::Y, Vec3::new(f32::NAN, 0.0, 0.0)];
        assert!(!fan_projects_one_to_one(
            Vec3::ZERO,
            not_finite.iter().copied(),
            true
        ));
    }

    /// A certified fan has no overlapping pair, over 20,000 random fans: regular rings jittered
    /// by up to their own radius, squashed flat or not, open or closed, wound once or twice.
    /// Both certified fans and fans with an overlapping pair must be common, or the survey
    /// proves nothing.
    #[test]
    fn a_certified_fan_has_no_overlapping_pair() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(26);
        let (mut certified, mut overlapping) = (0, 0);
        for _ in 0..20_000 {
            let count = rng.random_range(3..10);
            let turns = [1.0, 1.0, 1.0, 2.0, 0.7][rng.random_range(0..5)];
            let (tilt, spread) = (rng.random_range(-3.0..3.0), rng.random_range(0.0..1.5));
            let (flatten, closed) = (rng.random_bool(0.5), rng.random_bool(0.5));
            let ring: Vec<Vec3> = regular_ring(count, turns, tilt)
                .into_iter()
                .map(|p| {
                    let q =
                        p + Vec3::from_array([(); 3].map(|_| rng.random_range(-spread..spread)));
                    if flatten {
                        Vec3::new(q.x, q.y, q.z * 1e-4)
                    } else {
                        q
                    }
                })
                .collect();
            let overlaps = some_pair_overlaps(Vec3::ZERO, &ring, closed);
            if fan_projects_one_to_one(Vec3::ZERO, ring.iter().copied(), closed) {
                assert!(
                    !overlaps,
                    "certified, yet a pair overlaps: {ring:?}, closed {closed}"
                );
                certified += 1;
            }
            overlapping += usize::from(overlaps);
        }
        assert!(
            certified > 5_000 && overlapping > 2_000,
            "{certified} certified, {overlapping} overlapping"
        );
    }
}
