//! Deterministic generated scenes (docs/bench.md): a flat `plane`, a closed `sphere`, and the
//! layered materials of the sLayer paper — `plaster` (3 layers), `bark` (4) and `metal` (3).
//!
//! Sheets sit on a unit square; upper layers float a few mean edge lengths above the layer below
//! (the gap scales with the edge length, so strokes that press layers together collide at any
//! size), upper layers have holes and disconnected patches, and the same name, size and seed
//! always give the same mesh, bit for bit.

mod jitter;
mod noise;
pub mod shapes;
mod sheet;
mod sphere;

pub use jitter::{MAX_JITTER, jitter};
pub use noise::WaveNoise;
pub use sheet::{Lattice, SheetLayer, build_sheets, kept_face_count, kept_faces};
pub use sphere::{frequency_for, geodesic_sphere};

use std::fmt;
use std::str::FromStr;

use glam::Vec2;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use thiserror::Error;

use crate::material;
use crate::mesh::{Mesh, MeshError};

/// Vertical gap between stacked layers, in lattice edge lengths.
pub const LAYER_GAP_EDGES: f32 = 3.0;
/// Patches smaller than this share of the faces (at least 6, at most 40 faces) are dropped:
/// crumbs a few triangles wide are noise, not material.
fn min_patch_faces(triangles: usize) -> usize {
    (triangles / 1000).clamp(6, 40)
}
/// Accepted range of `--triangles`.
pub const MIN_TRIANGLES: usize = 100;
pub const MAX_TRIANGLES: usize = 64_000_000;

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SceneKind {
    Plane,
    Sphere,
    Plaster,
    Bark,
    Metal,
}

impl SceneKind {
    pub const ALL: [SceneKind; 5] = [
        SceneKind::Plane,
        SceneKind::Sphere,
        SceneKind::Plaster,
        SceneKind::Bark,
        SceneKind::Metal,
    ];

    pub fn name(self) -> &'static str {
        match self {
            SceneKind::Plane => "plane",
            SceneKind::Sphere => "sphere",
            SceneKind::Plaster => "plaster",
            SceneKind::Bark => "bark",
            SceneKind::Metal => "metal",
        }
    }

    /// The size the paper's Table 1 used for the materials; 100K for the test shapes.
    pub fn default_triangles(self) -> usize {
        match self {
            SceneKind::Plane | SceneKind::Sphere => 100_000,
            SceneKind::Plaster => 640_000,
            SceneKind::Bark => 981_000,
            SceneKind::Metal => 525_000,
        }
    }
}

impl fmt::Display for SceneKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for SceneKind {
    type Err = SceneError;

    fn from_str(s: &str) -> Result<Self, SceneError> {
        SceneKind::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| SceneError::UnknownScene(s.to_string()))
    }
}

#[derive(Debug, Error)]
pub enum SceneError {
    #[error("unknown scene `{0}` (expected one of: plane, sphere, plaster, bark, metal)")]
    UnknownScene(String),
    #[error("--triangles {0} is out of range ({MIN_TRIANGLES} to {MAX_TRIANGLES})")]
    TriangleCount(usize),
    #[error("generated mesh is invalid: {0}")]
    Mesh(#[from] MeshError),
}

/// What to generate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SceneSpec {
    pub kind: SceneKind,
    pub triangles: usize,
    pub seed: u64,
}

impl SceneSpec {
    pub fn new(kind: SceneKind) -> Self {
        SceneSpec {
            kind,
            triangles: kind.default_triangles(),
            seed: 1,
        }
    }
}

