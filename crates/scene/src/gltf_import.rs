//! glTF 2.0 import (`.gltf` with external or embedded buffers, and `.glb`), with
//! `KHR_lights_punctual` lights.
//!
//! What is read, and nothing else: triangle geometry (`TRIANGLES`, `TRIANGLE_STRIP` and
//! `TRIANGLE_FAN`, converted to lists; points and lines are skipped and counted), positions,
//! normals (computed from faces where absent), node transforms baked into world space, each
//! material's factors as glTF's metallic-roughness model ([`Brdf::Ggx`]: base colour, metallic,
//! roughness, emissive times `KHR_materials_emissive_strength`, and with `alphaMode: BLEND` the
//! base colour's alpha as opacity), the first camera of the scene if any, and point and spot lights (directional
//! lights have no position or radius and are skipped and counted). A light without a `range`
//! gets the radius at which its inverse-square irradiance falls to
//! [`GltfOptions::light_threshold`]. A primitive without a material gets glTF's default
//! material (white, metallic 1, roughness 1).
//!
//! Not read: textures (base colour, metallic-roughness, normal, occlusion, emissive: their
//! count is [`ImportReport::unread_textures`], which the CLI prints as a warning), vertex
//! colours and texture coordinates, `alphaCutoff` (MASK is opaque), `doubleSided` (every
//! surface is two-sided) and the material extensions other than emissive strength (clear coat,
//! sheen, transmission, specular, IOR, volume: the procedural scenes' `materials` option has
//! clear coat and sheen models of its own). A factor out of range (negative roughness, metallic
//! above 1, a base colour channel above 1) is an error naming the material and the field.
//!
//! Malformed files give a [`SceneError::Gltf`] naming the file and the problem: schema errors,
//! missing buffers, indices out of range, attribute arrays of unequal length, non-finite
//! values, and node cycles. Nothing in a file can make the importer panic.

use std::path::Path;

use glam::{Mat3, Mat4, Vec3};

use crate::{
    Aabb, Brdf, Camera, Light, LightKind, Material, Primitive, Projection, Scene, SceneError,
};

mod materials;
use materials::{material, textures};

/// Options of the importer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GltfOptions {
    /// Irradiance threshold that sets the radius of lights without a `range`.
    pub light_threshold: f32,
}

impl Default for GltfOptions {
    fn default() -> Self {
        Self {
            light_threshold: 0.01,
        }
    }
}

/// What the importer skipped (it never skips silently).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ImportReport {
    /// Point and line primitives skipped.
    pub skipped_primitives: usize,
    /// Directional lights skipped.
    pub skipped_directional_lights: usize,
    /// Textures that materials name, none of which is read (their factors are).
    pub unread_textures: usize,
    /// Whether the file has no camera node, so that the camera frames the scene's box.
    pub framed_camera: bool,
}

/// Deepest node hierarchy accepted; deeper files are reported as malformed.
const MAX_NODE_DEPTH: usize = 256;

/// Imports a glTF file into a [`Scene`] (compressed where its name ends in `.xz`, as the
/// vendored scenes are: [`crate::real`]).
pub fn load(path: &Path, options: &GltfOptions) -> Result<(Scene, ImportReport), SceneError> {
    if !path.is_file() {
        return Err(SceneError::Gltf {
            path: path.to_path_buf(),
            problem: "no such file".into(),
        });
    }
    let bytes = std::fs::read(path).map_err(|e| SceneError::Gltf {
        path: path.to_path_buf(),
        problem: format!("cannot read: {e}"),
    })?;
    load_bytes(path, &bytes, options)
}

