//! A mirrored stroke's samples: each sample and its image across the stroke's plane are
//! selected and deformed separately, then moved together in every step — one union of the two
//! selections, one collision response — so each side collides with what the other did in the
//! same step. A vertex both dabs reach moves by the sum of their displacements, added in an order
//! that does not depend on the side (addition commutes), so a mirror-symmetric mesh stays
//! symmetric to the last bit through selection, frames and deformation.

use std::time::Instant;

use glam::Vec3;

use super::{Active, Opened, SamplesReport, refresh_normals};
use crate::brush::{BrushKind, Dab, DabFrame, Mirror, Sample};
use crate::mesh::Mesh;
use crate::pipeline::engine::millis;
use crate::pipeline::kernels::{FrameSource, StepKernels};
use crate::pipeline::step::{longest_move, steps_for};

/// Which of a mirrored sample's two dabs.
#[derive(Clone, Copy, PartialEq)]
enum Side {
    Drawn,
    Image,
}

impl Active {
    /// [`Active::run_sample`] for a mirrored stroke: the sample and its image across `mirror`,
    /// deformed in the same steps. Returns the vertices it moved.
    pub(super) fn run_mirrored_sample(
        &mut self,
        kernels: &mut dyn StepKernels,
        mesh: &mut Mesh,
        (sample, mirror): (&Sample, Mirror),
        call: &mut SamplesReport,
    ) -> Option<Vec<u32>> {
        let started = Instant::now();
        let probe = self.probe_at(sample, self.previous);
        self.previous = Some(sample.position);
        self.start_grab_sample(probe.frame.motion);
        let image = image_dab(&probe, &mirror);
        let image_normal = sample.normal.map(|n| mirror.direction_image(n));
        let drawn = self.open_side(kernels, mesh, (probe, sample.normal), Side::Drawn);
        let imaged = self.open_side(kernels, mesh, (image, image_normal), Side::Image);
        let deform_millis = drawn.1 + imaged.1;
        call.phases.selection += millis(started) - deform_millis;
        call.phases.deformation += deform_millis;
        let sides = [drawn.0, imaged.0];
        if sides.iter().all(|side| side.selection.is_empty()) {
            return None;
        }
        for side in &sides {
            self.paint_opened(mesh, side, call);
        }
        if !self.stroke.brush.kind.deforms() {
            return None;
        }
        let moved = self.deform_mirrored_in_steps(kernels, mesh, &sides, call);
        refresh_normals(kernels, mesh, &moved, &mut self.scratch.vertex_marks, call);
        Some(moved)
    }

    /// One side's selection, frame and whole move (a grab keeps what that side caught at the
    /// stroke's first sample), and the milliseconds its deformation took.
    fn open_side(
        &mut self,
        kernels: &mut dyn StepKernels,
        mesh: &Mesh,
        (probe, normal): (Dab, Option<Vec3>),
        side: Side,
    ) -> (Opened, f64) {
        let kind = self.stroke.brush.kind;
        let captured = match side {
            Side::Drawn => &self.captured,
            Side::Image => &self.captured_image,
        };
        let held = self.held_by_grab(mesh, captured.as_ref(), (&probe, normal));
        let deformed = held.unwrap_or_else(|| {
            let how = (FrameSource::Selection { normal }, kind.deforms());
            kernels.select_and_deform(&self.state(), mesh, &probe, how)
        });
        if kind == BrushKind::Grab {
            let slot = match side {
                Side::Drawn => &mut self.captured,
                Side::Image => &mut self.captured_image,
            };
            slot.get_or_insert_with(|| deformed.selection.clone());
        }
        let opened = Opened {
            probe,
            selection: deformed.selection,
            frame: deformed.frame,
            targets: deformed.targets,
        };
        (opened, deformed.deform_millis)
    }

