//! Seeded stroke scripts (docs/bench.md): strokes that push, drag, inflate, smooth and flatten
//! the upper layers of a layered scene, many of them pressing into the layers below. Samples are
//! placed on the surface by picking through the grid, so the script replays anywhere.

use glam::{Vec2, Vec3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::brush::{BrushKind, Falloff, LayerRef, SampleSpec, StrokeFile, StrokeSpec};
use crate::geom::Ray;
use crate::grid::SpatialHash;
use crate::mesh::Mesh;
use crate::scene::SceneKind;

/// Which brushes a script uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BrushMix {
    /// The benchmark's mix: draw and push-down, grab, inflate, smooth, flatten.
    Bench,
    /// Every brush, pushed harder: for the no-interpenetration property tests.
    Torture,
    /// Straight draw strokes across the sheet, 50 samples each, radius 5 % of its width,
    /// strength 0.5, on rows spread over it: an artist's plain stroke (the plane scene).
    StraightDraw,
    /// Inflate, deflate and grab strokes (the sphere scene).
    InflateGrab,
}

impl BrushMix {
    /// The strokes `slayer bench` runs on a scene.
    pub fn for_scene(kind: SceneKind) -> BrushMix {
        match kind {
            SceneKind::Plane => BrushMix::StraightDraw,
            SceneKind::Sphere => BrushMix::InflateGrab,
            SceneKind::Plaster | SceneKind::Bark | SceneKind::Metal => BrushMix::Bench,
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScriptSpec {
    pub strokes: usize,
    pub seed: u64,
    /// Brush radius in mean edge lengths (docs/bench.md: 12).
    pub radius_edges: f32,
    /// Sample spacing as a share of the radius (docs/bench.md: 1/4).
    pub spacing: f32,
    /// Samples per stroke.
    pub samples: usize,
    pub mix: BrushMix,
}

impl Default for ScriptSpec {
    fn default() -> Self {
        ScriptSpec {
            strokes: 40,
            seed: 1,
            radius_edges: 12.0,
            spacing: 0.25,
            samples: 32,
            mix: BrushMix::Bench,
        }
    }
}

/// Picks the topmost surface point under `(x, y)`.
struct Surface<'a> {
    mesh: &'a Mesh,
    grid: SpatialHash,
    vertex_faces: crate::mesh::VertexFaces,
    top: f32,
    max_edge: f32,
}

impl<'a> Surface<'a> {
    fn new(mesh: &'a Mesh) -> Option<Surface<'a>> {
        let stats = mesh.edge_length_stats();
        let grid = SpatialHash::build(mesh, stats.mean as f32).ok()?;
        let (_, hi) = mesh.bounds()?;
        Some(Surface {
            mesh,
            grid,
            vertex_faces: mesh.vertex_faces(),
            top: hi.z + 1.0,
            max_edge: stats.max as f32,
        })
    }

    /// Point and upward normal of the first face hit looking down at `(x, y)`.
    fn under(&self, xy: Vec2) -> Option<(Vec3, Vec3)> {
        let ray = Ray {
            origin: xy.extend(self.top),
            direction: -Vec3::Z,
        };
        let hit = self.grid.first_hit(
            self.mesh.positions(),
            self.mesh.faces(),
            &self.vertex_faces,
            &ray,
            self.max_edge,
        )?;
        let n = self.mesh.face_normal(hit.face as usize);
        Some((hit.point, if n.z < 0.0 { -n } else { n }))
    }
}

/// A stroke script for `mesh`.
pub fn generate_script(mesh: &Mesh, spec: &ScriptSpec) -> StrokeFile {
    let mut rng = ChaCha8Rng::seed_from_u64(spec.seed);
    let Some(surface) = Surface::new(mesh) else {
        return StrokeFile {
            version: 1,
            strokes: Vec::new(),
            fuse: Vec::new(),
        };
    };
    if spec.mix == BrushMix::StraightDraw {
        return straight_draws(mesh, &surface, spec.strokes);
    }
    let (lo, hi) = mesh.bounds().unwrap_or((Vec3::ZERO, Vec3::ONE));
    let edge = mesh.mean_edge_length();
    let radius = spec.radius_edges * edge;
    let step = spec.spacing * radius;
    let layers = mesh.layer_count() as u32;
    let mut strokes = Vec::with_capacity(spec.strokes);
    while strokes.len() < spec.strokes {
        let (brush, invert, strength) = pick_brush(&mut rng, spec.mix);
        // Active layers: the upper ones, pressed into the base; sometimes only the top one,
        // sometimes all of them.
        let lowest_upper = layers.saturating_sub(2).max(1).min(layers - 1);
        let active: Vec<u32> = match rng.random_range(0..10) {
            0..=5 => (lowest_upper..layers).collect(),
            6..=7 => vec![layers - 1],
            _ => (0..layers).collect(),
        };
        let samples = if brush == BrushKind::Grab {
            (spec.samples / 4).max(2)
        } else {
            spec.samples
        };
        let length = step * (samples - 1) as f32;
        let margin = Vec2::splat(radius + 0.5 * length.min((hi - lo).truncate().min_element()));
        let span = ((hi - lo).truncate() - 2.0 * margin).max(Vec2::ZERO);
        let start = lo.truncate() + margin + span * Vec2::new(rng.random(), rng.random());
        let angle = rng.random_range(0.0..std::f32::consts::TAU);
        let direction = Vec2::new(angle.cos(), angle.sin());
        let start = start - direction * 0.5 * length;
        let mut points = Vec::with_capacity(samples);
        let mut last: Option<(Vec3, Vec3)> = None;
        for k in 0..samples {
            let xy = start + direction * (step * k as f32);
            let Some((point, normal)) = surface.under(xy).or(last) else {
                continue;
            };
            last = Some((point, normal));
            // Grab presses down as it drags: up to four edge lengths over the stroke.
            let sink = if brush == BrushKind::Grab {
                -Vec3::Z * (4.0 * edge * k as f32 / (samples - 1).max(1) as f32)
            } else {
                Vec3::ZERO
            };
            let pressure = 0.6 + 0.4 * (std::f32::consts::PI * k as f32 / samples as f32).sin();
            points.push(SampleSpec {
                position: (point + sink).to_array(),
                pressure,
                normal: Some(normal.to_array()),
            });
        }
        if points.is_empty() {
            continue;
        }
        strokes.push(StrokeSpec {
            brush,
            radius,
            strength,
            falloff: Falloff::blend(3),
            invert,
            layers: active.into_iter().map(LayerRef::Index).collect(),
            paint: None,
            spacing: spec.spacing,
            symmetry: None,
            samples: points,
        });
    }
    StrokeFile {
        version: 1,
        strokes,
        fuse: Vec::new(),
    }
}

/// [`BrushMix::StraightDraw`]: strokes along x from 10 % to 90 % of the sheet's width, on
/// seven rows from 10 % to 90 % of its depth (a later stroke goes over an earlier row again).
fn straight_draws(mesh: &Mesh, surface: &Surface<'_>, count: usize) -> StrokeFile {
    const SAMPLES: usize = 50;
    const ROWS: usize = 7;
    let (lo, hi) = mesh.bounds().unwrap_or((Vec3::ZERO, Vec3::ONE));
    let size = (hi - lo).truncate();
    let layers = (0..mesh.layer_count() as u32)
        .map(LayerRef::Index)
        .collect::<Vec<_>>();
    let strokes = (0..count)
        .map(|i| {
            let row = (i % ROWS) as f32 / (ROWS - 1) as f32;
            let samples = (0..SAMPLES)
                .filter_map(|k| {
                    let across = k as f32 / (SAMPLES - 1) as f32;
                    let xy = lo.truncate() + size * Vec2::new(0.1 + 0.8 * across, 0.1 + 0.8 * row);
                    let (point, _) = surface.under(xy)?;
                    Some(SampleSpec {
                        position: point.to_array(),
                        pressure: 1.0,
                        normal: None,
                    })
                })
                .collect();
            StrokeSpec {
                brush: BrushKind::Draw,
                radius: 0.05 * size.x,
                strength: 0.5,
                falloff: Falloff::blend(3),
                invert: false,
                layers: layers.clone(),
                paint: None,
                spacing: 0.25,
                symmetry: None,
                samples,
            }
        })
        .filter(|stroke| !stroke.samples.is_empty())
        .collect();
    StrokeFile {
        version: 1,
        strokes,
        fuse: Vec::new(),
    }
}

/// The torture mix's brushes: the nine it was tuned with (those before Freestyle's in
/// [`BrushKind::ALL`]), so that its scripts, and every torture suite's strokes, stay what they
/// were when Freestyle's brushes came. Random sweeps across stacked layers made the remeshing
/// torture test about twice as slow (140 s against 61–72 s); `tests/sweep.rs` and the deform
/// parity tests cover sweep, sweep-volume and trim.
const TORTURE_BRUSHES: &[BrushKind] = BrushKind::ALL.split_at(9).0;

fn pick_brush(rng: &mut ChaCha8Rng, mix: BrushMix) -> (BrushKind, bool, f32) {
    match mix {
        BrushMix::StraightDraw => (BrushKind::Draw, false, 0.5),
        BrushMix::InflateGrab => match rng.random_range(0..4) {
            0..=1 => (BrushKind::Inflate, rng.random(), rng.random_range(0.2..0.5)),
            _ => (BrushKind::Grab, false, 1.0),
        },
        BrushMix::Bench => match rng.random_range(0..20) {
            0..=6 => (BrushKind::Draw, true, rng.random_range(0.3..0.6)),
            7..=8 => (BrushKind::Draw, false, rng.random_range(0.2..0.4)),
            9..=12 => (BrushKind::Grab, false, 1.0),
            13..=14 => (BrushKind::Inflate, rng.random(), rng.random_range(0.2..0.4)),
            15..=17 => (BrushKind::Smooth, false, rng.random_range(0.3..0.7)),
            _ => (BrushKind::Flatten, false, rng.random_range(0.3..0.7)),
        },
        BrushMix::Torture => {
            let kind = TORTURE_BRUSHES[rng.random_range(0..TORTURE_BRUSHES.len())];
            let invert = kind == BrushKind::Draw || rng.random_bool(0.3);
            (kind, invert, rng.random_range(0.5..1.0))
        }
    }
}
