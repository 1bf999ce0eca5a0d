//! Offset duplication (sLayer, "Editing Tools"): the selected part of a layer copied into a
//! new layer lifted along the normals — a flake of paint above the plaster, a second skin of
//! bark — optionally thickened into a closed shell.
//!
//! The copy collides like a brush. Each of its vertices walks from where it was copied along
//! its normal in steps of `d/4` and stops before the first step that comes within the
//! collision distance `d` of another layer (a step that short cannot jump through a face: the
//! distance changes by at most the step), or within a step of a face of its own layer that is
//! nearer to it than to where it started (a groove's other wall, not the surface it left). Then the whole copy is checked exactly: every
//! vertex at least `d` from the mesh, no face crossing a face of the mesh or of the copy.
//! Only a copy that passes is added; one that cannot be placed is refused with the vertex and
//! layer in the way.

use std::time::Instant;

use glam::Vec3;
use rayon::prelude::*;

use super::obstacles::{Obstacles, Passing};
use super::select::{Selection, selected_faces};
use super::shell::thicken;
use super::{ToolError, check_length};
use crate::collide::find_intersections;
use crate::geom::Aabb;
use crate::mesh::{Brdf, LayerId, Mesh};
use crate::remesh::{RemeshSettings, remesh_piece};

/// The final check's allowance on `d` for rounding.
const CLEARANCE_SLACK: f32 = 1e-3;

/// How to duplicate.
#[derive(Debug, Clone, PartialEq)]
pub struct DuplicateSettings {
    /// How far the copy is lifted along the normals (world units).
    pub offset: f32,
    /// A closed shell this thick, from the offset outward, instead of a sheet.
    pub thickness: Option<f32>,
    /// The new layer's name.
    pub name: String,
    /// The new layer's material.
    pub material: Brdf,
    /// The mesh's edge length `L`: the copy is remeshed to it.
    pub edge: f32,
    /// Nothing of the copy comes closer than this to the mesh.
    pub collision_distance: f32,
    /// Remesh the copy to `edge` (lifting stretches it on convex parts).
    pub remesh: bool,
}

impl DuplicateSettings {
    /// Lifted by 2·L (above the collision distance `d` = L), a sheet, remeshed.
    pub fn for_mesh(mesh: &Mesh, name: &str, material: Brdf) -> DuplicateSettings {
        let edge = mesh.mean_edge_length();
        DuplicateSettings {
            offset: 2.0 * edge,
            thickness: None,
            name: name.to_string(),
            material,
            edge,
            collision_distance: edge,
            remesh: true,
        }
    }
}

/// What a duplication made.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct DuplicateReport {
    /// The new layer.
    pub layer: LayerId,
    pub faces: usize,
    pub vertices: usize,
    /// Vertices stopped short of the offset by something in the way.
    pub clamped: usize,
    /// The shortest lift of a vertex of the sheet (the offset unless clamped).
    pub smallest_lift: f32,
    /// Whether the remeshed copy was kept (the copy as lifted is kept where remeshing it
    /// brought it within `d` of the mesh).
    pub remeshed: bool,
    pub millis: f64,
}

/// Duplicates `selection` of `mesh` into a new layer after the last; on an error the mesh is
/// unchanged.
pub fn duplicate(
    mesh: &mut Mesh,
    selection: Selection,
    settings: &DuplicateSettings,
) -> Result<DuplicateReport, ToolError> {
    let started = Instant::now();
    let (piece, mut report) = plan_duplicate(mesh, selection, settings)?;
    report.layer = mesh.append(&piece);
    report.millis = started.elapsed().as_secs_f64() * 1e3;
    Ok(report)
}

/// The copy [`duplicate`] would add, as a one-layer mesh, checked against `mesh`; the
/// report's `layer` is the one it would become.
pub fn plan_duplicate(
    mesh: &Mesh,
    selection: Selection,
    settings: &DuplicateSettings,
) -> Result<(Mesh, DuplicateReport), ToolError> {
    check_settings(mesh, settings)?;
    let faces = selected_faces(mesh, selection)?;
    let source = mesh.face_layers()[faces[0] as usize];
    let (piece, _) = mesh.extract_faces(&faces, &settings.name)?;
    lift_off(mesh, piece, source, settings)
}

