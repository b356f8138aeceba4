//! WGSL composition. Shared WGSL (frame, vertex stage, lights and falloff, shading model) lives
//! once under `shaders/common/`; a shader is the generated constant prelude followed by a list
//! of files, concatenated in order. Files are embedded at compile time, so the binary runs
//! anywhere without the source tree.
//!
//! Every [`ShaderDef`] of every crate is listed by that crate (`SHADERS`) and validated with naga
//! in a test that needs no GPU; the same test fails if a `.wgsl` file under `shaders/` is used by
//! no definition.

use crate::layout::wgsl_prelude;

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
/// Material and shading model.
pub const SHADING: ShaderFile = shader_file!("common/shading.wgsl");

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
    /// The full WGSL text.
    pub fn compose(&self) -> String {
        let mut s = wgsl_prelude();
        for c in self.consts {
            match c {
                WgslConst::U32(name, v) => s.push_str(&format!("const {name}: u32 = {v}u;\n")),
                WgslConst::F32(name, v) => s.push_str(&format!("const {name}: f32 = {v:?};\n")),
            }
        }
        for f in self.files {
            s.push_str("\n// ---- shaders/");
            s.push_str(f.path);
            s.push_str(" ----\n");
            s.push_str(f.source);
        }
        s
    }

    /// Compiles the shader on `device`.
    pub fn create(&self, device: &wgpu::Device) -> wgpu::ShaderModule {
        device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(self.name),
            source: wgpu::ShaderSource::Wgsl(self.compose().into()),
        })
    }
}

/// The depth prepass: the shared vertex stage alone.
pub const PREPASS: ShaderDef = ShaderDef {
    name: "prepass.depth",
    consts: &[],
    files: &[FRAME, VERTEX],
};

/// Every shader this crate defines.
pub const SHADERS: &[ShaderDef] = &[PREPASS];
