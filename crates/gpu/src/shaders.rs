//! WGSL composition. Shared WGSL (frame, vertex stage, lights and falloff, shading model) lives
//! once under `shaders/common/`; a shader is the generated constant prelude followed by a list
//! of files, concatenated in order. Files are embedded at compile time, so the binary runs
//! anywhere without the source tree.
//!
//! For ablations without a rebuild, `MANYLIGHTS_SHADER_DIR` names a directory laid out like
//! `shaders/`: a file found there replaces the embedded one (each replacement is printed as a
//! warning, once), and the rest stay embedded. A named directory that does not exist, or a file
//! there that cannot be read, is an error, not a silent fallback.
//!
//! Every [`ShaderDef`] of every crate is listed by that crate (`SHADERS`) and validated with naga
//! in a test that needs no GPU; the same test fails if a `.wgsl` file under `shaders/` is used by
//! no definition.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use crate::layout::wgsl_prelude;

/// The environment variable naming a directory of replacement shader files (see the module
/// documentation).
pub const SHADER_DIR_ENV: &str = "MANYLIGHTS_SHADER_DIR";

/// Checks [`SHADER_DIR_ENV`] up front: an error naming it and its value when it is set but is
/// not a directory, so that a command fails cleanly before any shader is built (building one
/// would panic with the same message).
pub fn check_override_dir() -> Result<(), String> {
    override_dir().map(|_| ())
}

/// The replacement directory from [`SHADER_DIR_ENV`], read once; an error when it is named but
/// is not a directory.
fn override_dir() -> Result<Option<&'static Path>, String> {
    static DIR: OnceLock<Result<Option<PathBuf>, String>> = OnceLock::new();
    DIR.get_or_init(|| match std::env::var_os(SHADER_DIR_ENV) {
        None => Ok(None),
        Some(v) if v.is_empty() => Ok(None),
        Some(v) => {
            let dir = PathBuf::from(v);
            if dir.is_dir() {
                Ok(Some(dir))
            } else {
                Err(format!(
                    "{SHADER_DIR_ENV}={}: not a directory (expected a directory laid out like shaders/, or unset)",
                    dir.display()
                ))
            }
        }
    })
    .as_ref()
    .map(|d| d.as_deref())
    .map_err(Clone::clone)
}

/// One WGSL file of the shader tree.
#[derive(Clone, Copy, Debug)]
pub struct ShaderFile {
    /// Path relative to `shaders/`.
    pub path: &'static str,
    /// Its text.
    pub source: &'static str,
}

/// Embeds `shaders/<path>` from the repository root.
#[macro_export]
macro_rules! shader_file {
    ($path:literal) => {
        $crate::shaders::ShaderFile {
            path: $path,
            source: include_str!(concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/../../shaders/",
                $path
            )),
        }
    };
}

/// Per-frame uniform and view direction.
pub const FRAME: ShaderFile = shader_file!("common/frame.wgsl");
/// The shared vertex stage.
pub const VERTEX: ShaderFile = shader_file!("common/vertex.wgsl");
/// Light struct, falloff, spot cone.
pub const LIGHT: ShaderFile = shader_file!("common/light.wgsl");
/// Material struct and the scene's light and material buffers (after LIGHT).
pub const SCENE: ShaderFile = shader_file!("common/scene.wgsl");
/// Material and shading model (after [`BVH`], whose shadow rays it casts with `SHADOWS`).
pub const SHADING: ShaderFile = shader_file!("common/shading.wgsl");
/// The BVH of the opaque triangles and the any-hit shadow ray through it (after [`SCENE`],
/// which places its buffers in group 0, or with `BVH_GROUP` and `BVH_BINDING` of its own).
pub const BVH: ShaderFile = shader_file!("common/bvh.wgsl");
/// The material models (`shaders/common/brdf.wgsl`), composed before [`SHADING`].
pub const BRDF: ShaderFile = shader_file!("common/brdf.wgsl");

