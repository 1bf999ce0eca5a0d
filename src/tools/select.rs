//! What a tool works on: a whole layer, the masked part of one, or a connected component
//! (numbered as [`Mesh::components`] numbers them, which `slayer layer list` prints).

use serde::Serialize;

use super::ToolError;
use crate::mesh::{LayerId, Mesh};

/// A mask weight at least this selects a vertex.
const MASKED: f32 = 0.5;

/// The faces a tool works on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Selection {
    /// Every face of a layer.
    Layer(LayerId),
    /// The faces of a layer whose three vertices are masked (weight ≥ 1/2).
    Masked(LayerId),
    /// One connected component.
    Component(u32),
}

/// The live faces `selection` names, ascending; an error for a layer or component that does
/// not exist, or a selection with no face.
pub fn selected_faces(mesh: &Mesh, selection: Selection) -> Result<Vec<u32>, ToolError> {
    let live = |f: usize| !mesh.is_face_dead(f);
    let faces: Vec<u32> = match selection {
        Selection::Layer(layer) | Selection::Masked(layer) => {
            check_layer(mesh, layer)?;
            let masked = |f: usize| {
                let flags = mesh.flags();
                mesh.faces()[f]
                    .iter()
                    .all(|&v| flags[v as usize].mask() >= MASKED)
            };
            let want_mask = matches!(selection, Selection::Masked(_));
            (0..mesh.face_count())
                .filter(|&f| live(f) && mesh.face_layers()[f] == layer)
                .filter(|&f| !want_mask || masked(f))
                .map(|f| f as u32)
                .collect()
        }
        Selection::Component(component) => {
            let components = mesh.components();
            if component as usize >= components.count() {
                return Err(ToolError::NoSuchComponent {
                    component,
                    count: components.count(),
                });
            }
            let labels = &components.face_component;
            (0..mesh.face_count() as u32)
                .filter(|&f| labels[f as usize] == component)
                .collect()
        }
    };
    if faces.is_empty() {
        let what = match selection {
            Selection::Layer(l) => format!("layer {l} has no face"),
            Selection::Masked(l) => format!("no face of layer {l} has its three vertices masked"),
            Selection::Component(c) => format!("component {c} has no face"),
        };
        return Err(ToolError::EmptySelection(what));
    }
    Ok(faces)
}

pub(super) fn check_layer(mesh: &Mesh, layer: LayerId) -> Result<(), ToolError> {
    if (layer as usize) < mesh.layer_count() {
        Ok(())
    } else {
        Err(ToolError::NoSuchLayer {
            layer,
            layer_count: mesh.layer_count(),
        })
    }
}

/// One layer as `slayer layer list` prints it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LayerSummary {
    pub layer: LayerId,
    pub name: String,
    pub faces: usize,
    pub vertices: usize,
    pub components: Vec<ComponentSummary>,
}

/// One connected component of a layer.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ComponentSummary {
    /// Its number (what `Selection::Component` and `--component` take).
    pub component: u32,
    pub faces: usize,
    /// No boundary edge.
    pub closed: bool,
}

/// Every layer with its components, in layer order.
pub fn layer_summaries(mesh: &Mesh) -> Vec<LayerSummary> {
    let components = mesh.components();
    let open = mesh.open_components(&components);
    let mut vertices = vec![0; mesh.layer_count()];
    for v in 0..mesh.vertex_count() as u32 {
        if mesh.is_vertex_live(v) {
            vertices[mesh.vertex_layers()[v as usize] as usize] += 1;
        }
    }
    let faces = mesh.faces_per_layer();
    let mut summaries: Vec<LayerSummary> = (0..mesh.layer_count())
        .map(|l| LayerSummary {
            layer: l as LayerId,
            name: mesh.layer_names()[l].clone(),
            faces: faces[l],
            vertices: vertices[l],
            components: Vec::new(),
        })
        .collect();
    for (c, &layer) in components.layer.iter().enumerate() {
        summaries[layer as usize].components.push(ComponentSummary {
            component: c as u32,
            faces: components.size[c],
            closed: !open[c],
        });
    }
    summaries
}
