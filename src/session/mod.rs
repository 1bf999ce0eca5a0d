//! The editing session (the document): the mesh, each layer's settings, the brush, and the
//! history that undoes and redoes every change a user makes.
//!
//! The mesh can only be changed through an [`Edit`], which records what changed as one
//! history entry when it ends — a stroke, a paint stroke, a mask edit, a layer tool — so
//! nothing a user does escapes undo. An entry keeps only the rows that changed
//! ([`MeshDelta`]), found by comparing the mesh with the copy the session keeps of it as the
//! last entry left it (`recorded`): one copy of the mesh, however long the history, made when
//! the first edit starts (or by [`Session::prepare_history`]), so a session that is only opened,
//! converted or measured never holds two. [`Session::without_history`] keeps none at all: a
//! batch that writes a mesh file, whose history would be thrown away, needs no copy.
//!
//! ```
//! use slayer::pipeline::{Pipeline, PipelineSettings};
//! use slayer::scene::{SceneKind, SceneSpec, generate};
//! use slayer::session::Session;
//!
//! let mesh = generate(&SceneSpec { kind: SceneKind::Plaster, triangles: 2_000, seed: 1 })?;
//! let before = mesh.digest();
//! let mut session = Session::new(mesh);
//! let mut pipeline = Pipeline::new(PipelineSettings::default());
//! let script = slayer::bench::generate_script(session.mesh(), &Default::default());
//! let stroke = &script.resolve(session.mesh(), "script")?[0];
//! session.apply_stroke(&mut pipeline, stroke)?;
//! session.undo();
//! assert_eq!(session.mesh().digest(), before);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod file;
mod history;
mod tools;

pub use file::{
    SessionFileError, VERSION, check_save_path, is_session_path, open, open_with, read_session,
    save, stage, write_session,
};
pub use history::{DEFAULT_HISTORY_CAP_BYTES, Entry, History};
pub use tools::Deleted;

use serde::{Deserialize, Serialize};

use crate::brush::{BrushKind, Falloff, Stroke, StrokeSettings};
use crate::mesh::{Brdf, LayerId, Mesh, MeshDelta};
use crate::pipeline::{Pipeline, PipelineError, StrokeReport};
pub use crate::topology::ProximityPolicy;

/// A layer's settings; its name lives in the mesh (files keep it there).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LayerSettings {
    pub visible: bool,
    /// Brushed by strokes that do not name their layers.
    pub active: bool,
    pub policy: ProximityPolicy,
    /// What painting with the layer's own material lays down.
    pub material: Brdf,
}

/// The brush a user has picked (the app's brush panel; a stroke file names its own).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BrushSettings {
    pub kind: BrushKind,
    pub radius: f32,
    pub strength: f32,
    pub falloff: Falloff,
    pub invert: bool,
    /// Resampling step as a share of the radius.
    pub spacing: f32,
}

impl BrushSettings {
    /// A draw brush twelve edge lengths wide (the bench's size), for a mesh of edge `edge`.
    pub fn for_edge(edge: f32) -> BrushSettings {
        BrushSettings {
            kind: BrushKind::Draw,
            radius: 12.0 * edge,
            strength: 0.5,
            falloff: Falloff::default(),
            invert: false,
            spacing: 0.25,
        }
    }
}

/// What recording an edit did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Recorded {
    /// The entry changed the mesh or the layers (one that changed nothing is recorded too:
    /// every action is one entry, so undoing as many steps as strokes were made undoes them).
    pub changed: bool,
    /// Bytes the entry holds.
    pub bytes: usize,
    /// The oldest entries dropped to stay under the memory cap.
    pub dropped: usize,
}

/// An entry undone or redone.
#[derive(Debug, Clone, PartialEq)]
pub struct Stepped {
    pub label: String,
    /// The vertices whose rows changed: what a viewer re-uploads.
    pub touched_vertices: Vec<u32>,
}

/// The document a user edits.
#[derive(Debug, Clone)]
pub struct Session {
    mesh: Mesh,
    layers: Vec<LayerSettings>,
    /// The brush the user has picked.
    pub brush: BrushSettings,
    history: History,
    /// The mesh as the history's last done entry left it: the next edit is compared with it.
    /// `None` until the first edit (the mesh is then as recorded) or when the session keeps no
    /// history.
    recorded: Option<Mesh>,
    /// Whether edits are recorded (undoable).
    keeps_history: bool,
}

