//! Self-adaptive topology (Freestyle): where a layer whose policy is [`ProximityPolicy::Fuse`]
//! comes within the join distance of itself, its surface changes genus instead of only
//! colliding.
//!
//! After a stroke (the pipeline calls [`adapt`] once its remeshing is done), the vertices of a
//! fuse layer near what the stroke touched are tested against the faces of their own layer
//! that are not their neighbours ([`contacts`]). Touching vertices group into clusters along
//! the mesh's edges. For the nearest contact:
//! - its vertex and its face in **different clusters** — two parts of the surface facing each
//!   other across a gap (outside: two blobs meet; inside: a thin wall) — are **joined**: the
//!   faces around both clusters, one ring more, are removed (each must be a disc) and the two
//!   holes bridged by a tube. Blobs merge, or a wall is pierced (genus + 1).
//! - both in **one cluster** — the touching vertices go all the way round, a neck thinner than
//!   the join distance — the neck is **split**: the band of faces around the cluster is removed
//!   (it must be an annulus) and both holes capped. One component becomes two, or a handle is
//!   cut (genus − 1).
//!
//! Each change is remeshed to edge length `L` and then checked: every new edge has a face on
//! both sides, and no pair of faces near it intersects that did not before (exact tests: the
//! raw new faces first, the remeshed region after). A change that fails is undone, bit for
//! bit, and the contact stays a collision: the stroke already clamped it at the collision
//! distance. Layers never join each other.
//!
//! Floors: `contacts`, `regions`, `checks` ← `sew` ← this; below the pipeline, above `collide`
//! and `remesh`.

mod checks;
mod contacts;
mod regions;
mod sew;

use std::collections::HashSet;
use std::time::Instant;

use serde::{Deserialize, Serialize};

pub use contacts::{Contact, find_contacts};

use crate::collide::find_intersections_in;
use crate::geom::Aabb;
use crate::grid::SpatialHash;
use crate::mesh::{LayerId, Mesh};
use crate::remesh::{RemeshSettings, remesh_region};

/// How a layer meets itself within the collision distance.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ProximityPolicy {
    /// Contact stops motion (sLayer): the layer never crosses anything.
    #[default]
    Collide,
    /// Contact with itself joins or splits the surface (Freestyle); other layers still collide.
    Fuse,
}

impl std::str::FromStr for ProximityPolicy {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "collide" => Ok(ProximityPolicy::Collide),
            "fuse" => Ok(ProximityPolicy::Fuse),
            other => Err(format!(
                "unknown policy `{other}` (expected collide or fuse)"
            )),
        }
    }
}

/// Freestyle keeps edges within `[d, d_detail]`, moves a vertex at most `d_move` a step and joins
/// within `d_thickness`, with `d_thickness² = 4·d_move² + 0.35·d_detail²`: two vertices closing
/// in at `d_move` each cannot pass a triangle (circumradius² ≤ d_detail²/3 ≈ 0.35·d_detail²)
/// between two tests. With our band (`d_detail` = 4/3·L, the split length) and Freestyle's
/// `d_move` = 0.33·`d_detail`, `d_thickness` = 1.18·L. Our clamp already stops a vertex at the
/// collision distance `d`, so what the join needs is only to lie beyond it: a clamped contact
/// then always joins.
pub const JOIN_OVER_EDGE: f32 = 1.18;
/// The join distance is kept at least this many collision distances.
pub const JOIN_OVER_COLLISION: f32 = 1.1;
/// Topology changes made after one stroke at most.
pub const MAX_CHANGES_PER_PASS: usize = 16;
/// The neighbourhood a vertex skips when looking for contacts: its own faces and those touching
/// its neighbours. Collision sizes its ring from the thinnest faces (`collide::neighbourhood`),
/// which a pinched neck makes thin: a ring sized so would hide the neck's far side. A face
/// beyond one ring of a well-shaped sheet is farther than the join distance anyway, and a
/// contact between near neighbours (on slivers) is refused as overlapping or not simple.
const CONTACT_RING: u32 = 1;
/// A split leaves each side at least this many faces (before capping): a smaller part is a
/// crumb the contact clusters happened to ring, not a body pinched off.
pub const MIN_SPLIT_FACES: usize = 4 * crate::remesh::MIN_CLOSED_FACES;
/// Rounds of contact reading after one stroke at most (each after the changes of the last).
const MAX_ROUNDS: usize = 4;

/// Lengths in world units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FuseSettings {
    /// The edge length `L` the changed surface is remeshed to.
    pub edge: f32,
    /// `d`: the distance other surfaces keep (the remesher's).
    pub collision_distance: f32,
    /// `d_thickness`: parts of one fuse layer closer than this join or split.
    pub join_distance: f32,
    /// The neighbourhood ring a vertex skips when looking for contacts (one: see
    /// `CONTACT_RING`).
    pub exclusion_ring: u32,
    /// The ring the remesher skips (for `collision_distance`).
    pub collision_ring: u32,
}

