//! The renderers of a run, kept from cell to cell: building one compiles every culling and
//! shading pipeline, most of a small cell's time (on lavapipe about 1.5 s of a tiny stability
//! cell's 2.3). A renderer's pipelines depend only on the sample count, the lit image's format,
//! whether the scene has transparent surfaces, its opaque surfaces' material models and its
//! lights' path (`manylights_gpu::LightPath`): bind group layouts of equal entries are one layout
//! to wgpu, so a renderer serves every scene laid out alike. Also the brute-force reference
//! frames of the latest views ([`ReferenceFrames`]), and the latest scene file read
//! ([`LoadedScenes`]: the kitchen's 1.4M triangles take 2 s to read).

use manylights_gpu::{GpuContext, GpuError, GpuScene, LightPath};
use manylights_scene::gltf_import::ImportReport;
use manylights_scene::{Camera, Scene};
use manylights_shade::{HdrFormat, ReferenceFrame, Renderer, Shadows, VisibilityPass};

use crate::experiment::Config;

/// What a renderer is built for: samples a pixel, glass, the opaque material models in order,
/// the lights' path, the lit image's format, shadows.
type Key = (u32, bool, Vec<u32>, LightPath, HdrFormat, Shadows);

/// The renderers built so far in a run (the most recent [`Renderers::KEEP`]).
#[derive(Default)]
pub(crate) struct Renderers(Vec<(Key, Renderer)>);

impl Renderers {
    /// The most renderers kept: a sweep's cells rarely need more kinds.
    const KEEP: usize = 4;

    /// Gives every renderer kept the occluders of the scene it renders next (culling by
    /// visibility).
    pub fn set_occluders(
        &mut self,
        ctx: &GpuContext,
        occluders: &[manylights_scene::occluders::Occluder],
    ) -> Result<(), manylights_cull::CullError> {
        for (_, r) in &mut self.0 {
            r.culler.set_occluders(ctx, occluders)?;
        }
        Ok(())
    }

    /// A renderer for `scene` at `samples` samples a pixel into a lit image of format `hdr`
    /// (one built before for a scene laid out alike, or a new one), casting `shadows`, its
    /// visibility backend drawn by `visibility_pass`; and where it casts shadows, the same
    /// renderer without them (what the rays cost is the difference of their frames).
    pub fn get_with_unshadowed(
        &mut self,
        ctx: &GpuContext,
        scene: &GpuScene,
        (samples, hdr, shadows): (u32, HdrFormat, Shadows),
        visibility_pass: VisibilityPass,
    ) -> Result<(&Renderer, Option<&Renderer>), GpuError> {
        let key = self.built(ctx, scene, (samples, hdr, shadows), visibility_pass)?;
        let plain = shadows
            .casts()
            .then(|| self.built(ctx, scene, (samples, hdr, Shadows::Off), visibility_pass))
            .transpose()?;
        // Both are kept: KEEP > 1, and the second built pushes out only the oldest.
        Ok((self.kept(&key), plain.map(|k| self.kept(&k))))
    }

    /// The key of the renderer for `scene` and its settings, built and kept unless it was.
    fn built(
        &mut self,
        ctx: &GpuContext,
        scene: &GpuScene,
        (samples, hdr, shadows): (u32, HdrFormat, Shadows),
        visibility_pass: VisibilityPass,
    ) -> Result<Key, GpuError> {
        let key = (
            samples,
            scene.has_transparent(),
            scene
                .opaque_models
                .iter()
                .map(|&(model, _)| model)
                .collect(),
            scene.light_path(),
            hdr,
            shadows,
        );
        let i = match self.0.iter().position(|(k, _)| *k == key) {
            Some(i) => i,
            None => {
                let renderer =
                    Renderer::with_format(ctx, scene, samples, hdr)?.with_shadows(shadows);
                if self.0.len() == Self::KEEP {
                    self.0.remove(0);
                }
                self.0.push((key.clone(), renderer));
                self.0.len() - 1
            }
        };
        self.0[i].1.visibility_pass = visibility_pass;
        Ok(key)
    }

    /// The kept renderer of `key`.
    fn kept(&self, key: &Key) -> &Renderer {
        &self.0.iter().find(|(k, _)| k == key).expect("a kept key").1
    }
}

/// The brute-force (windowed) reference frames of a run's recent views, kept from cell to cell:
/// the cells of a sweep over strategies and backends share their scene, lights and view, and
/// so their reference, which on a software rasteriser costs more than the cell itself.
///
/// A frame is kept under [`ReferenceFrames::key`]: the cell's configuration less what does not
/// reach the reference (strategy, backend, the culler's budgets, frame counts, the oracle's
/// stride, export) and the camera. Cells of moving lights do not use it (their lights differ
/// from frame to frame).
#[derive(Default)]
pub(crate) struct ReferenceFrames(std::cell::RefCell<Vec<(String, ReferenceFrame)>>);

impl ReferenceFrames {
    /// The most frames kept (a camera path's poses, or the views of a few scenes).
    const KEEP: usize = 4;