/// Lifts `piece` (lying on `source`'s surface, facing as it does) off it along the normals
/// by the offset, as far as nothing is in the way, then finishes it: thickened if asked,
/// remeshed, painted and checked exactly against `mesh`. The report's `layer` is the one it
/// would become.
pub(super) fn lift_off(
    mesh: &Mesh,
    mut piece: Mesh,
    source: LayerId,
    settings: &DuplicateSettings,
) -> Result<(Mesh, DuplicateReport), ToolError> {
    let d = settings.collision_distance;
    let total = settings.offset + settings.thickness.unwrap_or(0.0);
    let piece_box = piece
        .bounds()
        .map_or(Aabb::EMPTY, |(a, b)| Aabb::of_points(&[a, b]));
    let obstacles = Obstacles::near(
        mesh,
        piece_box.expanded(total + d + settings.edge),
        1.5 * settings.edge,
    );
    let lifts = lift_all(&piece, &obstacles, source, (total, d));
    let thickness = settings.thickness.unwrap_or(0.0);
    let smallest_lift = lifts.iter().map(|l| l.0).fold(f32::INFINITY, f32::min) - thickness;
    if let Some((v, &(lift, layer))) = lifts
        .iter()
        .enumerate()
        .find(|(_, (lift, _))| lift - thickness < d)
    {
        return Err(ToolError::NoRoom {
            vertex: v as u32,
            layer,
            reached: lift,
            needed: d + thickness,
        });
    }
    let clamped = lifts.iter().filter(|l| l.0 < total).count();
    let normals = piece.normals().to_vec();
    for ((p, n), (lift, _)) in piece.positions_mut().iter_mut().zip(&normals).zip(&lifts) {
        *p += *n * (lift - thickness);
    }
    piece.recompute_normals();
    let (piece, remeshed) = finish(piece, settings, &obstacles)?;
    let report = DuplicateReport {
        layer: mesh.layer_count() as LayerId,
        faces: piece.live_face_count(),
        vertices: piece.live_vertex_count(),
        clamped,
        smallest_lift,
        remeshed,
        millis: 0.0,
    };
    Ok((piece, report))
}

pub(super) fn check_settings(mesh: &Mesh, settings: &DuplicateSettings) -> Result<(), ToolError> {
    let extent = mesh.extent().unwrap_or(0.0);
    check_length("the offset", settings.offset, extent)?;
    if let Some(thickness) = settings.thickness {
        check_length("the thickness", thickness, extent)?;
    }
    check_length("the edge length", settings.edge, extent)?;
    check_length(
        "the collision distance",
        settings.collision_distance,
        extent,
    )
}

/// How far each vertex of `piece` can be lifted along its normal, up to `total`, and the
/// layer that stopped it (its own source layer where nothing did).
///
/// The walk goes in steps of `d/4` and stops before the first step that comes within `d` of
/// another layer, or within a step of its own layer's surface ahead (a groove's far wall).
fn lift_all(
    piece: &Mesh,
    obstacles: &Obstacles,
    source: LayerId,
    (total, d): (f32, f32),
) -> Vec<(f32, LayerId)> {
    let walk = Walk {
        step: d / 4.0,
        steps: (total / (d / 4.0)).ceil() as usize,
        total,
        d,
        source,
    };
    (0..piece.vertex_count())
        .into_par_iter()
        .map_init(Vec::new, |passing, v| {
            walk.lift(
                obstacles,
                (piece.positions()[v], piece.normals()[v]),
                passing,
            )
        })
        .collect()
}

/// One vertex's walk off its surface ([`lift_all`]).
struct Walk {
    step: f32,
    steps: usize,
    total: f32,
    d: f32,
    source: LayerId,
}

impl Walk {
    fn at(&self, k: usize) -> f32 {
        (k as f32 * self.step).min(self.total)
    }

    /// The lift from `start` along `normal`, and what stopped it.
    fn lift(
        &self,
        obstacles: &Obstacles,
        (start, normal): (Vec3, Vec3),
        passing: &mut Vec<Passing>,
    ) -> (f32, LayerId) {
        let source = self.source;
        let reach = |layer| if layer == source { self.step } else { self.d };
        let span = (self.at(1), self.total);
        obstacles.passing((start, normal), span, (reach, self.d), passing);
        // Each face is tried only at the steps within its reach, up to the first step found
        // so far that stops the walk: that step, over all faces, is where the walk stops.
        let mut stop = self.steps + 1;
        for near in passing.iter() {
            let first = ((near.from / self.step).floor() as usize).max(1);
            let last = ((near.to / self.step).ceil() as usize).min(stop - 1);
            for k in first..=last {
                let p = start + normal * self.at(k);
                let stops = if near.layer == source {
                    obstacles.ahead(near.face, p, start, self.step)
                } else {
                    obstacles.distance_within(near.face, p, self.d).is_some()
                };
                if stops {
                    stop = k;
                    break;
                }
            }
        }
        if stop > self.steps {
            return (self.at(self.steps), source);
        }
        let lift = if stop == 1 { 0.0 } else { self.at(stop - 1) };
        let p = start + normal * self.at(stop);
        let other = obstacles.nearest_passing(passing, (p, self.d), |l| l != source);
        (lift, other.map_or(source, |(layer, _)| layer))
    }
}