/// Why a session operation was refused; the session is unchanged.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SessionError {
    #[error("layer {layer} does not exist (the mesh has {layer_count})")]
    NoSuchLayer { layer: LayerId, layer_count: usize },
    #[error("a layer name must be one line of at most 255 bytes, not {0:?}")]
    BadLayerName(String),
    #[error("vertex {0} does not exist or belongs to no face")]
    NoSuchVertex(u32),
}

impl Session {
    /// A new session on `mesh`: every layer visible, active and colliding, its material the
    /// BRDF of its first vertex; an empty history with the default cap.
    pub fn new(mesh: Mesh) -> Session {
        let layers = default_layers(&mesh);
        let brush = BrushSettings::for_edge(mesh.mean_edge_length());
        Session::from_parts(mesh, layers, brush, History::default())
    }

    /// A session from its parts (a session file); `history`'s done entries end at `mesh`.
    pub(crate) fn from_parts(
        mesh: Mesh,
        layers: Vec<LayerSettings>,
        brush: BrushSettings,
        history: History,
    ) -> Session {
        Session {
            recorded: None,
            keeps_history: true,
            mesh,
            layers,
            brush,
            history,
        }
    }

    /// A session that records nothing: edits cannot be undone, and no copy of the mesh is
    /// kept (half the memory of a session with history, for batch work that writes a mesh).
    pub fn without_history(mesh: Mesh) -> Session {
        let mut session = Session::new(mesh);
        session.drop_history();
        session
    }

    /// From now on records nothing, and lets go of the history and of the copy of the mesh:
    /// [`Session::without_history`] for a session already open.
    pub fn drop_history(&mut self) {
        self.keeps_history = false;
        self.recorded = None;
        self.history = History::with_cap(self.history.cap_bytes());
    }

    /// Whether edits are recorded as undoable history entries.
    pub fn keeps_history(&self) -> bool {
        self.keeps_history
    }

    /// Makes the copy of the mesh the next edit is compared with now rather than when that
    /// edit starts (an app calls it after opening a large file, so the first stroke does not
    /// wait for the copy). Nothing to do without history or once made.
    pub fn prepare_history(&mut self) {
        if self.keeps_history && self.recorded.is_none() {
            self.recorded = Some(self.mesh.clone());
        }
    }

    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// The mesh, leaving the session.
    pub fn into_mesh(self) -> Mesh {
        self.mesh
    }

    pub fn layers(&self) -> &[LayerSettings] {
        &self.layers
    }

    pub fn history(&self) -> &History {
        &self.history
    }

    /// Sets the history's memory cap; returns how many of the oldest entries it dropped.
    pub fn set_history_cap(&mut self, bytes: usize) -> usize {
        self.history.set_cap(bytes)
    }

    /// The active layers, ascending (what a stroke that names none brushes).
    pub fn active_layers(&self) -> Vec<LayerId> {
        (0..self.layers.len() as LayerId)
            .filter(|&l| self.layers[l as usize].active)
            .collect()
    }