    /// The key of a cell's reference of `camera` (none where it cannot be written).
    pub fn key(c: &Config, camera: &Camera) -> Option<String> {
        let neutral = Config {
            strategy: manylights_cull::Strategy::tiled_gather(16),
            backend: manylights_shade::Backend::Forward,
            visibility_pass: VisibilityPass::Compute,
            capacity: None,
            mask_budget: None,
            tile_boxes: false,
            slack: 0.0,
            frames: 1,
            warmup: 0,
            exact_stride: 1,
            export: false,
            shadows: c.shadows.truth(),
            ..c.clone()
        };
        Some(format!(
            "{}\n{}",
            ron::to_string(&neutral).ok()?,
            serde_json::to_string(camera).ok()?
        ))
    }

    /// The frame kept under `key`, or `render`'s (then kept).
    pub fn get_or<E>(
        &self,
        key: Option<&str>,
        render: impl FnOnce() -> Result<ReferenceFrame, E>,
    ) -> Result<ReferenceFrame, E> {
        let Some(key) = key else {
            return render();
        };
        if let Some((_, f)) = self.0.borrow().iter().find(|(k, _)| k == key) {
            return Ok(f.clone());
        }
        let frame = render()?;
        let mut kept = self.0.borrow_mut();
        if kept.len() == Self::KEEP {
            kept.remove(0);
        }
        kept.push((key.to_string(), frame.clone()));
        Ok(frame)
    }
}

/// The scene file read last in a run, as read (before any cell's materials and lights), so
/// that the cells of one scene read it once.
#[derive(Default)]
pub(crate) struct LoadedScenes(std::cell::RefCell<Option<(String, Scene, ImportReport)>>);

impl LoadedScenes {
    /// The scene of `key` (a path, or a real scene's name), read by `read` unless it was the
    /// last one read.
    pub(crate) fn get(
        &self,
        key: &str,
        read: impl FnOnce() -> Result<(Scene, ImportReport), crate::LabError>,
    ) -> Result<(Scene, ImportReport), crate::LabError> {
        if let Some((k, scene, report)) = &*self.0.borrow()
            && k == key
        {
            return Ok((scene.clone(), *report));
        }
        let (scene, report) = read()?;
        *self.0.borrow_mut() = Some((key.to_owned(), scene.clone(), report));
        Ok((scene, report))
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::{ImportReport, LoadedScenes, ReferenceFrames};
    use crate::Experiment;

    /// Cells that differ only in strategy, backend and the culler's budgets share their
    /// reference; cells of other lights or another view do not.
    #[test]
    fn cells_of_one_view_and_light_set_share_a_reference() {
        let src = r#"Experiment(
            name: "t",
            config: Config(scene: Atrium(), lights: (count: 64), resolution: (16, 8)),
            sweep: (
                light_count: [64, 128],
                variants: [
                    (label: "a", backend: Forward, strategy: TiledGather(tile_size: 16)),
                    (label: "b", backend: Deferred, strategy: ZBin(tile_size: 8, bins: 16), capacity: Some(64)),
                ],
            ),
        )"#;
        let e = Experiment::parse(src, Path::new("t.ron")).unwrap();
        let cells = e.cells();
        assert_eq!(cells.len(), 4);
        let cam = manylights_scene::Camera::perspective(
            glam::Vec3::new(0.0, 1.0, 5.0),
            glam::Vec3::ZERO,
            60.0,
            0.1,
            50.0,
        );
        let key = |i: usize| ReferenceFrames::key(&cells[i].config, &cam).unwrap();
        let by_count = |n: u32| {
            (0..4)
                .filter(|&i| cells[i].config.lights.count == n)
                .map(key)
                .collect::<Vec<_>>()
        };
        let (small, big) = (by_count(64), by_count(128));
        assert_eq!(small.len(), 2);
        assert_eq!(small[0], small[1]);
        assert_eq!(big[0], big[1]);
        assert_ne!(small[0], big[0]);
        let moved = manylights_scene::Camera {
            position: cam.position + glam::Vec3::X,
            ..cam
        };
        assert_ne!(
            small[0],
            ReferenceFrames::key(&cells[0].config, &moved).unwrap()
        );
        // A frame is rendered once a key, and kept.
        let frames = ReferenceFrames::default();
        let mut rendered = 0;
        for k in [&small[0], &small[1], &big[0], &small[0]] {
            let _ = frames.get_or(Some(k), || {
                rendered += 1;
                Ok::<_, ()>(blank())
            });
        }
        assert_eq!(rendered, 2);
    }

    fn blank() -> manylights_shade::ReferenceFrame {
        let img = manylights_shade::HdrImage {
            width: 1,
            height: 1,
            data: vec![[0.0; 4]],
        };
        manylights_shade::ReferenceFrame {
            color: img.clone(),
            position: img.clone(),
            normal: img,
            depth: vec![1.0],
            timings: None,
        }
    }

    /// The cells of one scene read its file once; another file is read, and then the first
    /// again.
    #[test]
    fn a_scene_file_is_read_once_for_its_cells() {
        let loaded = LoadedScenes::default();
        let reads = std::cell::Cell::new(0);
        let read = |name: &str| {
            reads.set(reads.get() + 1);
            let mut s = manylights_scene::procedural::ProceduralScene::from_name("atrium")
                .unwrap()
                .build()
                .unwrap();
            s.name = name.into();
            Ok((s, ImportReport::default()))
        };
        for (key, want) in [("a", 1), ("a", 1), ("b", 2), ("a", 3)] {
            let (s, _) = loaded.get(key, || read(key)).unwrap();
            assert_eq!((s.name.as_str(), reads.get()), (key, want));
        }
    }
}
