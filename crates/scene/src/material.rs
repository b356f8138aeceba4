//! Materials: a base colour, an opacity, an emission and one of the material models
//! ([`Brdf`]), with only the parameters that model reads. The models themselves, in f64, are in
//! [`crate::brdf`]; their WGSL twin is `shaders/common/brdf.wgsl`.
//!
//! [`Model`] names a model without its parameters: the experiments' `materials` list, which
//! gives a scene's surfaces several models at once ([`assign_models`]).

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::{Primitive, SceneError};

/// A material model and its parameters (each in [0, 1]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Brdf {
    /// Lambert plus a normalised Blinn-Phong lobe of exponent [`crate::light::SHININESS`],
    /// weighted by `specular`.
    BlinnPhong {
        /// Weight of the Blinn-Phong lobe.
        specular: f32,
    },
    /// glTF 2.0's metallic-roughness model: GGX (Trowbridge-Reitz) distribution, Smith
    /// height-correlated visibility, Schlick Fresnel with `F0 = mix(0.04, base_colour,
    /// metallic)`, and a Lambertian diffuse of `base_colour * (1 - metallic)` weighted by
    /// `1 - F`.
    Ggx {
        /// Metalness.
        metallic: f32,
        /// Perceptual roughness (alpha = roughness^2), at least [`crate::brdf::MIN_ROUGHNESS`]
        /// where evaluated.
        roughness: f32,
    },
    /// Cloth: Lambert plus a sheen lobe, Estevez and Kulla's "Charlie" distribution with
    /// Neubelt and Pettineo's visibility (as Filament's cloth model).
    Sheen {
        /// Perceptual roughness of the sheen lobe.
        roughness: f32,
        /// Sheen colour (linear RGB).
        sheen: Vec3,
    },
    /// A clear coat over [`Brdf::Ggx`]: an isotropic GGX layer of F0 0.04 and its own roughness
    /// whose Fresnel weight `coat * F` takes the same share off the base layer.
    ClearCoat {
        /// Base layer metalness.
        metallic: f32,
        /// Base layer perceptual roughness.
        roughness: f32,
        /// Strength of the coat.
        coat: f32,
        /// The coat's perceptual roughness.
        coat_roughness: f32,
    },
    /// Wrapped diffuse (foliage, skin-like): `base_colour / pi * clamp((n.l + w) / (1 + w)^2,
    /// 0, 1)` in place of the cosine, so light reaches past the terminator; it conserves energy
    /// for every `w` (the white furnace integral is 1).
    Wrap {
        /// How far the light wraps, `w`.
        wrap: f32,
    },
}

/// A material model's name, without its parameters.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub enum Model {
    /// [`Brdf::BlinnPhong`].
    BlinnPhong,
    /// [`Brdf::Ggx`].
    Ggx,
    /// [`Brdf::Sheen`].
    Sheen,
    /// [`Brdf::ClearCoat`].
    ClearCoat,
    /// [`Brdf::Wrap`].
    Wrap,
}

impl Model {
    /// Every model, in the order of their ids ([`Model::id`]).
    pub const ALL: [Model; 5] = [
        Model::BlinnPhong,
        Model::Ggx,
        Model::Sheen,
        Model::ClearCoat,
        Model::Wrap,
    ];

    /// Its id on the GPU (`Material.model`; `MODEL_*` in the WGSL prelude).
    pub fn id(self) -> u32 {
        self as u32
    }

    /// Its name in cell names and result columns.
    pub fn name(self) -> &'static str {
        match self {
            Model::BlinnPhong => "blinn_phong",
            Model::Ggx => "ggx",
            Model::Sheen => "sheen",
            Model::ClearCoat => "clear_coat",
            Model::Wrap => "wrap",
        }
    }
}

impl Brdf {
    /// Its model.
    pub fn model(&self) -> Model {
        match self {
            Brdf::BlinnPhong { .. } => Model::BlinnPhong,
            Brdf::Ggx { .. } => Model::Ggx,
            Brdf::Sheen { .. } => Model::Sheen,
            Brdf::ClearCoat { .. } => Model::ClearCoat,
            Brdf::Wrap { .. } => Model::Wrap,
        }
    }