/// A constant generated into a shader's prelude from its Rust definition.
#[derive(Clone, Copy, Debug)]
pub enum WgslConst {
    /// `const NAME: u32 = value;`
    U32(&'static str, u32),
    /// `const NAME: f32 = value;`
    F32(&'static str, f32),
}

/// A shader: a name (its profiler scope), extra constants, and its files in order.
#[derive(Clone, Copy, Debug)]
pub struct ShaderDef {
    /// Pass name, such as `prepass.depth`.
    pub name: &'static str,
    /// Constants added to the common prelude (from the Rust constants of the defining crate).
    pub consts: &'static [WgslConst],
    /// Files, concatenated in this order after the prelude.
    pub files: &'static [ShaderFile],
}

impl ShaderDef {
    /// The full WGSL text, from the embedded files.
    pub fn compose(&self) -> String {
        self.compose_from(None)
            .expect("embedded shader files need no reading")
    }

    /// The full WGSL text, each file taken from `dir` (laid out like `shaders/`) where it exists
    /// there, and embedded otherwise. Errors name the file that could not be read.
    pub fn compose_from(&self, dir: Option<&Path>) -> Result<String, String> {
        self.compose_files(self.files, dir)
    }

    /// [`ShaderDef::compose`] with each file `from` of `swaps` replaced by its `to` (a variant
    /// of a shared building block, such as what culling reads its depth from).
    pub fn compose_swapped(&self, swaps: &[(ShaderFile, ShaderFile)]) -> String {
        self.compose_files(&self.swapped(swaps), None)
            .expect("embedded shader files need no reading")
    }

    /// This shader's files with each file `from` of `swaps` replaced by its `to`.
    fn swapped(&self, swaps: &[(ShaderFile, ShaderFile)]) -> Vec<ShaderFile> {
        self.files
            .iter()
            .map(|f| {
                swaps
                    .iter()
                    .find(|(from, _)| from.path == f.path)
                    .map_or(*f, |&(_, to)| to)
            })
            .collect()
    }

    /// The WGSL text of `files` after the prelude, each taken from `dir` where it exists there.
    fn compose_files(&self, files: &[ShaderFile], dir: Option<&Path>) -> Result<String, String> {
        let mut enables = String::new();
        let mut s = wgsl_prelude();
        for c in self.consts {
            match c {
                WgslConst::U32(name, v) => s.push_str(&format!("const {name}: u32 = {v}u;\n")),
                WgslConst::F32(name, v) => s.push_str(&format!("const {name}: f32 = {v:?};\n")),
            }
        }
        for f in files {
            let replaced = dir.map(|d| d.join(f.path)).filter(|p| p.is_file());
            s.push_str("\n// ---- shaders/");
            s.push_str(f.path);
            let text = match replaced {
                Some(p) => {
                    s.push_str(&format!(" (replaced by {}) ----\n", p.display()));
                    std::fs::read_to_string(&p).map_err(|e| format!("{}: {e}", p.display()))?
                }
                None => {
                    s.push_str(" ----\n");
                    f.source.to_owned()
                }
            };
            s.push_str(&hoist_enables(&text, &mut enables));
        }
        Ok(enables + &s)
    }

    /// Compiles the shader on `device`, with the files of `MANYLIGHTS_SHADER_DIR` where it is
    /// set (a warning names each replaced file, once).
    ///
    /// # Panics
    /// When `MANYLIGHTS_SHADER_DIR` is set but is not a directory, or a file there cannot be
    /// read: a measurement must not silently run other shaders than asked for.
    pub fn create(&self, device: &wgpu::Device) -> wgpu::ShaderModule {
        self.create_swapped(device, &[])
    }

    /// [`ShaderDef::create`] with each file `from` of `swaps` replaced by its `to` (see
    /// [`ShaderDef::compose_swapped`]): a variant, such as culling over a multisampled depth
    /// buffer (`manylights_cull::shaders::DepthVariant`).
    pub fn create_swapped(
        &self,
        device: &wgpu::Device,
        swaps: &[(ShaderFile, ShaderFile)],
    ) -> wgpu::ShaderModule {
        self.module(device, self.source(&self.swapped(swaps)))
    }

    /// Whether this shader composes `file`.
    pub fn has_file(&self, file: ShaderFile) -> bool {
        self.files.iter().any(|f| f.path == file.path)
    }

    /// The module of `source`, labelled with this shader's name.
    fn module(&self, device: &wgpu::Device, source: String) -> wgpu::ShaderModule {
        device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(self.name),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        })
    }

