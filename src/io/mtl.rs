//! Wavefront material libraries: a layer's BRDF written as one material, and a material read
//! back as a BRDF, so that an OBJ slayer wrote comes back with its colours.

use std::io::{self, Write};

use crate::mesh::{Brdf, INVALID, LayerId, Mesh};

/// The BRDF a material describes: `Kd` the diffuse albedo, `Ks` the specular, the roughness
/// from `Pr` (the PBR extension's roughness, which is our linearized roughness) or else from
/// the Blinn–Phong exponent `Ns`; what the material leaves out is [`Brdf::CLAY`]'s. Values are
/// clamped to [0, 1].
pub fn material_brdf(material: &tobj::Material) -> Brdf {
    let clay = Brdf::CLAY;
    let pr = material
        .unknown_param
        .get("Pr")
        .and_then(|v| v.trim().parse::<f32>().ok());
    let roughness = pr
        .or(material.shininess.map(roughness_of_exponent))
        .unwrap_or(clay.roughness);
    Brdf::new(
        material.diffuse.unwrap_or(clay.diffuse),
        material.specular.unwrap_or(clay.specular),
        roughness,
    )
    .clamped()
}

/// The inverse of [`crate::mesh::blinn_exponent`] (`e = 2/α² − 2`, `α = r²`): exact above the
/// smallest slope that mapping keeps.
fn roughness_of_exponent(exponent: f32) -> f32 {
    if exponent.is_nan() || exponent < 0.0 {
        return 1.0;
    }
    (2.0 / (exponent + 2.0)).sqrt().sqrt()
}

/// What a material holds that a BRDF does not keep, one item each.
pub fn material_not_kept(material: &tobj::Material) -> Vec<String> {
    let name = &material.name;
    let mut items: Vec<String> = [
        &material.diffuse_texture,
        &material.specular_texture,
        &material.normal_texture,
        &material.ambient_texture,
        &material.shininess_texture,
        &material.dissolve_texture,
    ]
    .into_iter()
    .flatten()
    .map(|map| {
        format!(
            "texture map `{}` of material `{name}`",
            crate::files::escape(map)
        )
    })
    .collect();
    if material.dissolve.is_some_and(|d| d < 1.0) {
        items.push(format!("opacity (`d`) of material `{name}`"));
    }
    items
}

/// Each layer with faces, with its material: the mean BRDF of its live vertices. The
/// parametrization is linear, so the mean is the layer's average material; a layer nobody has
/// painted gets exactly its default (generated scenes give each layer a preset).
pub fn layer_materials(mesh: &Mesh) -> Vec<(LayerId, String, Brdf)> {
    let mut sums = vec![[0f64; 7]; mesh.layer_count()];
    let mut counts = vec![0usize; mesh.layer_count()];
    let mut has_faces = vec![false; mesh.layer_count()];
    for (t, &l) in mesh.faces().iter().zip(mesh.face_layers()) {
        if t[0] != INVALID {
            has_faces[l as usize] = true;
        }
    }
    for (v, brdf) in mesh.brdfs().iter().enumerate() {
        if !mesh.is_vertex_live(v as u32) {
            continue;
        }
        let layer = mesh.vertex_layers()[v] as usize;
        for (sum, value) in sums[layer].iter_mut().zip(brdf.as_array()) {
            *sum += value as f64;
        }
        counts[layer] += 1;
    }
    (0..mesh.layer_count())
        .filter(|&l| has_faces[l])
        .map(|l| {
            let n = counts[l].max(1) as f64;
            let mean = Brdf::from_array(sums[l].map(|s| (s / n) as f32));
            (l as LayerId, sanitize_name(&mesh.layer_names()[l]), mean)
        })
        .collect()
}

/// Writes a Wavefront material library with one `newmtl` per layer ([`layer_materials`]):
/// `Kd` the diffuse albedo, `Ks` the specular albedo, `Ns` the Blinn–Phong exponent of the
/// linearized roughness ([`crate::mesh::blinn_exponent`]) and `Pr` the roughness itself (the
/// PBR extension's key, read back exactly by [`material_brdf`]).
pub fn write_mtl(mesh: &Mesh, out: &mut impl Write) -> io::Result<()> {
    writeln!(out, "# slayer materials: one per layer")?;
    for (_, name, brdf) in layer_materials(mesh) {
        writeln!(out)?;
        writeln!(out, "newmtl {name}")?;
        if let Some(preset) = crate::material::PRESETS
            .iter()
            .find(|m| close(&m.brdf, &brdf))
        {
            writeln!(out, "# preset {}", preset.name)?;
        }
        writeln!(out, "# linearized roughness {}", brdf.roughness)?;
        let [r, g, b] = brdf.diffuse;
        writeln!(out, "Kd {r} {g} {b}")?;
        let [r, g, b] = brdf.specular;
        writeln!(out, "Ks {r} {g} {b}")?;
        writeln!(out, "Ns {}", brdf.blinn_exponent())?;
        writeln!(out, "Pr {}", brdf.roughness)?;
        writeln!(out, "illum 2")?;
    }
    Ok(())
}

fn close(a: &Brdf, b: &Brdf) -> bool {
    a.as_array()
        .iter()
        .zip(b.as_array())
        .all(|(x, y)| (x - y).abs() <= 1e-5)
}

/// OBJ names end at whitespace.
pub(super) fn sanitize_name(name: &str) -> String {
    let cleaned: String = name
        .chars()
        .map(|c| if c.is_whitespace() { '_' } else { c })
        .collect();
    if cleaned.is_empty() {
        "layer".into()
    } else {
        cleaned
    }
}
