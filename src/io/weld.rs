//! A soup built triangle by triangle from formats that store each triangle's points on their
//! own (STL, glTF's split vertices): points at identical positions within a layer are welded, by
//! bit pattern, as OBJ's are.

use glam::Vec3;
use rustc_hash::FxHashMap;

use super::import::{ImportReport, Parsed};
use crate::mesh::{Brdf, LayerId, Soup};

/// Welding identity of a point: its bits, with -0 folded into +0 (OBJ's welder uses it too).
pub(super) fn weld_key(p: Vec3) -> [u32; 3] {
    (p + Vec3::ZERO).to_array().map(f32::to_bits)
}

/// Builds a soup from triangles, welding each layer's points; each welded point keeps the BRDF
/// of its first triangle, where the format gives one.
#[derive(Default)]
pub(super) struct SoupBuilder {
    pub soup: Soup,
    pub layer_names: Vec<String>,
    pub report: ImportReport,
    /// Each point's BRDF, when some triangle brought one.
    brdfs: Vec<Option<Brdf>>,
    /// Each layer's points by bit pattern.
    welds: Vec<FxHashMap<[u32; 3], u32>>,
}

impl SoupBuilder {
    /// Starts a layer; its triangles follow.
    pub fn layer(&mut self, name: String) -> LayerId {
        self.layer_names.push(name);
        self.welds.push(FxHashMap::default());
        (self.layer_names.len() - 1) as LayerId
    }

    pub fn triangle(&mut self, corners: [Vec3; 3], layer: LayerId) {
        let face = corners.map(|p| self.point(p, None, layer));
        self.face(face, layer);
    }

    /// A face of points [`SoupBuilder::point`] gave.
    pub fn face(&mut self, face: [u32; 3], layer: LayerId) {
        self.soup.faces.push(face);
        self.soup.face_layers.push(layer);
    }

    /// A point of `layer` with its BRDF (the first one's where it welds): its number.
    pub fn point(&mut self, p: Vec3, brdf: Option<Brdf>, layer: LayerId) -> u32 {
        // NaN never welds.
        let key = (!p.is_nan()).then(|| weld_key(p));
        if let Some(&v) = key.and_then(|k| self.welds[layer as usize].get(&k)) {
            self.report.welded_vertices += 1;
            return v;
        }
        self.soup.positions.push(p);
        self.brdfs.push(brdf);
        let v = (self.soup.positions.len() - 1) as u32;
        if let Some(k) = key {
            self.welds[layer as usize].insert(k, v);
        }
        v
    }

    /// What the reader hands on: the soup, the layers, the BRDFs where any point had one
    /// ([`Brdf::CLAY`] for the others), and the report with the non-finite points counted.
    pub fn finish(mut self) -> Parsed {
        self.report.non_finite_vertices = self
            .soup
            .positions
            .iter()
            .filter(|p| !p.is_finite())
            .count();
        let brdfs = self
            .brdfs
            .iter()
            .any(Option::is_some)
            .then(|| self.brdfs.iter().map(|b| b.unwrap_or(Brdf::CLAY)).collect());
        Parsed {
            soup: self.soup,
            layer_names: self.layer_names,
            brdfs,
            report: self.report,
            ..Parsed::default()
        }
    }
}