    /// Splits the two sides' summed motion into steps of at most `max_step` edge lengths; each
    /// step deforms both sides on their first selections by a share of their moves (as a grab
    /// does) and moves the union at once. Returns the vertices moved.
    fn deform_mirrored_in_steps(
        &mut self,
        kernels: &mut dyn StepKernels,
        mesh: &mut Mesh,
        sides: &[Opened; 2],
        call: &mut SamplesReport,
    ) -> Vec<u32> {
        let started = Instant::now();
        let whole = sides.each_ref().map(|side| Dab {
            frame: side.frame,
            ..side.probe
        });
        let state = self.state();
        let full: Vec<Vec<Vec3>> = sides
            .iter()
            .zip(&whole)
            .map(|(side, dab)| match &side.targets {
                Some(targets) => targets.clone(),
                None if side.selection.is_empty() => Vec::new(),
                None => kernels.deform(&state, mesh, dab, &side.selection, None),
            })
            .collect();
        let (selection, first_targets) = union_of_moves(mesh, sides, &full);
        let split = steps_for(
            longest_move(mesh, &selection, &first_targets),
            self.lengths.step_limit,
        );
        let steps = split.steps;
        call.capped_samples += usize::from(split.capped);
        call.phases.deformation += millis(started);
        let mut moved = Vec::new();
        let mut first_targets = Some(first_targets);
        for _ in 0..steps {
            let targets = match first_targets.take().filter(|_| steps == 1) {
                Some(targets) => targets,
                None => {
                    let started = Instant::now();
                    let state = self.state();
                    let share = split.share;
                    let shares: Vec<Vec<Vec3>> = sides
                        .iter()
                        .zip(&whole)
                        .map(|(side, dab)| {
                            let dab = Dab { share, ..*dab };
                            if side.selection.is_empty() {
                                Vec::new()
                            } else {
                                kernels.deform(&state, mesh, &dab, &side.selection, None)
                            }
                        })
                        .collect();
                    call.phases.deformation += millis(started);
                    union_of_moves(mesh, sides, &shares).1
                }
            };
            moved.extend(self.take_step(kernels, mesh, (&selection, &targets), call));
            if self.stopped_stretched.is_some() {
                break;
            }
        }
        moved
    }
}

/// The image of a dab across `mirror`: its centre, plane point, normal and motion mirrored;
/// a twist turns the other way (a reflection reverses the sense of a turn).
pub(super) fn image_dab(dab: &Dab, mirror: &Mirror) -> Dab {
    let frame = dab.frame;
    let mut brush = dab.brush;
    if brush.kind == BrushKind::Twist {
        brush.invert = !brush.invert;
    }
    Dab {
        brush,
        frame: DabFrame {
            center: mirror.point_image(frame.center),
            normal: mirror.direction_image(frame.normal),
            plane_point: mirror.point_image(frame.plane_point),
            motion: mirror.direction_image(frame.motion),
        },
        ..*dab
    }
}

/// The union of the two sides' selections (ascending, the larger weight where both reach a
/// vertex) and each vertex's target: its position moved by the sum of both sides'
/// displacements (`targets[i]` pairs with side `i`'s selection).
fn union_of_moves(
    mesh: &Mesh,
    sides: &[Opened; 2],
    targets: &[Vec<Vec3>],
) -> (Vec<(u32, f32)>, Vec<Vec3>) {
    let positions = mesh.positions();
    let displacement = |side: usize, i: usize| -> Vec3 {
        let v = sides[side].selection[i].0 as usize;
        targets[side][i] - positions[v]
    };
    let (a, b) = (&sides[0].selection, &sides[1].selection);
    let (mut i, mut j) = (0, 0);
    let mut selection = Vec::with_capacity(a.len() + b.len());
    let mut moved_to = Vec::with_capacity(a.len() + b.len());
    while i < a.len() || j < b.len() {
        let take_a = j == b.len() || (i < a.len() && a[i].0 <= b[j].0);
        let take_b = i == a.len() || (j < b.len() && b[j].0 <= a[i].0);
        if take_a && take_b {
            let v = a[i].0;
            // Commutative: the vertex's mirror image adds the same two terms the other way.
            let sum = displacement(0, i) + displacement(1, j);
            selection.push((v, a[i].1.max(b[j].1)));
            moved_to.push(positions[v as usize] + sum);
            i += 1;
            j += 1;
        } else if take_a {
            selection.push(a[i]);
            moved_to.push(targets[0][i]);
            i += 1;
        } else {
            selection.push(b[j]);
            moved_to.push(targets[1][j]);
            j += 1;
        }
    }
    (selection, moved_to)
}
