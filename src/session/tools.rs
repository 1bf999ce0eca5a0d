//! The layer tools (`crate::tools`) as history entries: each is planned and checked on the
//! mesh as it is, and only a tool that succeeds opens an entry, which holds the mesh's rows and
//! the layer settings together, so one undo takes a new or deleted layer back whole.

use std::time::Instant;

use super::{LayerSettings, ProximityPolicy, Recorded, Session};
use crate::mesh::LayerId;
use crate::tools::{
    CutReport, CutSettings, DeleteTarget, DuplicateReport, DuplicateSettings, Selection, ToolError,
    plan_delete, plan_duplicate, plan_patch,
};

/// What a delete removed.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Deleted {
    pub components: usize,
    pub faces: usize,
    /// The layer removed, for [`DeleteTarget::Layer`].
    pub layer: Option<LayerId>,
    pub millis: f64,
}

impl Session {
    /// Copies `selection` into a new layer lifted off it (visible, active, colliding, in
    /// `settings.material`), as one history entry; on an error nothing changes.
    pub fn duplicate(
        &mut self,
        selection: Selection,
        settings: &DuplicateSettings,
    ) -> Result<(DuplicateReport, Recorded), ToolError> {
        let started = Instant::now();
        let (piece, report) = plan_duplicate(&self.mesh, selection, settings)?;
        self.add_layer("duplicate layer", &piece, report, settings, started)
    }

    /// Makes a new layer of the Coons patch filling the closed `outline` drawn on `layer`,
    /// lifted off it (visible, active, colliding, in `settings.material`), as one history
    /// entry; on an error nothing changes.
    pub fn patch(
        &mut self,
        outline: &[glam::Vec3],
        layer: LayerId,
        settings: &DuplicateSettings,
    ) -> Result<(DuplicateReport, Recorded), ToolError> {
        let started = Instant::now();
        let (piece, report) = plan_patch(&self.mesh, outline, layer, settings)?;
        self.add_layer("patch layer", &piece, report, settings, started)
    }

    /// Appends `piece` as a new layer with its settings, as one history entry.
    fn add_layer(
        &mut self,
        label: &str,
        piece: &crate::mesh::Mesh,
        mut report: DuplicateReport,
        settings: &DuplicateSettings,
        started: Instant,
    ) -> Result<(DuplicateReport, Recorded), ToolError> {
        let mut edit = self.edit(label);
        let (mesh, layers) = edit.mesh_and_layers();
        report.layer = mesh.append(piece);
        layers.push(LayerSettings {
            visible: true,
            active: true,
            policy: ProximityPolicy::Collide,
            material: settings.material,
        });
        let recorded = edit.commit();
        report.millis = started.elapsed().as_secs_f64() * 1e3;
        Ok((report, recorded))
    }

    /// Cuts `settings.layers` open along `stroke` (points on or near the surface), as one
    /// history entry; on an error nothing changes.
    pub fn cut(
        &mut self,
        stroke: &[glam::Vec3],
        settings: &CutSettings,
    ) -> Result<(CutReport, Recorded), ToolError> {
        // The cut changes the mesh only once it is made and checked; the entry compares the
        // mesh with the history's copy, made before it.
        self.prepare_history();
        let report = crate::tools::cut(&mut self.mesh, stroke, settings)?;
        Ok((report, self.edit("cut").commit()))
    }

    /// Deletes `target` and compacts the mesh, as one history entry; on an error (a target
    /// that does not exist, or one that would leave no face) nothing changes.
    pub fn delete(&mut self, target: DeleteTarget) -> Result<(Deleted, Recorded), ToolError> {
        let started = Instant::now();
        let (doomed, components) = plan_delete(&self.mesh, target)?;
        let faces = doomed.iter().filter(|&&d| d).count();
        let label = match target {
            DeleteTarget::Layer(_) => "delete layer",
            _ => "delete components",
        };
        let mut edit = self.edit(label);
        let (mesh, layers) = edit.mesh_and_layers();
        let layer = match target {
            DeleteTarget::Layer(layer) => {
                mesh.remove_layer(layer);
                layers.remove(layer as usize);
                Some(layer)
            }
            _ => {
                mesh.remove_faces(&doomed);
                None
            }
        };
        let recorded = edit.commit();
        let deleted = Deleted {
            components,
            faces,
            layer,
            millis: started.elapsed().as_secs_f64() * 1e3,
        };
        Ok((deleted, recorded))
    }
}
