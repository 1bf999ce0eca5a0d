//! Deleting pieces (the sLayer paper's Fig. 5 removes the flakes a cut detached): a component,
//! the smallest ones, every one under a face count, or a whole layer; the mesh is compacted.

use super::ToolError;
use super::select::check_layer;
use crate::mesh::{Components, LayerId, Mesh};

/// What to delete.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DeleteTarget {
    /// A whole layer; the layers after it move down by one.
    Layer(LayerId),
    /// One connected component (numbered as `slayer layer list` prints them).
    Component(u32),
    /// The `n` components with the fewest faces (ties: the lower number first).
    Smallest(usize),
    /// Every component with fewer faces than this.
    Under(usize),
}

/// Which faces deleting `target` removes (per face), and how many components that is; an
/// error for a target that does not exist or would leave no face.
pub fn plan_delete(mesh: &Mesh, target: DeleteTarget) -> Result<(Vec<bool>, usize), ToolError> {
    let components = mesh.components();
    let doomed_components: Vec<bool> = match target {
        DeleteTarget::Layer(layer) => {
            check_layer(mesh, layer)?;
            components.layer.iter().map(|&l| l == layer).collect()
        }
        DeleteTarget::Component(c) => {
            if c as usize >= components.count() {
                return Err(ToolError::NoSuchComponent {
                    component: c,
                    count: components.count(),
                });
            }
            (0..components.count()).map(|i| i == c as usize).collect()
        }
        DeleteTarget::Smallest(n) => smallest(&components, n),
        DeleteTarget::Under(faces) => components.size.iter().map(|&s| s < faces).collect(),
    };
    let count = doomed_components.iter().filter(|&&d| d).count();
    // A layer with no face may still go (its name does); any other target must match.
    if count == 0 && !matches!(target, DeleteTarget::Layer(_)) {
        return Err(ToolError::EmptySelection(
            "no component matches".to_string(),
        ));
    }
    if count > 0 && count == components.count() {
        return Err(ToolError::WouldEmpty(match target {
            DeleteTarget::Layer(l) => format!("layer {l}, the only one with faces,"),
            _ => "every component".to_string(),
        }));
    }
    let doomed = components
        .face_component
        .iter()
        .map(|&c| (c as usize) < doomed_components.len() && doomed_components[c as usize])
        .collect();
    Ok((doomed, count))
}

/// The `n` smallest components, ties to the lower number.
fn smallest(components: &Components, n: usize) -> Vec<bool> {
    let mut order: Vec<usize> = (0..components.count()).collect();
    order.sort_by_key(|&c| (components.size[c], c));
    let mut doomed = vec![false; components.count()];
    for &c in order.iter().take(n) {
        doomed[c] = true;
    }
    doomed
}