/// Generates a scene.
pub fn generate(spec: &SceneSpec) -> Result<Mesh, SceneError> {
    if !(MIN_TRIANGLES..=MAX_TRIANGLES).contains(&spec.triangles) {
        return Err(SceneError::TriangleCount(spec.triangles));
    }
    let mut rng = ChaCha8Rng::seed_from_u64(spec.seed);
    match spec.kind {
        SceneKind::Sphere => Ok(geodesic_sphere(frequency_for(spec.triangles), 0.5)?),
        SceneKind::Plane => sheet_scene(spec.triangles, |_| {
            vec![SheetLayer {
                name: "plane".into(),
                brdf: material::CLAY.brdf,
                height: Box::new(|_| 0.0),
                keep: Box::new(|_| true),
            }]
        }),
        SceneKind::Plaster => {
            let recipe = PlasterRecipe::new(&mut rng);
            sheet_scene(spec.triangles, |edge| recipe.layers(edge))
        }
        SceneKind::Bark => {
            let recipe = BarkRecipe::new(&mut rng);
            sheet_scene(spec.triangles, |edge| recipe.layers(edge))
        }
        SceneKind::Metal => {
            let recipe = MetalRecipe::new(&mut rng);
            sheet_scene(spec.triangles, |edge| recipe.layers(edge))
        }
    }
}

/// Finds the lattice edge at which the layers' masks keep `triangles` faces in all, then builds.
fn sheet_scene<'a>(
    triangles: usize,
    layers_at: impl Fn(f32) -> Vec<SheetLayer<'a>>,
) -> Result<Mesh, SceneError> {
    let size = Vec2::ONE;
    let faces_at = |edge: f32| {
        let layers = layers_at(edge);
        let masks: Vec<&(dyn Fn(Vec2) -> bool + Sync)> = layers.iter().map(|l| &*l.keep).collect();
        kept_face_count(&Lattice::covering(size, edge), &masks)
    };
    // A full layer of equilateral triangles with edge e has 2 / (√3 e²) faces per unit area.
    let full_layer_edge = |faces: f64| (2.0 / (3f64.sqrt() * faces)).sqrt() as f32;
    let layer_count = layers_at(1.0).len() as f64;
    let mut edge = full_layer_edge(triangles as f64 / layer_count);
    // Masks alone first (cheap), then with the cleanup, which drops small patches and matters
    // at small sizes.
    for _ in 0..8 {
        let ratio = faces_at(edge).max(1) as f64 / triangles as f64;
        if (ratio - 1.0).abs() < 0.004 {
            break;
        }
        edge *= ratio.sqrt() as f32;
    }
    let mut lattice = Lattice::covering(size, edge);
    let mut kept = kept_faces(&lattice, &layers_at(edge), min_patch_faces(triangles));
    for _ in 0..4 {
        let count: usize = kept.iter().map(Vec::len).sum();
        let ratio = count.max(1) as f64 / triangles as f64;
        if (ratio - 1.0).abs() < 0.015 {
            break;
        }
        edge *= ratio.sqrt() as f32;
        lattice = Lattice::covering(size, edge);
        kept = kept_faces(&lattice, &layers_at(edge), min_patch_faces(triangles));
    }
    Ok(build_sheets(&lattice, &layers_at(edge), &kept)?)
}

/// Smooth ramp from 0 at `x ≤ a` to 1 at `x ≥ b`.
fn ramp(x: f32, a: f32, b: f32) -> f32 {
    ((x - a) / (b - a)).clamp(0.0, 1.0)
}

/// How far a flake's rim curls up: 0 inside, rising toward the rim where `inside` meets 0.
fn curl(inside: f32) -> f32 {
    let t = 1.0 - ramp(inside, 0.0, 1.0);
    t * t
}

/// Peeling plaster: a wavy base, a paint coat with holes, and peeling paint flakes above it.
struct PlasterRecipe {
    base: WaveNoise,
    paint_offset: WaveNoise,
    holes: WaveNoise,
    flake_offset: WaveNoise,
    flakes: WaveNoise,
}