impl FuseSettings {
    /// Settings for `mesh` at edge length `edge` and collision distance `collision_distance`.
    pub fn new(mesh: &Mesh, edge: f32, collision_distance: f32) -> Self {
        let ring = crate::collide::neighbourhood::exclusion_ring(mesh, collision_distance);
        FuseSettings::with_ring(edge, collision_distance, ring)
    }

    /// [`FuseSettings::new`] with the collision ring already known (the pipeline's, which its
    /// own remeshing uses).
    pub fn with_ring(edge: f32, collision_distance: f32, collision_ring: u32) -> Self {
        FuseSettings {
            edge,
            collision_distance,
            join_distance: (JOIN_OVER_EDGE * edge).max(JOIN_OVER_COLLISION * collision_distance),
            exclusion_ring: CONTACT_RING,
            collision_ring,
        }
    }
}

/// What one pass did.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct TopologyReport {
    /// Contacts found (vertices within the join distance of a stranger face), summed over tries.
    pub contacts: usize,
    /// Two parts bridged by a tube (components merged, or a wall pierced).
    pub joins: usize,
    /// Necks cut and capped.
    pub splits: usize,
    /// Changes tried and undone (the contact stays a collision), with why, in order.
    pub refused: Vec<Refusal>,
    pub millis: f64,
    /// Vertices whose position, faces or neighbours changed, added ones included, ascending.
    #[serde(skip)]
    pub changed: Vec<u32>,
}

impl TopologyReport {
    pub fn add(&mut self, other: &TopologyReport) {
        self.contacts += other.contacts;
        self.joins += other.joins;
        self.splits += other.splits;
        self.refused.extend_from_slice(&other.refused);
        self.millis += other.millis;
    }
}

/// Why a change was not made.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Refusal {
    /// The faces around the two clusters overlap: the parts are too close along the surface.
    Overlapping,
    /// What would be removed is no disc (a join) or no annulus (a split), or reaches a
    /// boundary of the mesh.
    NotSimple,
    /// The new faces would have made an edge shared by three faces or a pinched vertex.
    NotManifold,
    /// The new faces would cross something.
    WouldIntersect,
    /// A split would cut off a part of fewer than [`MIN_SPLIT_FACES`] faces.
    TinyPart,
}

impl Refusal {
    /// The reason as the JSON reports name it.
    pub fn name(self) -> &'static str {
        match self {
            Refusal::Overlapping => "overlapping",
            Refusal::NotSimple => "not_simple",
            Refusal::NotManifold => "not_manifold",
            Refusal::WouldIntersect => "would_intersect",
            Refusal::TinyPart => "tiny_part",
        }
    }
}

/// Joins and splits fuse layers (`fuse[layer]`) where they touch themselves near `seeds` (the
/// vertices a stroke changed), keeping `grid` exact. See the module documentation.
pub fn adapt(
    mesh: &mut Mesh,
    grid: &mut SpatialHash,
    fuse: &[bool],
    seeds: &[u32],
    settings: &FuseSettings,
) -> TopologyReport {
    let started = Instant::now();
    let mut report = TopologyReport::default();
    let mut seeds = seeds.to_vec();
    let mut changes = 0;
    // Each round reads the contacts once and tries each pair of clusters in order, nearest
    // first; a pair near a change made this round waits for the next round, which reads the
    // contacts again around the changes only.
    for _ in 0..MAX_ROUNDS {
        let found = contacts_around(mesh, fuse, &seeds, settings);
        report.contacts += found.len();
        let mut changed_area = Aabb::EMPTY;
        for (side_a, side_b) in planned_changes(mesh, &found) {
            let near_a_change = |sides: &[u32]| {
                sides.iter().any(|&v| {
                    !mesh.is_vertex_live(v)
                        || changed_area.within(mesh.positions()[v as usize], settings.join_distance)
                })
            };
            if changes == MAX_CHANGES_PER_PASS
                || near_a_change(&side_a)
                || side_b.as_deref().is_some_and(near_a_change)
            {
                continue;
            }
            let outcome = match &side_b {
                Some(side_b) => join(mesh, grid, (&side_a, side_b), settings),
                None => split(mesh, grid, &side_a, settings),
            };
            match outcome {
                Ok(changed) => {
                    match side_b {
                        Some(_) => report.joins += 1,
                        None => report.splits += 1,
                    }
                    changes += 1;
                    changed_area = changed_area.including_box(&contacts::box_of(mesh, &changed));
                    report.changed.extend(changed);
                }
                Err(why) => report.refused.push(why),
            }
        }
        if changed_area.is_empty() {
            break;
        }
        seeds = report.changed.clone();
    }
    report.changed.sort_unstable();
    report.changed.dedup();
    report.millis = started.elapsed().as_secs_f64() * 1e3;
    report
}

