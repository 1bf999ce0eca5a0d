//! Errors that name the broken element of a mesh.

use thiserror::Error;

/// What is wrong with a mesh, with the element that is wrong.
///
/// Every variant carries the indices a user (or a test) needs to find the problem: the face,
/// the corner, the vertex or the edge's two end points.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum MeshError {
    #[error(
        "face {face} corner {corner} refers to vertex {vertex}, but the mesh has {vertex_count} vertices"
    )]
    IndexOutOfRange {
        face: usize,
        corner: usize,
        vertex: u32,
        vertex_count: usize,
    },
    #[error("face {face} repeats vertex {vertex} (degenerate triangle)")]
    DegenerateFace { face: usize, vertex: u32 },
    #[error("edge ({a}, {b}) is shared by {faces} faces (non-manifold edge)")]
    NonManifoldEdge { a: u32, b: u32, faces: usize },
    #[error(
        "edge ({a}, {b}) is traversed in the same direction by faces {face_a} and {face_b} (inconsistent orientation)"
    )]
    InconsistentOrientation {
        a: u32,
        b: u32,
        face_a: usize,
        face_b: usize,
    },
    #[error("vertex {vertex} joins more than one fan of faces (non-manifold vertex)")]
    NonManifoldVertex { vertex: u32 },
    #[error("corner {corner}: opposite link is broken ({detail})")]
    BrokenOpposite { corner: usize, detail: String },
    #[error("vertex {vertex}: its corner link is broken ({detail})")]
    BrokenVertexCorner { vertex: u32, detail: String },
    #[error("vertex {vertex} is alive but no face uses it (isolated vertex)")]
    IsolatedVertex { vertex: u32 },
    #[error("live face {face} uses dead vertex {vertex}")]
    DeadVertexInFace { face: usize, vertex: u32 },
    #[error("vertex {vertex} has a non-finite position {position:?}")]
    NonFinitePosition { vertex: u32, position: [f32; 3] },
    #[error(
        "vertex {vertex} has coordinate {value} beyond the supported range ±{limit:e} (distances would overflow)"
    )]
    CoordinateOutOfRange { vertex: u32, value: f32, limit: f32 },
    #[error("vertex {vertex} has a non-finite {attribute}")]
    NonFiniteAttribute {
        vertex: u32,
        attribute: &'static str,
    },
    #[error(
        "face {face} is on layer {face_layer} but its vertex {vertex} is on layer {vertex_layer}"
    )]
    LayerMismatch {
        face: usize,
        vertex: u32,
        face_layer: u32,
        vertex_layer: u32,
    },
    #[error("face {face} is on layer {layer}, but only {layer_count} layers are named")]
    LayerOutOfRange {
        face: usize,
        layer: u32,
        layer_count: usize,
    },
    #[error("attribute `{attribute}` has {len} entries, expected {expected}")]
    AttributeLength {
        attribute: &'static str,
        len: usize,
        expected: usize,
    },
    #[error("the mesh has more than {limit} {what}; indices are 32-bit")]
    TooLarge { what: &'static str, limit: usize },
}