    /// Its parameters as the GPU holds them (`Material.params`).
    pub fn params(&self) -> [f32; 4] {
        match *self {
            Brdf::BlinnPhong { specular } => [specular, 0.0, 0.0, 0.0],
            Brdf::Ggx {
                metallic,
                roughness,
            } => [metallic, roughness, 0.0, 0.0],
            Brdf::Sheen { roughness, sheen } => [sheen.x, sheen.y, sheen.z, roughness],
            Brdf::ClearCoat {
                metallic,
                roughness,
                coat,
                coat_roughness,
            } => [metallic, roughness, coat, coat_roughness],
            Brdf::Wrap { wrap } => [wrap, 0.0, 0.0, 0.0],
        }
    }

    /// Each parameter with its name, for validation and messages.
    fn named(&self) -> Vec<(&'static str, f32)> {
        match *self {
            Brdf::BlinnPhong { specular } => vec![("specular", specular)],
            Brdf::Ggx {
                metallic,
                roughness,
            } => vec![("metallic", metallic), ("roughness", roughness)],
            Brdf::Sheen { roughness, sheen } => vec![
                ("roughness", roughness),
                ("sheen.x", sheen.x),
                ("sheen.y", sheen.y),
                ("sheen.z", sheen.z),
            ],
            Brdf::ClearCoat {
                metallic,
                roughness,
                coat,
                coat_roughness,
            } => vec![
                ("metallic", metallic),
                ("roughness", roughness),
                ("coat", coat),
                ("coat_roughness", coat_roughness),
            ],
            Brdf::Wrap { wrap } => vec![("wrap", wrap)],
        }
    }
}

/// A material: what the shading model reads, and its opacity.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// Linear RGB base colour (albedo; a metal's specular colour), each channel in [0, 1].
    pub base_color: Vec3,
    /// The material model and its parameters.
    pub brdf: Brdf,
    /// Opacity in [0, 1]: 1 is opaque; below 1 the surface is transparent, drawn after the
    /// opaque ones, sorted back to front and blended over them with this weight (glTF's
    /// `alphaMode: BLEND` and base colour alpha).
    #[serde(default = "opaque")]
    pub opacity: f32,
    /// Emitted radiance (linear RGB, finite and at least 0), added once a pixel to what the
    /// lights reflect (glTF's `emissiveFactor` times its emissive strength).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub emissive: Vec3,
}

fn opaque() -> f32 {
    1.0
}

fn is_zero(v: &Vec3) -> bool {
    *v == Vec3::ZERO
}

impl Material {
    /// An opaque Blinn-Phong material with the given albedo and specular weight.
    pub const fn new(base_color: Vec3, specular: f32) -> Self {
        Self::transparent(base_color, specular, 1.0)
    }

    /// A Blinn-Phong material of opacity `opacity` (below 1: transparent; 1: opaque).
    pub const fn transparent(base_color: Vec3, specular: f32, opacity: f32) -> Self {
        Self {
            base_color,
            brdf: Brdf::BlinnPhong { specular },
            opacity,
            emissive: Vec3::ZERO,
        }
    }

    /// Whether surfaces of this material are transparent (opacity below 1).
    pub fn is_transparent(&self) -> bool {
        self.opacity < 1.0
    }