    /// Starts a change of the mesh, recorded as one history entry labelled `label` when the
    /// returned [`Edit`] is committed or dropped (even one that changed nothing: every action
    /// is one entry).
    pub fn edit(&mut self, label: &str) -> Edit<'_> {
        self.prepare_history();
        Edit {
            label: label.to_string(),
            session: self,
            layers_before: None,
            done: false,
        }
    }

    /// Those of `layers` whose policy is fuse: what a stroke brushing them gives as
    /// [`StrokeSettings::fuse`].
    pub fn fuse_layers(&self, layers: &[LayerId]) -> Vec<LayerId> {
        (layers.iter().copied())
            .filter(|&l| {
                self.layers
                    .get(l as usize)
                    .is_some_and(|s| s.policy == ProximityPolicy::Fuse)
            })
            .collect()
    }

    /// Every layer whose policy is fuse (what a slayer PLY marks, what `check` reports).
    pub fn all_fuse_layers(&self) -> Vec<LayerId> {
        let all: Vec<LayerId> = (0..self.layers.len() as LayerId).collect();
        self.fuse_layers(&all)
    }

    /// A whole stroke through `pipeline`, as one history entry named after its brush.
    pub fn apply_stroke(
        &mut self,
        pipeline: &mut Pipeline,
        stroke: &Stroke,
    ) -> Result<(StrokeReport, Recorded), PipelineError> {
        let settings = StrokeSettings {
            fuse: self.fuse_layers(&stroke.layers),
            ..stroke.settings()
        };
        let mut edit = self.edit(&stroke_label(&settings));
        let report = pipeline
            .begin_stroke(edit.mesh(), settings)
            .and_then(|s| s.finish_with(&stroke.samples));
        // A failed stroke leaves the mesh intact but may have moved some of it: recorded too.
        let recorded = edit.commit();
        Ok((report?, recorded))
    }

    /// Changes a layer's settings, as one history entry.
    pub fn set_layer(
        &mut self,
        layer: LayerId,
        settings: LayerSettings,
    ) -> Result<Recorded, SessionError> {
        self.check_layer(layer)?;
        let before = self.layers.clone();
        self.layers[layer as usize] = settings;
        let changed = before != self.layers;
        let after = self.layers.clone();
        let entry = Entry::new(
            "layer settings",
            MeshDelta::default(),
            Some((before, after)),
        );
        Ok(self.push(entry, changed))
    }

    /// Renames a layer, as one history entry.
    pub fn rename_layer(&mut self, layer: LayerId, name: &str) -> Result<Recorded, SessionError> {
        self.check_layer(layer)?;
        if name.is_empty() || name.len() > 255 || name.chars().any(char::is_control) {
            return Err(SessionError::BadLayerName(name.to_string()));
        }
        let mut edit = self.edit("rename layer");
        edit.mesh().set_layer_name(layer, name);
        Ok(edit.commit())
    }

    /// Clears the mask of every vertex, as one history entry.
    pub fn clear_mask(&mut self) -> Recorded {
        self.mask_where("clear mask", |_, _| Some(0.0))
    }

    /// Inverts the mask (a weight `m` becomes `1 − m`), as one history entry.
    pub fn invert_mask(&mut self) -> Recorded {
        self.mask_where("invert mask", |_, mask| Some(1.0 - mask))
    }

    /// Sets the mask of every vertex of `layer` to `weight` (0 unmasks, 1 masks fully), as one
    /// history entry.
    pub fn mask_layer(&mut self, layer: LayerId, weight: f32) -> Result<Recorded, SessionError> {
        self.check_layer(layer)?;
        let layers = self.mesh.vertex_layers().to_vec();
        Ok(self.mask_where("mask layer", |v, _| (layers[v] == layer).then_some(weight)))
    }

    /// Sets the mask of the connected component holding `vertex` to `weight`, as one history
    /// entry.
    pub fn mask_component(&mut self, vertex: u32, weight: f32) -> Result<Recorded, SessionError> {
        let mesh = &self.mesh;
        let live = (vertex as usize) < mesh.vertex_count() && !mesh.is_vertex_dead(vertex);
        let Some(face) = live.then(|| mesh.faces_around(vertex).next()).flatten() else {
            return Err(SessionError::NoSuchVertex(vertex));
        };
        let components = mesh.components();
        let wanted = components.face_component[face as usize];
        let mut inside = vec![false; mesh.vertex_count()];
        for (f, tri) in mesh.faces().iter().enumerate() {
            if !mesh.is_face_dead(f) && components.face_component[f] == wanted {
                tri.iter().for_each(|&v| inside[v as usize] = true);
            }
        }
        Ok(self.mask_where("mask component", |v, _| inside[v].then_some(weight)))
    }

    /// Sets the mask of each live vertex to what `new_mask(vertex, mask)` says (`None` keeps
    /// it), as one history entry labelled `label`.
    fn mask_where(
        &mut self,
        label: &str,
        new_mask: impl Fn(usize, f32) -> Option<f32>,
    ) -> Recorded {
        let mut edit = self.edit(label);
        let mesh = edit.mesh();
        let dead: Vec<bool> = (0..mesh.vertex_count() as u32)
            .map(|v| mesh.is_vertex_dead(v))
            .collect();
        for (v, flags) in mesh.flags_mut().iter_mut().enumerate() {
            if let Some(weight) = new_mask(v, flags.mask()).filter(|_| !dead[v]) {
                flags.set_mask(weight);
            }
        }
        edit.commit()
    }

    /// Undoes the last done entry; `None` when there is none.
    pub fn undo(&mut self) -> Option<Stepped> {
        let entry = self.history.step_back()?;
        entry.undo(&mut self.mesh, &mut self.layers);
        // Without a copy the mesh was as recorded, and stays so.
        if let Some(recorded) = &mut self.recorded {
            entry.mesh.undo(recorded);
        }
        Some(Stepped {
            label: entry.label.clone(),
            touched_vertices: entry.touched_vertices(),
        })
    }

    /// Redoes the first undone entry; `None` when there is none.
    pub fn redo(&mut self) -> Option<Stepped> {
        let entry = self.history.step_forward()?;
        entry.redo(&mut self.mesh, &mut self.layers);
        if let Some(recorded) = &mut self.recorded {
            entry.mesh.redo(recorded);
        }
        Some(Stepped {
            label: entry.label.clone(),
            touched_vertices: entry.touched_vertices(),
        })
    }

    fn check_layer(&self, layer: LayerId) -> Result<(), SessionError> {
        if (layer as usize) < self.layers.len() {
            Ok(())
        } else {
            Err(SessionError::NoSuchLayer {
                layer,
                layer_count: self.layers.len(),
            })
        }
    }

    /// Records what changed since the last entry as one entry labelled `label` (with the
    /// layer settings, where `layers_before` says what they were and they changed).
    /// Without history nothing is recorded, and whether the mesh changed is not known: it
    /// is reported changed.
    fn record(&mut self, label: &str, layers_before: Option<Vec<LayerSettings>>) -> Recorded {
        let layers = layers_before
            .filter(|before| *before != self.layers)
            .map(|before| (before, self.layers.clone()));
        let Some(recorded) = self.recorded.as_mut().filter(|_| self.keeps_history) else {
            return Recorded {
                changed: true,
                ..Recorded::default()
            };
        };
        let delta = MeshDelta::between(recorded, &self.mesh);
        let changed = !delta.is_empty() || layers.is_some();
        delta.redo(recorded);
        self.push(Entry::new(label, delta, layers), changed)
    }

    fn push(&mut self, entry: Entry, changed: bool) -> Recorded {
        if !self.keeps_history {
            return Recorded {
                changed,
                ..Recorded::default()
            };
        }
        let bytes = entry.bytes();
        let dropped = self.history.push(entry);
        Recorded {
            changed,
            bytes,
            dropped,
        }
    }
}