/// The contacts of `seeds` (what a stroke moved) and of the vertices near the faces they
/// touch: a stroke that brings a part against a still one finds the moved side's contacts
/// from its own vertices, and the still side's from theirs.
fn contacts_around(
    mesh: &Mesh,
    fuse: &[bool],
    seeds: &[u32],
    settings: &FuseSettings,
) -> Vec<Contact> {
    let reach = (settings.join_distance, settings.exclusion_ring);
    let mut found = find_contacts(mesh, fuse, seeds, reach);
    let touched: Vec<u32> = found
        .iter()
        .flat_map(|c| mesh.faces()[c.face as usize])
        .collect();
    let mut others: Vec<u32> = regions::faces_around(mesh, &touched, 1)
        .iter()
        .flat_map(|&f| mesh.faces()[f as usize])
        .collect();
    others.sort_unstable();
    others.dedup();
    let mut sorted_seeds = seeds.to_vec();
    sorted_seeds.sort_unstable();
    others.retain(|v| sorted_seeds.binary_search(v).is_err());
    found.extend(find_contacts(mesh, fuse, &others, reach));
    found.sort_by(|a, b| {
        a.distance
            .total_cmp(&b.distance)
            .then(a.vertex.cmp(&b.vertex))
    });
    found
}

/// Per cluster of touching vertices, in order of its nearest contact: the cluster, and the
/// cluster of that contact's face when it is another one (`None`: the same cluster, a neck).
fn planned_changes(mesh: &Mesh, found: &[Contact]) -> Vec<(Vec<u32>, Option<Vec<u32>>)> {
    let mut members: Vec<u32> = found.iter().map(|c| c.vertex).collect();
    members.sort_unstable();
    let clusters = regions::clusters(mesh, &members);
    let mut cluster_of = std::collections::HashMap::new();
    for (i, cluster) in clusters.iter().enumerate() {
        for &v in cluster {
            cluster_of.insert(v, i);
        }
    }
    let mut planned = vec![false; clusters.len()];
    let mut changes = Vec::new();
    for contact in found {
        let a = cluster_of[&contact.vertex];
        if std::mem::replace(&mut planned[a], true) {
            continue;
        }
        let tri = mesh.faces()[contact.face as usize];
        let b = tri.iter().find_map(|v| cluster_of.get(v).copied());
        changes.push(match b {
            Some(b) if b == a => (clusters[a].clone(), None),
            Some(b) => {
                planned[b] = true;
                (clusters[a].clone(), Some(clusters[b].clone()))
            }
            // The face's side has no vertex within the join distance of this side (its
            // vertices are farther than its middle): that face is the other side.
            None => (clusters[a].clone(), Some(tri.to_vec())),
        });
    }
    changes
}

/// Bridges the holes left by removing the faces around `sides` (each, one ring more, must be
/// a disc, and the two apart) with a tube. Returns the vertices it changed.
fn join(
    mesh: &mut Mesh,
    grid: &mut SpatialHash,
    (side_a, side_b): (&[u32], &[u32]),
    settings: &FuseSettings,
) -> Result<Vec<u32>, Refusal> {
    let disc_a = regions::faces_around(mesh, side_a, 1);
    let disc_b = regions::faces_around(mesh, side_b, 1);
    // The tube's new edges must not exist already: no vertex of one disc may be a vertex
    // or a neighbour of the other's.
    let vertices_a: HashSet<u32> = disc_a
        .iter()
        .flat_map(|&f| mesh.faces()[f as usize])
        .collect();
    let vertices_b: HashSet<u32> = disc_b
        .iter()
        .flat_map(|&f| mesh.faces()[f as usize])
        .collect();
    if vertices_b.iter().any(|&v| {
        vertices_a.contains(&v) || mesh.neighbours(v).iter().any(|w| vertices_a.contains(w))
    }) {
        return Err(Refusal::Overlapping);
    }
    let hole = |disc: &[u32]| -> Result<Vec<u32>, Refusal> {
        match regions::hole_loops(mesh, disc) {
            Some(mut loops)
                if loops.len() == 1 && regions::euler_characteristic(mesh, disc) == 1 =>
            {
                Ok(loops.remove(0))
            }
            _ => Err(Refusal::NotSimple),
        }
    };
    let (hole_a, hole_b) = (hole(&disc_a)?, hole(&disc_b)?);
    let doomed: Vec<u32> = disc_a.iter().chain(&disc_b).copied().collect();
    replace(mesh, grid, &doomed, settings, |mesh| {
        sew::tube(mesh, &hole_a, &hole_b)
    })
}