/// [`load`] of the file `path` already read as `bytes`; where `path` ends in `.xz` the bytes
/// are xz-compressed (a `.glb.xz`, or a `.gltf.xz` whose other files lie beside it).
pub fn load_bytes(
    path: &Path,
    bytes: &[u8],
    options: &GltfOptions,
) -> Result<(Scene, ImportReport), SceneError> {
    let err = |problem: String| SceneError::Gltf {
        path: path.to_path_buf(),
        problem,
    };
    let decompressed;
    let bytes = if path.extension().is_some_and(|x| x == "xz") {
        let mut out = Vec::new();
        lzma_rs::xz_decompress(&mut std::io::BufReader::new(bytes), &mut out)
            .map_err(|e| err(format!("cannot decompress (xz): {e}")))?;
        decompressed = out;
        &decompressed[..]
    } else {
        bytes
    };
    let raw = gltf::Gltf::from_slice_without_validation(bytes)
        .map_err(|e| err(format!("cannot parse: {e}")))?;
    let root = raw.document.into_json();
    validate_schema(&root)
        .map_err(|problem| err(format!("cannot parse: invalid glTF: {problem}")))?;
    let gltf = gltf::Gltf {
        document: gltf::Document::from_json_without_validation(root),
        blob: raw.blob,
    };
    let base = path.parent();
    let buffers = gltf::import_buffers(&gltf.document, base, gltf.blob.clone())
        .map_err(|e| err(format!("cannot load buffers: {e}")))?;
    let doc = &gltf.document;
    let scene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or_else(|| err("the file has no scene".into()))?;

    let mut out = Importer {
        buffers: &buffers,
        prims: Vec::new(),
        lights: Vec::new(),
        camera: None,
        report: ImportReport::default(),
        options,
    };
    let mut path_stack = Vec::new();
    for node in scene.nodes() {
        out.visit(&node, Mat4::IDENTITY, &mut path_stack)
            .map_err(err)?;
    }

    let mut materials = Vec::new();
    for (i, m) in doc.materials().enumerate() {
        let at = match m.name() {
            Some(name) => format!("materials[{i}] ({name:?})"),
            None => format!("materials[{i}]"),
        };
        materials.push(material(&m, &at).map_err(|e| err(e.to_string()))?);
        out.report.unread_textures += textures(&m);
    }
    // Primitives without a material use the glTF default material, appended last.
    let default_material = materials.len() as u32;
    materials.push(Material {
        base_color: Vec3::ONE,
        brdf: Brdf::Ggx {
            metallic: 1.0,
            roughness: 1.0,
        },
        opacity: 1.0,
        emissive: Vec3::ZERO,
    });
    let primitives: Vec<Primitive> = out
        .prims
        .into_iter()
        .map(|(mut p, m)| {
            p.material = m.map_or(default_material, |m| m as u32);
            p
        })
        .collect();
    if primitives.is_empty() {
        return Err(err("the scene holds no triangle geometry".into()));
    }
    let bounds = primitives
        .iter()
        .flat_map(|p| p.positions.iter())
        .fold(Aabb::EMPTY, |b, &p| b.union_point(p));
    out.report.framed_camera = out.camera.is_none();
    let camera = out.camera.unwrap_or_else(|| framing_camera(bounds));
    // `sponza.glb.xz` is `sponza`, as `sponza.glb` is.
    let stem_of = if path.extension().is_some_and(|x| x == "xz") {
        path.with_extension("")
    } else {
        path.to_path_buf()
    };
    let name = stem_of
        .file_stem()
        .map_or_else(|| "gltf".into(), |s| s.to_string_lossy().into_owned());
    let result = Scene {
        name,
        primitives,
        materials,
        lights: out.lights,
        camera,
        light_bounds: bounds,
    };
    result.validate().map_err(|e| err(e.to_string()))?;
    Ok((result, out.report))
}