impl PlasterRecipe {
    fn new(rng: &mut ChaCha8Rng) -> Self {
        PlasterRecipe {
            base: WaveNoise::new(rng, 6, (0.8, 3.0)),
            paint_offset: WaveNoise::new(rng, 6, (2.0, 6.0)),
            holes: WaveNoise::new(rng, 6, (2.0, 5.0)),
            flake_offset: WaveNoise::new(rng, 6, (3.0, 8.0)),
            flakes: WaveNoise::new(rng, 8, (3.0, 7.0)),
        }
    }

    fn base(&self, p: Vec2) -> f32 {
        0.015 * self.base.at(p.x, p.y)
    }

    fn paint(&self, p: Vec2, gap: f32) -> f32 {
        self.base(p) + gap * (1.0 + 0.25 * self.paint_offset.at(p.x, p.y))
    }

    fn layers(&self, edge: f32) -> Vec<SheetLayer<'_>> {
        let gap = LAYER_GAP_EDGES * edge;
        vec![
            SheetLayer {
                name: "plaster".into(),
                brdf: material::PLASTER.brdf,
                height: Box::new(move |p| self.base(p)),
                keep: Box::new(|_| true),
            },
            SheetLayer {
                name: "paint".into(),
                brdf: material::PAINT.brdf,
                height: Box::new(move |p| self.paint(p, gap)),
                keep: Box::new(move |p| self.holes.at(p.x, p.y) < 0.45),
            },
            SheetLayer {
                name: "flakes".into(),
                brdf: material::PEELING_PAINT.brdf,
                height: Box::new(move |p| {
                    let inside = (self.flakes.at(p.x, p.y) - 0.3) / 0.4;
                    self.paint(p, gap)
                        + gap * (1.0 + 0.25 * self.flake_offset.at(p.x, p.y))
                        + gap * 1.2 * curl(inside)
                }),
                keep: Box::new(move |p| self.flakes.at(p.x, p.y) > 0.3),
            },
        ]
    }
}

/// Tree bark: wood, inner bark with short cracks, plates split by deep cracks, lichen flakes.
struct BarkRecipe {
    wobble: WaveNoise,
    detail: WaveNoise,
    offsets: [WaveNoise; 3],
    short_cracks: WaveNoise,
    lichen: WaveNoise,
}

const BARK_RIDGES: f32 = 6.0;

impl BarkRecipe {
    fn new(rng: &mut ChaCha8Rng) -> Self {
        BarkRecipe {
            wobble: WaveNoise::new(rng, 5, (0.5, 2.0)),
            detail: WaveNoise::new(rng, 6, (4.0, 9.0)),
            offsets: [
                WaveNoise::new(rng, 6, (3.0, 8.0)),
                WaveNoise::new(rng, 6, (3.0, 8.0)),
                WaveNoise::new(rng, 6, (3.0, 8.0)),
            ],
            short_cracks: WaveNoise::new(rng, 6, (2.0, 5.0)),
            lichen: WaveNoise::new(rng, 8, (4.0, 9.0)),
        }
    }

    /// Position across the ridges: integer values are crack lines.
    fn across(&self, p: Vec2) -> f32 {
        BARK_RIDGES * p.x + 0.4 * self.wobble.at(p.x, p.y) + 0.5
    }

    /// 0 on a crack line, 1 midway between cracks.
    fn crack_distance(&self, p: Vec2) -> f32 {
        (std::f32::consts::PI * self.across(p)).sin().abs()
    }

    fn layer_height(&self, p: Vec2, layer: usize, gap: f32) -> f32 {
        let ridge = 0.006 * (std::f32::consts::TAU * (self.across(p) - 0.5)).cos();
        let mut z = ridge + 0.003 * self.detail.at(p.x, p.y);
        for offset in &self.offsets[..layer] {
            z += gap * (1.0 + 0.25 * offset.at(p.x, p.y));
        }
        z
    }

    fn on_plate(&self, p: Vec2) -> bool {
        let column = self.across(p).floor();
        let break_line = (std::f32::consts::PI
            * (4.0 * p.y + 0.37 * column + 0.3 * self.wobble.at(p.y, p.x)))
        .sin()
        .abs();
        self.crack_distance(p) > 0.18 && break_line > 0.1
    }

