//! Culling a whole-mesh remesh's safety checks (issue 28): the checks of `safety` prove, edit by
//! edit, that no face crosses another and no surface comes too close to another. Where a cell of
//! the mesh holds one *sheet* and nothing else, that proof is settled once for the cell.
//!
//! A cell's *zone* is every face that meets its box grown by [`MARGIN_EDGES`]·L, when
//! - they are all of one layer, none on the mesh's rim;
//! - their boundary is one loop, simple once projected along their mean normal `a`;
//! - every unit normal `n` has `n·a ≥` [`MIN_COS`].
//!
//! Such a set of faces projects one-to-one onto the plane across `a`: each face keeps its
//! orientation there, so a point of the plane lies under as many faces as the projected loop
//! winds around it, 0 or 1 (the normal-cone test of Volino & Magnenat-Thalmann, as the stroke's
//! culling uses it, `collide::sheet`). No two of its faces meet beyond what they share.
//!
//! An edit whose new faces lie in the box grown by [`INNER_EDGES`]·L, each facing along `a` by
//! at least [`MIN_COS`], keeps all that true: it rewires the sheet inside the loop without
//! touching the loop (the loop's edges lie outside the grown box, farther than an edit's faces
//! reach), and every face still faces along `a`. So its faces cross nothing of the sheet, and
//! nothing else is within the margin: the crossing tests, and the layer-gap tests against
//! other layers, would find nothing. The one check the zone answers differently is a vertex's
//! distance to its own layer outside its exclusion ring: within a sheet that cannot fold onto
//! itself there is no other part of the layer to keep away from, only the mesh's own next
//! rings, and the zone lets the move be. (On the torus the full checks refuse nothing
//! either way; `tests/remesh.rs` compares culled and unculled remeshes bit for bit.)
//!
//! An edit the zone cannot vouch for is checked in full, and the zone is dropped for the rest
//! of the cell's pass: its faces may leave the set no longer a sheet.
//!
//! A *lone sheet* is a zone too: a whole mesh of one layer whose rim is one loop, simple in
//! projection, every normal in the cone (a layer tool's new piece, remeshed on its own before
//! it joins the mesh and is checked exactly against it). The same argument holds with the rim
//! as the loop and no box: nothing else exists for an edit to come near, and an edit keeps the
//! loop as it is when it moves no rim vertex and rewires no rim edge, which the remesher tells
//! the zone with each edit (a cell's inner box is farther than an edit's reach from any rim,
//! so there the answer is always yes).

use glam::Vec3;

use super::normal;
use crate::collide::{Stamps, boundary_loop, normal_cone, projected_loop_is_simple, rim_loop};
use crate::geom::Aabb;
use crate::grid::SpatialHash;
use crate::mesh::Mesh;

/// How far (× L) an edit's faces may reach past the cell and still be vouched for: a cell's
/// vertices' faces reach an edge or so past it, a ring grown around them one more.
const INNER_EDGES: f32 = 3.0;
/// How far (× L) past the cell the zone's faces are gathered: beyond the inner box by more
/// than an edge, so that the sheet's boundary loop (edges of faces outside the gathered box)
/// is out of every vouched edit's reach.
pub(super) const MARGIN_EDGES: f32 = 6.0;
/// The least cosine between a zone face's unit normal and the axis: far enough from 0 that
/// `f32` rounding cannot turn a face over.
const MIN_COS: f32 = 0.25;
/// Faces with twice their area below this share of L² are left to the full checks: their
/// normals are too short to trust in `f32`.
const MIN_DOUBLE_AREA: f32 = 1e-3;

/// A cell where one sheet is all there is: what its edits must keep to be vouched for.
#[derive(Debug, Clone, Copy)]
pub(super) struct Zone {
    axis: Vec3,
    /// Where an edit's faces must lie: a cell's inner box, or anywhere in a lone sheet.
    inner: Option<Aabb>,
    min_double_area: f32,
}

/// Finds cells' zones, with the sets it marks faces in kept from cell to cell (sized to the
/// mesh once, emptied in O(1)).
#[derive(Debug, Clone, Default)]
pub(super) struct ZoneFinder {
    seen: Stamps,
    members: Stamps,
    faces: Vec<u32>,
}

impl ZoneFinder {
    /// The zone of the cell `core`, if the faces around it form a sheet (the module's
    /// conditions). `longest_edge` bounds every edge of the mesh: a face meeting the gathered
    /// box has a vertex within that of it.
    pub(super) fn find(
        &mut self,
        mesh: &Mesh,
        grid: &SpatialHash,
        core: &Aabb,
        lengths: (f32, f32),
    ) -> Option<Zone> {
        self.find_within(mesh, grid, core, lengths, usize::MAX)
    }