    /// The WGSL text of `files` (this shader's, or a variant's: [`ShaderDef::swapped`]), with
    /// the files of `MANYLIGHTS_SHADER_DIR` where it is set.
    pub(crate) fn source(&self, files: &[ShaderFile]) -> String {
        match override_dir() {
            Ok(None) => self
                .compose_files(files, None)
                .expect("embedded shader files need no reading"),
            Ok(Some(dir)) => {
                static WARNED: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());
                for f in files {
                    let p = dir.join(f.path);
                    if p.is_file() {
                        let mut warned = WARNED.lock().unwrap_or_else(|e| e.into_inner());
                        if !warned.contains(&p) {
                            // Printed, not only logged: benches install no log subscriber,
                            // and a replaced shader must never go unnoticed.
                            eprintln!("warning: shaders/{} replaced by {}", f.path, p.display());
                            warned.push(p);
                        }
                    }
                }
                self.compose_files(files, Some(dir))
                    .unwrap_or_else(|e| panic!("{SHADER_DIR_ENV}: {e}"))
            }
            Err(e) => panic!("{e}"),
        }
    }
}

/// `text` with its enable directives (`enable primitive_index;`) commented out, each appended
/// to `enables` (once): a directive comes before every declaration, so a file's is put before
/// the composed text.
fn hoist_enables(text: &str, enables: &mut String) -> String {
    let mut out = String::with_capacity(text.len());
    for line in text.split_inclusive('\n') {
        if line.starts_with("enable ") {
            if !enables.contains(line.trim_end()) {
                enables.push_str(line.trim_end());
                enables.push('\n');
            }
            out.push_str("// (before the prelude) ");
        }
        out.push_str(line);
    }
    out
}

/// The depth prepass: the shared vertex stage alone.
pub const PREPASS: ShaderDef = ShaderDef {
    name: "prepass.depth",
    consts: &[],
    files: &[FRAME, VERTEX],
};

/// Every shader this crate defines.
pub const SHADERS: &[ShaderDef] = &[
    PREPASS,
    crate::lookup_bounds::PREPASS_RANGES,
    crate::lookup_bounds::BOUNDS,
    crate::lookup_bounds::BOUNDS_MSAA,
    crate::motion::MOTION,
    crate::stochastic::STOCHASTIC,
    crate::hierarchy::HIERARCHY,
    crate::hierarchy::HIERARCHY64,
    crate::bvh::SHADOW_RAYS,
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replacement_files_take_the_place_of_embedded_ones() {
        let dir = std::env::temp_dir().join(format!("manylights-shaders-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("common")).unwrap();
        std::fs::write(dir.join("common/vertex.wgsl"), "// replaced vertex stage\n").unwrap();
        let embedded = PREPASS.compose();
        let replaced = PREPASS.compose_from(Some(&dir)).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        assert!(embedded.contains(VERTEX.source));
        assert!(!replaced.contains(VERTEX.source));
        assert!(replaced.contains("// replaced vertex stage"));
        assert!(replaced.contains("(replaced by "));
        // FRAME has no replacement there: still embedded.
        assert!(replaced.contains(FRAME.source));
        assert_eq!(PREPASS.compose_from(None).unwrap(), embedded);
    }
}