/// The glTF schema validation, less one rule: accessor `min`/`max` are required on POSITION by
/// the specification but omitted by many real exporters, and nothing here reads them (bounds are
/// recomputed, and non-finite positions are rejected when read), so their absence is tolerated.
fn validate_schema(root: &gltf::json::Root) -> Result<(), String> {
    use gltf::json::validation::{Error, Validate};
    // gltf-json 1.4.1's validator indexes `accessors` with a primitive's POSITION accessor
    // before checking that index's range, and panics on an out-of-range one (found by
    // tests/fuzz.rs); check every primitive's accessor indices first.
    let accessors = root.accessors.len();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (k, prim) in mesh.primitives.iter().enumerate() {
            let indices = prim
                .attributes
                .values()
                .map(|a| a.value())
                .chain(prim.indices.as_ref().map(|a| a.value()));
            for (n, a) in indices.enumerate() {
                if a >= accessors {
                    return Err(format!(
                        "meshes[{m}].primitives[{k}]: accessor index {a} out of range (the file has {accessors}) (reference {n})"
                    ));
                }
            }
        }
    }
    let mut problems = Vec::new();
    root.validate(root, gltf::json::Path::new, &mut |path, error| {
        let path = path();
        let bound = path.as_str().ends_with(".min") || path.as_str().ends_with(".max");
        if !(bound && matches!(error, Error::Missing)) {
            problems.push(format!("{path}: {error}"));
        }
    });
    if problems.is_empty() {
        Ok(())
    } else {
        Err(problems.join("; "))
    }
}

/// A camera outside the bounds looking at their centre.
fn framing_camera(b: Aabb) -> Camera {
    let c = b.center();
    let r = (b.extent().length() * 0.5).max(1e-3);
    let eye = c + Vec3::new(0.6, 0.45, 1.0).normalize() * r * 2.2;
    Camera::perspective(eye, c, 50.0, r * 0.01, r * 6.0)
}

struct Importer<'a> {
    buffers: &'a [gltf::buffer::Data],
    prims: Vec<(Primitive, Option<usize>)>,
    lights: Vec<Light>,
    camera: Option<Camera>,
    report: ImportReport,
    options: &'a GltfOptions,
}