    /// [`find`](Self::find), giving up (`None`) once the faces around the box pass
    /// `max_faces`: a stroke's region may span a box far larger than itself (a long diagonal
    /// stroke), where gathering the box would cost more than checking the edits.
    pub(super) fn find_within(
        &mut self,
        mesh: &Mesh,
        grid: &SpatialHash,
        core: &Aabb,
        (target_edge, longest_edge): (f32, f32),
        max_faces: usize,
    ) -> Option<Zone> {
        let outer = core.expanded(MARGIN_EDGES * target_edge);
        let reach = outer.expanded(longest_edge);
        let (seen, members, faces) = (&mut self.seen, &mut self.members, &mut self.faces);
        seen.start(mesh.face_count());
        members.start(mesh.face_count());
        faces.clear();
        // Given up on once too many, or on a face of a second layer (stacked layers lie
        // within each other's margin everywhere: their regions have no zones).
        let mut given_up = false;
        let layers = mesh.face_layers();
        grid.for_each_in_box(reach.min, reach.max, |v| {
            given_up |= faces.len() > max_faces;
            if given_up {
                return;
            }
            for f in mesh.faces_around(v) {
                let meets =
                    |f: u32| Aabb::of_points(&mesh.face_positions(f as usize)).overlaps(&outer);
                if seen.insert(f as usize) && meets(f) {
                    given_up |= faces
                        .first()
                        .is_some_and(|&g| layers[g as usize] != layers[f as usize]);
                    members.insert(f as usize);
                    faces.push(f);
                }
            }
        });
        if given_up || !one_layer(mesh, faces) {
            return None;
        }
        let boundary = boundary_loop(mesh, faces, |g| members.contains(g as usize))?;
        let inner = core.expanded(INNER_EDGES * target_edge);
        Zone::of_sheet(mesh, faces, &boundary, (Some(inner), target_edge))
    }
}

fn one_layer(mesh: &Mesh, faces: &[u32]) -> bool {
    let layers = mesh.face_layers();
    faces.first().is_some_and(|&first| {
        let layer = layers[first as usize];
        faces.iter().all(|&f| layers[f as usize] == layer)
    })
}

impl Zone {
    /// The zone of the whole of `mesh` when it is a lone sheet (the module's conditions, with
    /// its rim as the loop).
    pub(super) fn of_lone_sheet(mesh: &Mesh, target_edge: f32) -> Option<Zone> {
        let faces: Vec<u32> = (0..mesh.face_count() as u32)
            .filter(|&f| !mesh.is_face_dead(f as usize))
            .collect();
        if !one_layer(mesh, &faces) {
            return None;
        }
        let rim = rim_loop(mesh, &faces)?;
        Zone::of_sheet(mesh, &faces, &rim, (None, target_edge))
    }

    /// The zone of `faces` bounded by `boundary`, if their normals lie in the cone and the
    /// loop projects simple along its axis.
    fn of_sheet(
        mesh: &Mesh,
        faces: &[u32],
        boundary: &[u32],
        (inner, target_edge): (Option<Aabb>, f32),
    ) -> Option<Zone> {
        let cone = normal_cone(mesh, faces, |v| mesh.positions()[v as usize])?;
        // The axis in f32 differs from the f64 one by far less than the margin asked here.
        let sheet = cone.cos >= f64::from(MIN_COS) + 0.01
            && projected_loop_is_simple(mesh, boundary, cone.axis);
        sheet.then(|| Zone {
            axis: cone.axis.as_vec3(),
            inner,
            min_double_area: MIN_DOUBLE_AREA * target_edge * target_edge,
        })
    }

