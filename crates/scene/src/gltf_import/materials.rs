//! A glTF material's factors as the metallic-roughness model, and the textures it names (none of
//! which is read).

use glam::Vec3;

use crate::{Brdf, Material, SceneError};

/// A glTF material as the metallic-roughness model ([`Brdf::Ggx`]): its base colour, metallic,
/// roughness and emissive factors (times `KHR_materials_emissive_strength`), and with
/// `alphaMode: BLEND` its base colour alpha as the opacity (OPAQUE and MASK are opaque: an alpha
/// test without textures passes every fragment). Factors out of range are an error naming the
/// material (`at`) and the field.
pub(super) fn material(m: &gltf::Material<'_>, at: &str) -> Result<Material, SceneError> {
    let pbr = m.pbr_metallic_roughness();
    let c = pbr.base_color_factor();
    let opacity = if m.alpha_mode() == gltf::material::AlphaMode::Blend {
        c[3]
    } else {
        1.0
    };
    if !(0.0..=1.0).contains(&c[3]) {
        return Err(SceneError::invalid(
            format!("{at}.pbrMetallicRoughness.baseColorFactor[3]"),
            c[3],
            "a value in [0, 1]",
        ));
    }
    let emissive = Vec3::from(m.emissive_factor()) * m.emissive_strength().unwrap_or(1.0);
    let material = Material {
        base_color: Vec3::new(c[0], c[1], c[2]),
        brdf: Brdf::Ggx {
            metallic: pbr.metallic_factor(),
            roughness: pbr.roughness_factor(),
        },
        opacity,
        emissive,
    };
    material.validate(at).map_err(|e| match e {
        // The glTF names of the fields.
        SceneError::InvalidValue {
            field,
            value,
            accepted,
        } => SceneError::InvalidValue {
            field: field
                .replace(".brdf.metallic", ".pbrMetallicRoughness.metallicFactor")
                .replace(".brdf.roughness", ".pbrMetallicRoughness.roughnessFactor")
                .replace(".base_color", ".pbrMetallicRoughness.baseColorFactor")
                .replace(".emissive", ".emissiveFactor"),
            value,
            accepted,
        },
        e => e,
    })?;
    Ok(material)
}

/// The textures a material names, none of which is read.
pub(super) fn textures(m: &gltf::Material<'_>) -> usize {
    let pbr = m.pbr_metallic_roughness();
    [
        pbr.base_color_texture().is_some(),
        pbr.metallic_roughness_texture().is_some(),
        m.normal_texture().is_some(),
        m.occlusion_texture().is_some(),
        m.emissive_texture().is_some(),
    ]
    .into_iter()
    .filter(|&t| t)
    .count()
}