impl Importer<'_> {
    fn visit(
        &mut self,
        node: &gltf::Node<'_>,
        parent: Mat4,
        stack: &mut Vec<usize>,
    ) -> Result<(), String> {
        if stack.contains(&node.index()) {
            return Err(format!(
                "node {} is its own ancestor (the node hierarchy has a cycle)",
                node.index()
            ));
        }
        if stack.len() >= MAX_NODE_DEPTH {
            return Err(format!("node hierarchy deeper than {MAX_NODE_DEPTH}"));
        }
        let local = Mat4::from_cols_array_2d(&node.transform().matrix());
        let world = parent * local;
        if !world.is_finite() {
            return Err(format!("node {} has a non-finite transform", node.index()));
        }
        stack.push(node.index());
        if let Some(mesh) = node.mesh() {
            for (k, prim) in mesh.primitives().enumerate() {
                let what = format!("mesh {} primitive {k}", mesh.index());
                if let Some(p) = self
                    .primitive(&prim, world)
                    .map_err(|e| format!("{what}: {e}"))?
                {
                    self.prims.push((p, prim.material().index()));
                }
            }
        }
        if let Some(light) = node.light() {
            self.light(&light, world)
                .map_err(|e| format!("node {} light {}: {e}", node.index(), light.index()))?;
        }
        if let (None, Some(cam)) = (self.camera, node.camera()) {
            self.camera = camera(&cam, world);
        }
        for child in node.children() {
            self.visit(&child, world, stack)?;
        }
        stack.pop();
        Ok(())
    }

    fn primitive(
        &mut self,
        prim: &gltf::Primitive<'_>,
        world: Mat4,
    ) -> Result<Option<Primitive>, String> {
        use gltf::mesh::Mode;
        let mode = prim.mode();
        if !matches!(
            mode,
            Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
        ) {
            self.report.skipped_primitives += 1;
            return Ok(None);
        }
        let buffers = self.buffers;
        use gltf::accessor::{DataType, Dimensions};
        let pos = prim
            .get(&gltf::Semantic::Positions)
            .ok_or("has no POSITION attribute")?;
        check_accessor(
            &pos,
            buffers,
            "POSITION",
            Dimensions::Vec3,
            &[DataType::F32],
        )?;
        if let Some(n) = prim.get(&gltf::Semantic::Normals) {
            check_accessor(&n, buffers, "NORMAL", Dimensions::Vec3, &[DataType::F32])?;
        }
        if let Some(ix) = prim.indices() {
            check_accessor(
                &ix,
                buffers,
                "index",
                Dimensions::Scalar,
                &[DataType::U8, DataType::U16, DataType::U32],
            )?;
        }
        let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
        let positions: Vec<Vec3> = reader
            .read_positions()
            .ok_or("has no POSITION attribute (or its buffer data is missing)")?
            .map(Vec3::from)
            .collect();
        let expected = prim
            .get(&gltf::Semantic::Positions)
            .map_or(0, |a| a.count());
        if positions.len() != expected {
            return Err(format!(
                "POSITION accessor declares {expected} elements but its buffer holds {}",
                positions.len()
            ));
        }
        if let Some(p) = positions.iter().find(|p| !p.is_finite()) {
            return Err(format!("non-finite position {p:?}"));
        }
        let normals: Option<Vec<Vec3>> =
            reader.read_normals().map(|it| it.map(Vec3::from).collect());
        if let Some(n) = &normals {
            if n.len() != positions.len() {
                return Err(format!(
                    "{} normals for {} positions (attribute arrays of unequal length)",
                    n.len(),
                    positions.len()
                ));
            }
            if n.iter().any(|v| !v.is_finite()) {
                return Err("non-finite normal".into());
            }
        }
        let raw: Vec<u32> = match reader.read_indices() {
            Some(ix) => {
                let ix: Vec<u32> = ix.into_u32().collect();
                let declared = prim.indices().map_or(0, |a| a.count());
                if ix.len() != declared {
                    return Err(format!(
                        "index accessor declares {declared} elements but its buffer holds {}",
                        ix.len()
                    ));
                }
                if let Some(&bad) = ix.iter().find(|&&i| i as usize >= positions.len()) {
                    return Err(format!(
                        "index {bad} out of range for {} vertices",
                        positions.len()
                    ));
                }
                ix
            }
            None => (0..positions.len() as u32).collect(),
        };
        let indices = match mode {
            Mode::Triangles => {
                if !raw.len().is_multiple_of(3) {
                    return Err(format!(
                        "triangle list of {} vertices is not a multiple of 3 (truncated vertex array)",
                        raw.len()
                    ));
                }
                raw
            }
            Mode::TriangleStrip => (2..raw.len())
                .flat_map(|i| {
                    if i % 2 == 0 {
                        [raw[i - 2], raw[i - 1], raw[i]]
                    } else {
                        [raw[i - 1], raw[i - 2], raw[i]]
                    }
                })
                .collect(),
            _ => (2..raw.len())
                .flat_map(|i| [raw[0], raw[i - 1], raw[i]])
                .collect(),
        };
        let normal_from_local = Mat3::from_mat4(world).inverse().transpose();
        let world_pos: Vec<Vec3> = positions
            .iter()
            .map(|&p| world.transform_point3(p))
            .collect();
        let world_n: Vec<Vec3> = match normals {
            Some(n) => n
                .iter()
                .map(|&v| (normal_from_local * v).normalize_or(Vec3::Y))
                .collect(),
            None => face_normals(&world_pos, &indices),
        };
        Ok(Some(Primitive {
            positions: world_pos,
            normals: world_n,
            indices,
            material: 0,
        }))
    }

    fn light(
        &mut self,
        light: &gltf::khr_lights_punctual::Light<'_>,
        world: Mat4,
    ) -> Result<(), String> {
        use gltf::khr_lights_punctual::Kind;
        let color = Vec3::from(light.color());
        let intensity = light.intensity();
        let position = world.transform_point3(Vec3::ZERO);
        let direction = world.transform_vector3(-Vec3::Z).normalize_or(-Vec3::Z);
        let kind = match light.kind() {
            Kind::Directional => {
                self.report.skipped_directional_lights += 1;
                return Ok(());
            }
            Kind::Point => LightKind::Point,
            Kind::Spot {
                inner_cone_angle,
                outer_cone_angle,
            } => LightKind::Spot {
                direction,
                inner_angle: inner_cone_angle,
                outer_angle: outer_cone_angle,
            },
        };
        let radius = light.range().unwrap_or_else(|| {
            (intensity * color.max_element() / self.options.light_threshold)
                .sqrt()
                .max(1e-3)
        });
        let l = Light {
            kind,
            position,
            radius,
            color,
            intensity,
        };
        l.validate(self.lights.len()).map_err(|e| e.to_string())?;
        self.lights.push(l);
        Ok(())
    }
}