    fn layers(&self, edge: f32) -> Vec<SheetLayer<'_>> {
        let gap = LAYER_GAP_EDGES * edge;
        vec![
            SheetLayer {
                name: "wood".into(),
                brdf: material::WOOD.brdf,
                height: Box::new(move |p| self.layer_height(p, 0, gap)),
                keep: Box::new(|_| true),
            },
            SheetLayer {
                name: "inner-bark".into(),
                brdf: material::INNER_BARK.brdf,
                height: Box::new(move |p| self.layer_height(p, 1, gap)),
                keep: Box::new(move |p| {
                    self.crack_distance(p) > 0.12 || self.short_cracks.at(p.x, p.y) < 0.2
                }),
            },
            SheetLayer {
                name: "bark-plates".into(),
                brdf: material::BARK.brdf,
                height: Box::new(move |p| self.layer_height(p, 2, gap)),
                keep: Box::new(move |p| self.on_plate(p)),
            },
            SheetLayer {
                name: "lichen".into(),
                brdf: material::LICHEN.brdf,
                height: Box::new(move |p| {
                    let inside = (self.lichen.at(p.x, p.y) - 0.35) / 0.4;
                    self.layer_height(p, 3, gap) + gap * 1.2 * curl(inside)
                }),
                keep: Box::new(move |p| self.lichen.at(p.x, p.y) > 0.35 && self.on_plate(p)),
            },
        ]
    }
}

/// Rusted metal: a dented plate, rust crust patches, rust flakes curling off the crust.
struct MetalRecipe {
    dents: WaveNoise,
    rust: WaveNoise,
    crust_offset: WaveNoise,
    flake_offset: WaveNoise,
    flakes: WaveNoise,
}

impl MetalRecipe {
    fn new(rng: &mut ChaCha8Rng) -> Self {
        MetalRecipe {
            dents: WaveNoise::new(rng, 6, (1.0, 4.0)),
            rust: WaveNoise::new(rng, 8, (2.0, 7.0)),
            crust_offset: WaveNoise::new(rng, 6, (4.0, 10.0)),
            flake_offset: WaveNoise::new(rng, 6, (4.0, 10.0)),
            flakes: WaveNoise::new(rng, 8, (5.0, 10.0)),
        }
    }

    fn crust(&self, p: Vec2, gap: f32) -> f32 {
        0.004 * self.dents.at(p.x, p.y) + gap * (1.0 + 0.3 * self.crust_offset.at(p.x, p.y))
    }

    fn layers(&self, edge: f32) -> Vec<SheetLayer<'_>> {
        let gap = LAYER_GAP_EDGES * edge;
        vec![
            SheetLayer {
                name: "steel".into(),
                brdf: material::BARE_METAL.brdf,
                height: Box::new(move |p| 0.004 * self.dents.at(p.x, p.y)),
                keep: Box::new(|_| true),
            },
            SheetLayer {
                name: "rust".into(),
                brdf: material::RUST.brdf,
                height: Box::new(move |p| self.crust(p, gap)),
                keep: Box::new(move |p| self.rust.at(p.x, p.y) > -0.05),
            },
            SheetLayer {
                name: "rust-flakes".into(),
                brdf: material::RUST_FLAKE.brdf,
                height: Box::new(move |p| {
                    let inside = (self.flakes.at(p.x, p.y) - 0.35) / 0.4;
                    self.crust(p, gap)
                        + gap * (1.0 + 0.25 * self.flake_offset.at(p.x, p.y))
                        + gap * 1.2 * curl(inside)
                }),
                keep: Box::new(move |p| {
                    self.flakes.at(p.x, p.y) > 0.35 && self.rust.at(p.x, p.y) > 0.1
                }),
            },
        ]
    }
}