/// A change of a session's mesh in progress; recorded as one history entry by
/// [`Edit::commit`], or when dropped (an error or a panic half-way does not escape undo).
pub struct Edit<'a> {
    session: &'a mut Session,
    label: String,
    /// The layer settings as the edit found them, once it asked to change them.
    layers_before: Option<Vec<LayerSettings>>,
    done: bool,
}

impl Edit<'_> {
    /// The mesh to change (give it to `Pipeline::begin_stroke`, a paint or mask tool, ...).
    pub fn mesh(&mut self) -> &mut Mesh {
        &mut self.session.mesh
    }

    /// The mesh and the layer settings, for an edit that adds or removes layers (the layer
    /// tools): the settings change with the mesh, in the same entry.
    pub fn mesh_and_layers(&mut self) -> (&mut Mesh, &mut Vec<LayerSettings>) {
        if self.layers_before.is_none() {
            self.layers_before = Some(self.session.layers.clone());
        }
        (&mut self.session.mesh, &mut self.session.layers)
    }

    /// Records the change as one history entry.
    pub fn commit(mut self) -> Recorded {
        self.done = true;
        self.session.record(&self.label, self.layers_before.take())
    }
}

impl Drop for Edit<'_> {
    fn drop(&mut self) {
        if !self.done {
            self.session.record(&self.label, self.layers_before.take());
        }
    }
}

/// Every layer visible, active, colliding, in the material of its first live vertex.
fn default_layers(mesh: &Mesh) -> Vec<LayerSettings> {
    let mut materials = vec![None; mesh.layer_count()];
    for v in 0..mesh.vertex_count() {
        let layer = mesh.vertex_layers()[v] as usize;
        if !mesh.is_vertex_dead(v as u32) && layer < materials.len() && materials[layer].is_none() {
            materials[layer] = Some(mesh.brdfs()[v]);
        }
    }
    materials
        .into_iter()
        .map(|material| LayerSettings {
            visible: true,
            active: true,
            policy: ProximityPolicy::Collide,
            material: material.unwrap_or(Brdf::CLAY),
        })
        .collect()
}

/// The history label of a stroke: "draw stroke", "paint stroke", "grab stroke (painting)".
pub fn stroke_label(stroke: &StrokeSettings) -> String {
    let kind = stroke.brush.kind.name();
    let painting = if stroke.paint.is_some() && stroke.brush.kind != BrushKind::Paint {
        " (painting)"
    } else {
        ""
    };
    format!("{kind} stroke{painting}")
}