fn camera(cam: &gltf::Camera<'_>, world: Mat4) -> Option<Camera> {
    let position = world.transform_point3(Vec3::ZERO);
    let target = position + world.transform_vector3(-Vec3::Z).normalize_or(-Vec3::Z);
    let up = world.transform_vector3(Vec3::Y).normalize_or(Vec3::Y);
    let projection = match cam.projection() {
        gltf::camera::Projection::Perspective(p) => Projection::Perspective {
            fov_y_deg: p.yfov().to_degrees(),
            near: p.znear(),
            far: p.zfar().unwrap_or(p.znear() * 1e4),
        },
        gltf::camera::Projection::Orthographic(o) => Projection::Orthographic {
            height: 2.0 * o.ymag(),
            near: o.znear(),
            far: o.zfar(),
        },
    };
    let c = Camera {
        position,
        target,
        up,
        projection,
    };
    c.validate().is_ok().then_some(c)
}

/// Checks an accessor before the `gltf` crate's reader touches it: its type, and that every
/// element lies inside its buffer view and the view inside its buffer. The reader itself asserts
/// and panics on such malformed data (found by tests/fuzz.rs).
fn check_accessor(
    acc: &gltf::Accessor<'_>,
    buffers: &[gltf::buffer::Data],
    what: &str,
    dims: gltf::accessor::Dimensions,
    types: &[gltf::accessor::DataType],
) -> Result<(), String> {
    let i = acc.index();
    if acc.dimensions() != dims || !types.contains(&acc.data_type()) {
        return Err(format!(
            "{what} accessor {i} holds {:?} {:?}; expected {dims:?} of {types:?}",
            acc.dimensions(),
            acc.data_type()
        ));
    }
    if acc.sparse().is_some() {
        return Err(format!(
            "{what} accessor {i} is sparse, which is not supported"
        ));
    }
    let view = acc
        .view()
        .ok_or_else(|| format!("{what} accessor {i} has no buffer view"))?;
    let elem = acc.size();
    let stride = view.stride().unwrap_or(elem);
    if stride < elem {
        return Err(format!(
            "{what} accessor {i}: byte stride {stride} is smaller than its element size {elem}"
        ));
    }
    let count = acc.count();
    let needed = if count == 0 {
        0
    } else {
        acc.offset() + stride * (count - 1) + elem
    };
    if needed > view.length() {
        return Err(format!(
            "{what} accessor {i} needs {needed} bytes but its buffer view has {}",
            view.length()
        ));
    }
    let buffer = buffers.get(view.buffer().index()).ok_or_else(|| {
        format!(
            "{what} accessor {i}: buffer {} is missing",
            view.buffer().index()
        )
    })?;
    if view.offset() + view.length() > buffer.0.len() {
        return Err(format!(
            "buffer view {} ends at byte {} but buffer {} has {}",
            view.index(),
            view.offset() + view.length(),
            view.buffer().index(),
            buffer.0.len()
        ));
    }
    Ok(())
}