    /// The same surface under material model `model`, its parameters carried over where the
    /// models share them: a Blinn-Phong weight `s` and a roughness `r` correspond as
    /// `r = clamp(1 - 2 s, 0.1, 1)` (and `s = (1 - r) / 2` back, the glTF importer's former
    /// mapping); metalness carries over between GGX and the clear coat and is 0 otherwise; the
    /// sheen colour is the square root of the base colour (Filament's default); the coat has
    /// strength 1 and roughness 0.1; the wrap is 0.5.
    pub fn with_model(&self, model: Model) -> Material {
        let (metallic, roughness) = match self.brdf {
            Brdf::BlinnPhong { specular } => (0.0, (1.0 - 2.0 * specular).clamp(0.1, 1.0)),
            Brdf::Ggx {
                metallic,
                roughness,
            }
            | Brdf::ClearCoat {
                metallic,
                roughness,
                ..
            } => (metallic, roughness),
            Brdf::Sheen { roughness, .. } => (0.0, roughness),
            Brdf::Wrap { .. } => (0.0, 1.0),
        };
        let brdf = match model {
            Model::BlinnPhong => Brdf::BlinnPhong {
                specular: 0.5 * (1.0 - roughness),
            },
            Model::Ggx => Brdf::Ggx {
                metallic,
                roughness,
            },
            Model::Sheen => Brdf::Sheen {
                roughness,
                sheen: self.base_color.map(f32::sqrt),
            },
            Model::ClearCoat => Brdf::ClearCoat {
                metallic,
                roughness,
                coat: 1.0,
                coat_roughness: 0.1,
            },
            Model::Wrap => Brdf::Wrap { wrap: 0.5 },
        };
        if brdf.model() == self.brdf.model() {
            return *self;
        }
        Material { brdf, ..*self }
    }

    /// Checks every value; the error names `at` (such as `materials[3]`), the field and the
    /// value, and the accepted range.
    pub fn validate(&self, at: &str) -> Result<(), SceneError> {
        let unit = |field: String, v: f32| {
            if (0.0..=1.0).contains(&v) {
                Ok(())
            } else {
                Err(SceneError::invalid(field, v, "a value in [0, 1]"))
            }
        };
        for (c, v) in ["x", "y", "z"].iter().zip(self.base_color.to_array()) {
            unit(format!("{at}.base_color.{c}"), v)?;
        }
        for (name, v) in self.brdf.named() {
            unit(format!("{at}.brdf.{name}"), v)?;
        }
        if !(0.0..=1.0).contains(&self.opacity) {
            return Err(SceneError::invalid(
                format!("{at}.opacity"),
                self.opacity,
                "an opacity in [0, 1] (1: opaque)",
            ));
        }
        if !(self.emissive.is_finite() && self.emissive.min_element() >= 0.0) {
            return Err(SceneError::invalid(
                format!("{at}.emissive"),
                format!("{:?}", self.emissive),
                "finite channels of at least 0",
            ));
        }
        Ok(())
    }
}