/// The lifted sheet thickened if asked, remeshed (where that keeps it clear), painted, and
/// checked exactly against the mesh and itself.
fn finish(
    sheet: Mesh,
    settings: &DuplicateSettings,
    obstacles: &Obstacles,
) -> Result<(Mesh, bool), ToolError> {
    let mut piece = match settings.thickness {
        Some(thickness) => thicken(&sheet, thickness, settings.edge)?,
        None => sheet,
    };
    piece.set_layer_brdf(0, settings.material);
    if settings.remesh {
        let mut remeshed = piece.clone();
        let mut remesh = RemeshSettings::new(settings.edge);
        remesh.collision_distance = settings.collision_distance;
        // Where lifting (or thickening) left edges out of band: the rest of the copy is its
        // source's, already at `L`.
        if remesh_piece(&mut remeshed, &remesh).is_ok() {
            remeshed.compact();
            if check_clear(&remeshed, obstacles, settings.collision_distance).is_ok() {
                return Ok((remeshed, true));
            }
        }
    }
    check_clear(&piece, obstacles, settings.collision_distance)?;
    Ok((piece, false))
}

/// Every vertex of `piece` at least `d` (less rounding) from the obstacles, and no face of it
/// crossing one of theirs or another of its own.
fn check_clear(piece: &Mesh, obstacles: &Obstacles, d: f32) -> Result<(), ToolError> {
    let reach = d * (1.0 - CLEARANCE_SLACK);
    let blocked = (0..piece.vertex_count())
        .into_par_iter()
        .find_map_first(|v| {
            obstacles
                .nearest_within(piece.positions()[v], reach, |_| true)
                .map(|(layer, gap)| (v, layer, gap))
        });
    if let Some((vertex, layer, gap)) = blocked {
        return Err(ToolError::TooClose {
            vertex: vertex as u32,
            layer,
            gap,
            distance: d,
        });
    }
    let triangles: Vec<[Vec3; 3]> = (0..piece.face_count())
        .map(|f| piece.face_positions(f))
        .collect();
    let with_mesh = obstacles.intersecting_pairs(&triangles);
    let within_copy = find_intersections(piece).total();
    if with_mesh + within_copy > 0 {
        return Err(ToolError::WouldIntersect {
            with_mesh,
            within_copy,
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{SceneKind, SceneSpec, generate};

    /// The walk as first written: every step asks the grid for the nearest face of another
    /// layer and tries every face of its own.
    fn lift_step_by_step(
        obstacles: &Obstacles,
        (start, normal): (Vec3, Vec3),
        source: LayerId,
        (total, d): (f32, f32),
    ) -> (f32, LayerId) {
        let step = d / 4.0;
        let mut lift = (0.0, source);
        for k in 1..=(total / step).ceil() as usize {
            let t = (k as f32 * step).min(total);
            let p = start + normal * t;
            if let Some((layer, _)) = obstacles.nearest_within(p, d, |l| l != source) {
                return (lift.0, layer);
            }
            let mut own = (0..obstacles.len() as u32).filter(|&i| obstacles.layer(i) == source);
            if own.any(|i| obstacles.ahead(i, p, start, step)) {
                return lift;
            }
            lift.0 = t;
        }
        lift
    }

    /// Each material's layers lifted far enough that many walks stop on another layer or on
    /// the far wall of a groove: every lift and every stopper as step by step.
    #[test]
    fn each_walk_stops_where_a_step_by_step_walk_does() {
        let (mut by_other, mut by_own) = (0, 0);
        for kind in [SceneKind::Plaster, SceneKind::Bark, SceneKind::Metal] {
            let spec = SceneSpec {
                kind,
                triangles: 5_000,
                seed: 3,
            };
            let mesh = generate(&spec).unwrap();
            let edge = mesh.mean_edge_length();
            let (lo, hi) = mesh.bounds().unwrap();
            let region = Aabb::of_points(&[lo, hi]).expanded(edge);
            let obstacles = Obstacles::near(&mesh, region, 1.5 * edge);
            for source in 0..mesh.layer_count() as LayerId {
                let layer: Vec<u32> = (0..mesh.face_count() as u32)
                    .filter(|&f| mesh.face_layers()[f as usize] == source)
                    .collect();
                let (piece, _) = mesh.extract_faces(&layer, "piece").unwrap();
                let reach = (6.0 * edge, edge);
                let lifts = lift_all(&piece, &obstacles, source, reach);
                for (v, &(lift, stopper)) in lifts.iter().enumerate() {
                    let walk = (piece.positions()[v], piece.normals()[v]);
                    let expected = lift_step_by_step(&obstacles, walk, source, reach);
                    assert_eq!(
                        (lift, stopper),
                        expected,
                        "{kind:?}, layer {source}, vertex {v}"
                    );
                    by_other += usize::from(stopper != source);
                    by_own += usize::from(stopper == source && lift < reach.0);
                }
            }
        }
        let stops = format!("{by_other} stopped by another layer, {by_own} by their own");
        assert!(by_other > 1000 && by_own > 50, "{stops}");
    }
}