fn face_normals(pos: &[Vec3], indices: &[u32]) -> Vec<Vec3> {
    let mut n = vec![Vec3::ZERO; pos.len()];
    for t in indices.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| i as usize);
        let f = (pos[b] - pos[a]).cross(pos[c] - pos[a]);
        for i in [a, b, c] {
            n[i] += f;
        }
    }
    n.into_iter().map(|v| v.normalize_or(Vec3::Y)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A material with `alphaMode: BLEND` is transparent with its base colour's alpha; without
    /// it (OPAQUE by default) the same material is opaque. (The glTF sample of
    /// `assimp-testmodels`, which .ci/run installs, with its material edited.)
    #[test]
    fn alpha_mode_blend_gives_the_base_colour_alpha_as_opacity() {
        let src = std::fs::read_to_string(
            "/usr/share/assimp/models/glTF2/BoxTextured-glTF-Embedded/BoxTextured.gltf",
        )
        .expect("install assimp-testmodels (as .ci/run does)");
        let dir = std::env::temp_dir().join(format!("manylights-alpha-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let blend = src
            .replace(
                "\"metallicFactor\": 0.0",
                "\"metallicFactor\": 0.0, \"baseColorFactor\": [1.0, 1.0, 1.0, 0.4]",
            )
            .replace(
                "\"name\": \"Texture\"",
                "\"name\": \"Texture\", \"alphaMode\": \"BLEND\"",
            );
        assert_ne!(blend, src);
        let opacity = |text: &str, name: &str| {
            let path = dir.join(name);
            std::fs::write(&path, text).unwrap();
            let (scene, _) = load(&path, &GltfOptions::default()).unwrap();
            scene.validate().unwrap();
            scene.materials[scene.primitives[0].material as usize].opacity
        };
        let (blended, opaque) = (opacity(&blend, "blend.gltf"), opacity(&src, "opaque.gltf"));
        std::fs::remove_dir_all(&dir).unwrap();
        assert!((blended - 0.4).abs() < 1e-6, "{blended}");
        assert_eq!(opaque, 1.0);
    }

    /// The material is glTF's metallic-roughness model with the file's factors (the default
    /// roughness 1 where the file gives none), its texture counted as unread; a factor out of
    /// range is an error that names the material and the glTF field.
    #[test]
    fn metallic_roughness_factors_are_read_and_checked() {
        let src = std::fs::read_to_string(
            "/usr/share/assimp/models/glTF2/BoxTextured-glTF-Embedded/BoxTextured.gltf",
        )
        .expect("install assimp-testmodels (as .ci/run does)");
        let dir = std::env::temp_dir().join(format!("manylights-pbr-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // The factors go in the pbrMetallicRoughness object; the emission beside it.
        let edit = |pbr: &str| {
            src.replace("\"metallicFactor\": 0.0", pbr).replace(
                "\"name\": \"Texture\"",
                "\"name\": \"Texture\", \"emissiveFactor\": [0.5, 0.25, 0.0]",
            )
        };
        let load_text = |text: String, name: &str| {
            let path = dir.join(name);
            std::fs::write(&path, text).unwrap();
            load(&path, &GltfOptions::default())
        };
        let (scene, report) = load_text(
            edit("\"metallicFactor\": 0.25, \"roughnessFactor\": 0.6"),
            "good.gltf",
        )
        .unwrap();
        let m = scene.materials[scene.primitives[0].material as usize];
        assert_eq!(
            m.brdf,
            Brdf::Ggx {
                metallic: 0.25,
                roughness: 0.6
            }
        );
        assert_eq!(m.emissive, Vec3::new(0.5, 0.25, 0.0));
        assert_eq!(report.unread_textures, 1);
        for (pbr, field) in [
            (
                "\"metallicFactor\": 1.5",
                "pbrMetallicRoughness.metallicFactor = 1.5",
            ),
            (
                "\"metallicFactor\": 0.0, \"roughnessFactor\": -0.2",
                "pbrMetallicRoughness.roughnessFactor = -0.2",
            ),
        ] {
            let e = load_text(edit(pbr), "bad.gltf").unwrap_err().to_string();
            assert!(
                e.contains("bad.gltf")
                    && e.contains("materials[0] (\"Texture\")")
                    && e.contains(field)
                    && e.contains("[0, 1]"),
                "{e}"
            );
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