/// Gives a scene's surfaces the material models `models`, in turns: the triangles of each
/// primitive, a pair at a time (so that a quad keeps one model), take the models in order,
/// starting at the primitive's index, so neighbouring objects and the faces of one object
/// differ. Each material becomes one material a model (material `k * models.len() + j` is
/// material `k` under model `j`, [`Material::with_model`]), and each primitive one a model.
/// An empty `models` changes nothing; one model gives every surface that model.
pub fn assign_models(
    primitives: &[Primitive],
    materials: &[Material],
    models: &[Model],
) -> (Vec<Primitive>, Vec<Material>) {
    if models.is_empty() {
        return (primitives.to_vec(), materials.to_vec());
    }
    let n = models.len();
    let out_materials = materials
        .iter()
        .flat_map(|m| models.iter().map(|&model| m.with_model(model)))
        .collect();
    let mut out = Vec::new();
    for (k, p) in primitives.iter().enumerate() {
        for j in 0..n {
            let mut remap = vec![u32::MAX; p.positions.len()];
            let mut q = Primitive {
                material: p.material * n as u32 + j as u32,
                ..Primitive::default()
            };
            for (t, tri) in p.indices.chunks(3).enumerate() {
                if (t / 2 + k) % n != j {
                    continue;
                }
                for &i in tri {
                    if remap[i as usize] == u32::MAX {
                        remap[i as usize] = q.positions.len() as u32;
                        q.positions.push(p.positions[i as usize]);
                        q.normals.push(p.normals[i as usize]);
                    }
                    q.indices.push(remap[i as usize]);
                }
            }
            if !q.indices.is_empty() {
                out.push(q);
            }
        }
    }
    (out, out_materials)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An opacity outside [0, 1] is an error naming the material, the value and the range;
    /// a material written without one is opaque.
    #[test]
    fn opacity_outside_zero_to_one_is_rejected() {
        let mut scene = crate::procedural::ProceduralScene::from_name("pillars")
            .unwrap()
            .build()
            .unwrap();
        for bad in [1.5, -0.1, f32::NAN] {
            scene.materials[1].opacity = bad;
            let e = scene.validate().unwrap_err().to_string();
            assert!(
                e.contains("materials[1].opacity") && e.contains("[0, 1]"),
                "{bad}: {e}"
            );
        }
        let m: Material =
            ron::from_str("(base_color: (0.5, 0.5, 0.5), brdf: BlinnPhong(specular: 0.1))")
                .unwrap();
        assert_eq!(m.opacity, 1.0);
        assert!(!m.is_transparent());
    }

    /// Parameters out of range (negative, above 1, NaN) name the material and the field.
    #[test]
    fn parameters_out_of_range_name_the_field() {
        for (brdf, field) in [
            (
                Brdf::Ggx {
                    metallic: 0.5,
                    roughness: -0.1,
                },
                "materials[2].brdf.roughness = -0.1",
            ),
            (
                Brdf::Ggx {
                    metallic: 1.5,
                    roughness: 0.5,
                },
                "materials[2].brdf.metallic = 1.5",
            ),
            (
                Brdf::ClearCoat {
                    metallic: 0.0,
                    roughness: 0.5,
                    coat: f32::NAN,
                    coat_roughness: 0.1,
                },
                "materials[2].brdf.coat = NaN",
            ),
            (Brdf::Wrap { wrap: 2.0 }, "materials[2].brdf.wrap = 2"),
        ] {
            let m = Material {
                brdf,
                ..Material::new(Vec3::splat(0.5), 0.0)
            };
            let e = m.validate("materials[2]").unwrap_err().to_string();
            assert!(e.contains(field) && e.contains("[0, 1]"), "{e}");
        }
        let m = Material {
            emissive: Vec3::new(0.0, -1.0, 0.0),
            ..Material::new(Vec3::splat(0.5), 0.0)
        };
        assert!(
            m.validate("materials[0]")
                .unwrap_err()
                .to_string()
                .contains("materials[0].emissive")
        );
    }

    /// An unknown model in RON is an error that lists the valid ones.
    #[test]
    fn unknown_model_lists_the_valid_ones() {
        let e = ron::from_str::<Vec<Model>>("[Ggx, Phong]")
            .unwrap_err()
            .to_string();
        for name in ["BlinnPhong", "Ggx", "Sheen", "ClearCoat", "Wrap"] {
            assert!(e.contains(name), "{e}");
        }
    }

    /// Every triangle keeps its place and takes one model in turn; materials multiply.
    #[test]
    fn models_are_assigned_in_turns_and_cover_every_triangle() {
        let scene = crate::procedural::ProceduralScene::from_name("cis5650")
            .unwrap()
            .build()
            .unwrap();
        let (prims, mats) = assign_models(&scene.primitives, &scene.materials, &Model::ALL);
        assert_eq!(mats.len(), scene.materials.len() * 5);
        let count = |ps: &[Primitive]| ps.iter().map(|p| p.indices.len()).sum::<usize>();
        assert_eq!(count(&prims), count(&scene.primitives));
        for model in Model::ALL {
            let n = prims
                .iter()
                .filter(|p| mats[p.material as usize].brdf.model() == model)
                .map(|p| p.indices.len() / 3)
                .sum::<usize>();
            assert!(n > 0, "{model:?} has no triangle");
        }
        for (k, m) in scene.materials.iter().enumerate() {
            assert_eq!(mats[k * 5].opacity, m.opacity);
            assert_eq!(mats[k * 5 + 1].brdf.model(), Model::Ggx);
        }
        let (same, _) = assign_models(&scene.primitives, &scene.materials, &[]);
        assert_eq!(same, scene.primitives);
    }
}
