//! Layer tools: the edits that make and remove layers, beside the brushes that shape them (the
//! sLayer paper's "Editing Tools": offset duplication, a Coons patch from a closed stroke,
//! cutting along a stroke, and deleting detached pieces).
//!
//! Every tool is planned on the mesh as it is and checked before anything changes: a tool
//! that fails returns its error and leaves the mesh untouched. `Session` runs them as history
//! entries (undoable, bit for bit), `slayer layer` from the command line.
//!
//! Floors: `select` ← `obstacles` ← `shell` ← `duplicate` ← `patch`; `obstacles` ← `cut`;
//! `delete` beside them. Nothing here imports the pipeline, the session or the GPU.

mod cut;
mod delete;
mod duplicate;
mod obstacles;
mod patch;
mod select;
mod shell;

pub use cut::{CutReport, CutSettings, cut};
pub use delete::{DeleteTarget, plan_delete};
pub use duplicate::{DuplicateReport, DuplicateSettings, duplicate, plan_duplicate};
pub use patch::{patch, plan_patch};
pub use select::{ComponentSummary, LayerSummary, Selection, layer_summaries, selected_faces};

use crate::mesh::{LayerId, MeshError};

/// Why a layer tool refused; the mesh is unchanged.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ToolError {
    #[error("layer {layer} does not exist (the mesh has {layer_count})")]
    NoSuchLayer { layer: LayerId, layer_count: usize },
    #[error(
        "component {component} does not exist (the mesh has {count}; `slayer layer list` numbers them)"
    )]
    NoSuchComponent { component: u32, count: usize },
    #[error("nothing is selected: {0}")]
    EmptySelection(String),
    #[error("the selection is not a surface on its own ({0}); mask a rounder region")]
    SelectionNotManifold(String),
    #[error("{what} must be a finite length {range}, not {value}")]
    BadLength {
        what: &'static str,
        range: &'static str,
        value: f32,
    },
    #[error(
        "the copy has no room at its vertex {vertex}: layer {layer} is in the way {reached:.4} \
         along its normal, and it needs {needed:.4} (the collision distance, and the \
         thickness); lower the thickness, or select less (a surface curled tighter than the \
         collision distance cannot be lifted off itself)"
    )]
    NoRoom {
        vertex: u32,
        layer: LayerId,
        reached: f32,
        needed: f32,
    },
    #[error(
        "the copy would come within {gap:.4} of layer {layer} at its vertex {vertex} (the \
         collision distance is {distance:.4}); lower the offset or select less"
    )]
    TooClose {
        vertex: u32,
        layer: LayerId,
        gap: f32,
        distance: f32,
    },
    #[error(
        "the copy would cross the mesh ({with_mesh} pairs of faces) or itself ({within_copy} \
         pairs: lifted farther than a curl's radius, a surface folds); lower the offset or \
         thickness, or select less"
    )]
    WouldIntersect {
        with_mesh: usize,
        within_copy: usize,
    },
    #[error("{0}")]
    BadStroke(String),
    #[error(
        "the cut's two sides could not be opened apart ({pairs} pairs of faces would touch or \
         fold); draw it across the piece, clear of the rim's corners, or where the surface is \
         finer"
    )]
    CutNotOpened { pairs: usize },
    #[error("deleting {0} would leave no face; a mesh keeps at least one")]
    WouldEmpty(String),
}

impl From<MeshError> for ToolError {
    fn from(error: MeshError) -> ToolError {
        ToolError::SelectionNotManifold(error.to_string())
    }
}

/// Checks that `value` is a finite length in `(0, max]`.
fn check_length(what: &'static str, value: f32, max: f32) -> Result<(), ToolError> {
    if value.is_finite() && value > 0.0 && value <= max {
        Ok(())
    } else {
        Err(ToolError::BadLength {
            what,
            range: "above 0 and at most the mesh's extent",
            value,
        })
    }
}