    /// Whether faces an edit makes (at their new positions) keep the zone a sheet: inside the
    /// inner box, and each facing along the axis.
    pub(super) fn holds<'t>(&self, triangles: impl IntoIterator<Item = &'t [Vec3; 3]>) -> bool {
        triangles.into_iter().all(|t| {
            let inside = self
                .inner
                .is_none_or(|inner| t.iter().all(|&p| inner.distance_squared_to(p) == 0.0));
            let n = normal(*t);
            let length = n.length();
            inside && length > self.min_double_area && n.dot(self.axis) >= MIN_COS * length
        })
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec2;

    use super::*;
    use crate::scene::shapes::{grid_patch, stacked_sheets};

    const EDGE: f32 = 1.0;

    /// The zone of a cell 4 edges wide in the middle of `mesh` (a patch 40 × 40 from 0).
    fn zone_of(mesh: &Mesh) -> Option<Zone> {
        let grid = SpatialHash::build(mesh, 4.0 * EDGE).unwrap();
        let core = Aabb {
            min: Vec3::new(18.0, 18.0, -2.0),
            max: Vec3::new(22.0, 22.0, 2.0),
        };
        ZoneFinder::default().find(mesh, &grid, &core, (EDGE, 1.5 * EDGE))
    }

    fn sheet(bend: impl Fn(Vec3) -> Vec3, copies: &[f32]) -> Mesh {
        let (mut positions, mut faces) = (Vec::new(), Vec::new());
        for &z in copies {
            let (p, f) = grid_patch(40, 40, EDGE, z, Vec2::ZERO);
            let base = positions.len() as u32;
            positions.extend(p.into_iter().map(&bend));
            faces.extend(f.into_iter().map(|t| t.map(|v| v + base)));
        }
        let layers = vec![0; faces.len()];
        Mesh::new(positions, faces, layers, vec!["one".into()]).unwrap()
    }

    #[test]
    fn a_gently_curved_sheet_is_a_zone_and_its_edits_must_keep_facing_up() {
        let mesh = sheet(|p| p + Vec3::Z * (0.1 * p.x).sin(), &[0.0]);
        let zone = zone_of(&mesh).expect("a sheet");
        let flat = [
            Vec3::new(19.0, 19.0, 0.0),
            Vec3::new(20.0, 19.0, 0.0),
            Vec3::new(19.0, 20.0, 0.0),
        ];
        assert!(zone.holds(&[flat]));
        let turned = [flat[0], flat[2], flat[1]];
        assert!(!zone.holds(&[turned]), "a face turned over");
        let standing = [flat[0], flat[1], flat[0] + Vec3::Z];
        assert!(!zone.holds(&[standing]), "a face across the axis");
        let outside = flat.map(|p| p + Vec3::X * 6.0);
        assert!(!zone.holds(&[outside]), "beyond the inner box");
        let sliver = [flat[0], flat[1], flat[1] + Vec3::X * 1e-3];
        assert!(!zone.holds(&[sliver]), "too thin to trust");
    }

    #[test]
    fn a_lone_sheet_is_a_zone_with_its_rim_as_its_loop() {
        let wavy = sheet(|p| p + Vec3::Z * (0.1 * p.x).sin(), &[0.0]);
        let zone = Zone::of_lone_sheet(&wavy, EDGE).expect("a lone sheet");
        assert!(zone.inner.is_none(), "no box: nothing else exists");
        let far = [
            Vec3::new(90.0, 90.0, 0.0),
            Vec3::new(91.0, 90.0, 0.0),
            Vec3::new(90.0, 91.0, 0.0),
        ];
        assert!(zone.holds(&[far]), "anywhere, facing along the axis");
        assert!(
            !zone.holds(&[[far[0], far[2], far[1]]]),
            "a face turned over"
        );
        // Two sheets: two rims. A sheet folded over itself: normals past the cone.
        assert!(Zone::of_lone_sheet(&sheet(|p| p, &[0.0, 2.0]), EDGE).is_none());
        let folded = sheet(
            |p| {
                let t = (p.x - 20.0).clamp(0.0, std::f32::consts::PI);
                Vec3::new(
                    p.x.min(20.0) + t.sin() - (p.x - 20.0 - t).max(0.0),
                    p.y,
                    1.0 - t.cos(),
                )
            },
            &[0.0],
        );
        assert!(Zone::of_lone_sheet(&folded, EDGE).is_none());
        // A closed surface has no rim.
        let sphere = crate::scene::generate(&crate::scene::SceneSpec {
            kind: crate::scene::SceneKind::Sphere,
            triangles: 500,
            seed: 1,
        })
        .unwrap();
        assert!(Zone::of_lone_sheet(&sphere, EDGE).is_none());
    }

    #[test]
    fn no_zone_where_more_than_one_sheet_is_near() {
        // Two sheets of one layer, 2 edges apart: their loops are two.
        assert!(zone_of(&sheet(|p| p, &[0.0, 2.0])).is_none());
        // Two layers.
        assert!(zone_of(&stacked_sheets(2, 40, 40, EDGE, 2.0)).is_none());
        // One sheet folded back over itself, 2 edges above, round a half-turn at x = 20.
        let folded = sheet(
            |p| {
                let t = (p.x - 20.0).clamp(0.0, std::f32::consts::PI);
                let back = (p.x - 20.0 - t).max(0.0);
                let x = p.x.min(20.0) + t.sin() - back;
                Vec3::new(x, p.y, 1.0 - t.cos())
            },
            &[0.0],
        );
        assert!(zone_of(&folded).is_none());
        // A mushroom's cap: an overhang all round the middle, the sheet's rim far off and flat.
        let cap = |p: Vec3| {
            let (from, r) = (
                (p - Vec3::new(20.0, 20.0, 0.0)).truncate(),
                p.truncate().distance(Vec2::splat(20.0)),
            );
            let t = ((r - 6.0) / 2.0).clamp(-std::f32::consts::PI, std::f32::consts::PI);
            let out = r - 2.6 * t.sin();
            let radial = if r > 0.0 { from / r * out } else { Vec2::ZERO };
            (Vec2::splat(20.0) + radial).extend(t)
        };
        assert!(zone_of(&sheet(cap, &[0.0])).is_none(), "an overhang inside");
        // A rim within the margin.
        let (p, f) = grid_patch(22, 40, EDGE, 0.0, Vec2::ZERO);
        let rim = Mesh::new(p, f.clone(), vec![0; f.len()], vec!["one".into()]).unwrap();
        assert!(zone_of(&rim).is_none());
        // And the flat sheet alone is one.
        assert!(zone_of(&sheet(|p| p, &[0.0])).is_some());
    }
}