/// Cuts a neck: removes the band of faces around `cluster` (one ring more; it must be an
/// annulus) and caps both holes. Returns the vertices it changed.
fn split(
    mesh: &mut Mesh,
    grid: &mut SpatialHash,
    cluster: &[u32],
    settings: &FuseSettings,
) -> Result<Vec<u32>, Refusal> {
    let band = regions::faces_around(mesh, cluster, 1);
    let holes = match regions::hole_loops(mesh, &band) {
        Some(loops) if loops.len() == 2 && regions::euler_characteristic(mesh, &band) == 0 => loops,
        _ => return Err(Refusal::NotSimple),
    };
    // A neck between a body and a crumb is no neck: both sides must be a body of their own.
    if holes
        .iter()
        .any(|hole| regions::faces_beyond(mesh, &band, hole, MIN_SPLIT_FACES) < MIN_SPLIT_FACES)
    {
        return Err(Refusal::TinyPart);
    }
    let layer = mesh.face_layers()[band[0] as usize];
    replace(mesh, grid, &band, settings, |mesh| {
        let mut faces = sew::cap(mesh, &holes[0], layer);
        faces.extend(sew::cap(mesh, &holes[1], layer));
        faces
    })
}

/// Removes `doomed`, sews in what `sew` makes (it may add vertices), remeshes around the new
/// faces and checks the result; undoes everything when a check fails.
fn replace(
    mesh: &mut Mesh,
    grid: &mut SpatialHash,
    doomed: &[u32],
    settings: &FuseSettings,
    sew: impl FnOnce(&mut Mesh) -> Vec<[u32; 3]>,
) -> Result<Vec<u32>, Refusal> {
    let layer: LayerId = mesh.face_layers()[doomed[0] as usize];
    let old_vertices: Vec<u32> = doomed
        .iter()
        .flat_map(|&f| mesh.faces()[f as usize])
        .collect();
    let reach = Aabb::of_points(
        &old_vertices
            .iter()
            .map(|&v| mesh.positions()[v as usize])
            .collect::<Vec<_>>(),
    )
    .expanded(4.0 * settings.edge);
    let snapshot = mesh.clone();
    let vertex_count_before = mesh.vertex_count() as u32;

    mesh.cut_out(doomed);
    let faces = sew(mesh);
    let first_new_face = mesh.face_count();
    let mut changed: Vec<u32> = old_vertices;
    changed.extend(vertex_count_before..mesh.vertex_count() as u32);
    let outcome = mesh
        .add_faces(&faces, layer)
        .map_err(|_| Refusal::NotManifold);
    let outcome = outcome.and_then(|()| {
        if !checks::sewn_shut(mesh, first_new_face) {
            return Err(Refusal::NotManifold);
        }
        sync_grid(grid, mesh, &changed);
        if checks::new_faces_cross(mesh, grid, first_new_face, 3.0 * settings.join_distance) {
            return Err(Refusal::WouldIntersect);
        }
        let seeds: Vec<u32> = changed
            .iter()
            .copied()
            .filter(|&v| mesh.is_vertex_live(v))
            .collect();
        mesh.recompute_normals_at(&seeds);
        let remesh = RemeshSettings {
            collision_distance: settings.collision_distance,
            exclusion_ring: settings.collision_ring,
            ..RemeshSettings::new(settings.edge)
        };
        let (_, remeshed) = remesh_region(mesh, grid, &seeds, &remesh);
        changed.extend(remeshed);
        changed.sort_unstable();
        changed.dedup();
        // Crossings the mesh had before are not this change's: counted there only when
        // there are any now (the engine keeps none, so the second count is rare).
        let reach = reach.including_box(&contacts::box_of(mesh, &changed));
        let crossings = find_intersections_in(mesh, &reach).total();
        if crossings > 0 && crossings > find_intersections_in(&snapshot, &reach).total() {
            return Err(Refusal::WouldIntersect);
        }
        Ok(())
    });
    match outcome {
        Ok(()) => Ok(changed),
        Err(why) => {
            *mesh = snapshot;
            changed.sort_unstable();
            changed.dedup();
            sync_grid(grid, mesh, &changed);
            Err(why)
        }
    }
}

/// Files `vertices` in `grid` as `mesh` has them now: live ones at their positions, the rest
/// (dead, or past the end of a mesh put back) out.
fn sync_grid(grid: &mut SpatialHash, mesh: &Mesh, vertices: &[u32]) {
    for &v in vertices {
        if grid.contains(v) {
            grid.remove(v);
        }
        if (v as usize) < mesh.vertex_count() && mesh.is_vertex_live(v) {
            grid.insert(v, mesh.positions()[v as usize]);
        }
    }
}
